"""A real CLI sweep killed mid-run (SIGTERM, as `kill` sends; SIGINT, as Ctrl-C) and
resumed writes exactly the rows of an uninterrupted one."""

import signal
import subprocess
import sys
import time

import pytest

SPEC = """
[sweep]
mode = "random"
samples = 20000
seed = 7
base = "paper"
chunk_size = 1000

[parameters]
gap_mm = {min = 0.3, max = 0.9}
n_drums = {min = 1, max = 3}
"""


def _sweep(spec, out, *extra):
    return [sys.executable, "-m", "mrclutch", "sweep", str(spec), "--out", str(out),
            "--no-progress", *extra]  # fmt: skip


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """(the spec, the rows of its sweep run without interruption): one run for both
    signals."""
    tmp = tmp_path_factory.mktemp("whole")
    spec = tmp / "spec.toml"
    spec.write_text(SPEC)
    subprocess.run(_sweep(spec, tmp / "whole.csv"), check=True, capture_output=True)
    return spec, (tmp / "whole.csv").read_text()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_killed_sweep_resumes_to_the_same_rows(tmp_path, sig, uninterrupted):
    """Killed once two of its 20 chunks are on disk (20 000 rows: the 18 left take far
    longer than the 20 ms poll, so the signal lands mid-run; 60 000 cost three times the
    time for the same claim)."""
    spec, whole = uninterrupted
    part = tmp_path / "part.csv"
    proc = subprocess.Popen(_sweep(spec, part), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # wait until a few chunks are on disk
        if part.exists() and part.read_text().count("\n") > 2001:
            break
        time.sleep(0.02)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    rows = part.read_text().count("\n") - 1
    if proc.returncode == 0:  # finished before the signal landed: nothing to resume
        pytest.skip("the sweep finished before it could be interrupted")
    assert proc.returncode == 130, err
    assert b"--resume" in err and b"Traceback" not in err
    assert 0 < rows < 20000 and rows % 1000 == 0  # whole chunks only
    subprocess.run(_sweep(spec, part, "--resume"), check=True, capture_output=True)
    assert part.read_text() == whole


HEAVY = ("build123d", "OCP", "skfem", "pyvista", "vtk", "trimesh")

#: Python that shrinks the Pareto search of ``optimize`` in the process it runs in.
SMALL_SEARCH = (
    "import mrclutch.cli.commands.optimize_pareto as _op\n"
    "_real = _op.pareto\n"
    "_op.pareto = lambda *a, **k: _real(*a, **{**k, 'pop_size': 16, 'generations': 4,"
    " 'members': 2})\n"
)


@pytest.mark.parametrize(
    "argv",
    [
        ["sweep", "{spec}", "--out", "{out}", "--no-progress"],
        ["optimize", "--drums", "2", "--no-verify", "--json"],
    ],
    ids=["sweep", "optimize"],
)
def test_sweeps_and_the_optimiser_never_build_cad(tmp_path, argv):
    """Issue 6: a sweep (and the optimiser's search) uses the closed forms and the circuit
    only — no CAD kernel, FEM or 3-D view is even imported. The search is a small one (a
    population of 16 for 4 generations, 2 members): what it imports does not depend on how
    long it runs, and the default (100 × 100) took a minute here."""
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC.replace("samples = 20000", "samples = 3000"))
    args = [a.format(spec=spec, out=tmp_path / "rows.csv") for a in argv]
    code = (
        "import sys, io, contextlib\n"
        "from mrclutch.cli.main import main\n"
        f"{SMALL_SEARCH}"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    rc = main({args!r})\n"
        f"print(rc, [m for m in {HEAVY!r} if m in sys.modules])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "0 []", out.stderr


def test_sweep_with_optional_columns_writes_them_after_the_default_ones(tmp_path, capsys):
    """``--with`` appends the asked-for columns, each equal to the single-design value;
    the default row already carries the backdrive force (issue 13). In process: the
    columns do not depend on how the command is started."""
    import csv

    from mrclutch.cli.main import main
    from mrclutch.design import design_preset
    from mrclutch.outputs import SWEEP_COLUMNS
    from mrclutch.pipeline import evaluate

    spec = tmp_path / "s.toml"
    spec.write_text(SPEC.replace("samples = 20000", "samples = 6"))
    out = tmp_path / "r.csv"
    cmd = _sweep(spec, out, "--with", "zwidth_area_N2_s_per_m2", "--with",
                 "max_passive_K_N_per_m")  # fmt: skip
    assert main(cmd[3:]) == 0, capsys.readouterr().err
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 6
    cols = list(rows[0])
    tail = ["max_passive_K_N_per_m", "zwidth_area_N2_s_per_m2"]
    assert cols[-2:] == tail and all(c in cols for c in SWEEP_COLUMNS)
    assert "backdrive_force_N" in SWEEP_COLUMNS
    for r in rows:
        assert float(r["zwidth_area_N2_s_per_m2"]) > 0
        assert float(r["backdrive_force_N"]) > 0
        assert float(r["torque_error_bound"]) >= 0  # the fast torque's own bound, every row
    # the paper preset row by row equals evaluate's figures
    ev = evaluate(design_preset("paper"))
    from mrclutch.pipeline import BatchEvaluator

    row = BatchEvaluator(design_preset("paper"), tuple(tail))({})
    assert row["zwidth_area_N2_s_per_m2"][0] == pytest.approx(
        ev.zwidth["mr"]["zwidth_area_N2_s_per_m2"], rel=1e-9
    )
    assert row["backdrive_force_N"][0] == pytest.approx(
        ev.hand["mr"]["backdrive_force_N"], rel=1e-9
    )


def test_sweep_with_an_unknown_column_is_refused(tmp_path, capsys):
    from mrclutch.cli.main import main

    spec = tmp_path / "s.toml"
    spec.write_text(SPEC)
    with pytest.raises(SystemExit) as exc:  # argparse's refusal: usage, then the error
        main(_sweep(spec, tmp_path / "r.csv", "--with", "nonsense")[3:])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--with: invalid choice: 'nonsense'" in err and "Traceback" not in err, err
    assert not (tmp_path / "r.csv").exists()


SMALL = """
[sweep]
mode = "grid"
chunk_size = 6
[parameters]
gap_mm = {min = 0.3, max = 0.9, count = 8}
n_drums = {min = 1, max = 3}
"""


def test_cli_refuses_a_damaged_chunk_in_one_line_and_repair_restores_the_file(tmp_path, capsys):
    from mrclutch.cli.main import main

    spec = tmp_path / "s.toml"
    spec.write_text(SMALL)  # 24 designs, 4 chunks of 6
    whole, out = tmp_path / "whole.csv", tmp_path / "r.csv"
    for path in (whole, out):
        assert main(["sweep", str(spec), "--out", str(path), "--no-progress"]) == 0
    lines = out.read_bytes().split(b"\n")
    out.write_bytes(b"\n".join(lines[: 1 + 14] + lines[1 + 15 :]))  # row 14 of chunk 2 lost
    capsys.readouterr()
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress", "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "r.csv: chunk 2 (rows 12–17) does not match its checksum" in err[0]
    assert "--repair" in err[0]
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress", "--repair"]) == 0
    assert "repaired chunk(s) 2 of" in capsys.readouterr().out
    assert out.read_bytes() == whole.read_bytes()
