"""Inputs a fuzzing session found crashing, exhausting memory or answering wrong: each now
ends in one line on stderr naming the user's key in the user's unit, exit status 2, no
traceback, and no output file left behind."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrclutch.cli.main import main

SWEEP = '[sweep]\nmode = "grid"\n{sweep}\n[parameters]\n{params}\n'
GAP = "gap_mm = {min = 0.3, max = 0.5, count = 2}"


def _fails(capsys, argv, fragment):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert fragment in err, err
    assert "Traceback" not in err and err.count("\n") == 1, err


@pytest.fixture
def here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize(
    ("clutch", "fragment"),
    [
        ("shaft_bore_clearance_mm = 10", "shaft_bore_clearance_mm = 10 mm: the front cap's bore"),
        ("shaft_bore_clearance_mm = 400", "shaft_bore_clearance_mm = 400 mm: must be in"),
        ("end_clearance_mm = 1e-15", "end_clearance_mm = 1e-15 mm: must be in [0.01, 300] mm"),
        ("end_clearance_mm = 1e-17", "end_clearance_mm = 1e-17 mm: must be in"),
        ("wire_insulation_mm = 1e303", "wire_insulation_mm = 1e+303 mm: must be in [0, 1] mm"),
        ("wire_diameter_mm = 1e-297", "wire_diameter_mm = 1e-297 mm: must be in [0.01, 10] mm"),
        ("shell_thickness_mm = 1e-17", "shell_thickness_mm = 1e-17 mm: must be in"),
        ("n_drums = 20\ndrum_thickness_mm = 20\ngap_mm = 5", "MAX_OUTER_DIAMETER"),
    ],
)
def test_design_fields_out_of_range(here, capsys, clutch, fragment):
    (here / "d.toml").write_text(f'[clutch]\nbase = "paper"\n{clutch}\n')
    _fails(capsys, ["evaluate", "d.toml", "--fidelity", "fast"], fragment)


def test_non_utf8_design_file(here, capsys):
    (here / "d.toml").write_bytes(b'[clutch]\nbase = "paper"\n# \xff\xfe\n')
    _fails(capsys, ["evaluate", "d.toml"], "d.toml: not UTF-8 text")


@pytest.mark.parametrize(
    ("table", "fragment"),
    [  # found by benchmarks/fuzz_cli.py: LinAlgError, numpy 'Maximum allowed size exceeded'
        ("[transmission]\nm2_g = 1e-300", "transmission.m2_g = 1e-300: m2 = 1e-303 kg: must be"),
        ("[amplifier]\ncurrent_bandwidth_Hz = 1e-18", "current_bandwidth"),
    ],
)
def test_fuzzed_design_files(here, capsys, table, fragment):
    (here / "d.toml").write_text(f'[clutch]\nbase = "paper"\n{table}\n')
    _fails(capsys, ["evaluate", "d.toml", "--fidelity", "fast"], fragment)


def test_transmission_lever_in_a_design_file(here, capsys):
    (here / "d.toml").write_text('[clutch]\nbase = "paper"\n[transmission]\nlever_mm = 1e-9\n')
    _fails(capsys, ["evaluate", "d.toml", "--fidelity", "fast"], "transmission.lever_mm = 1e-09")


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["inertia", "--tolerance-mm", "1e-6"], "--tolerance-mm = 1e-06 mm: must be >= 0.00294"),
        (["export", "--out", "x", "--tolerance-mm", "1e-6"], "--tolerance-mm = 1e-06 mm"),
        (["export", "--out", "x", "--tolerance-mm", "100"], "--tolerance-mm = 100 mm: must be <="),
        (["haptic", "--lever-mm", "1e-9"], "--lever-mm = 1e-09 mm: must be in [1, 2000] mm"),
        (["compare", "--delay-ms", "1e300"], "--delay-ms = 1e+300 ms: must be in [0, 1000] ms"),
        # found by benchmarks/fuzz_cli.py: a MemoryError and a 30 s+ stability search
        (["compare", "--stiffness", "1e300", "--delay-ms", "1e-300"], "--stiffness = 1e+300"),
        (["compare", "--workspace-mm", "1e-300"], "--workspace-mm = 1e-300 mm: must be in [1,"),
        (["haptic", "--gearing", "1e-6"], "--gearing = 1e-06: must be in [0.01, 100]"),
    ],
)
def test_memory_and_time_guards(here, capsys, argv, fragment):
    _fails(capsys, argv, fragment)
    assert not (here / "x").exists()


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["torque", "--plot", "/proc/x/y.png"], "--plot /proc/x/y.png: cannot write in /proc"),
        (["torque", "--plot", "afile/y.png"], "--plot afile/y.png: cannot be created"),
        (["torque", "--plot", "adir"], "--plot adir: is a directory"),
        (["view", "--screenshot", "afile/v.png"], "--screenshot afile/v.png: cannot be created"),
        (["export", "--out", "afile"], "--out afile: is a file, not a folder"),
        (["export", "--out", "afile/sub"], "--out afile/sub: cannot be created"),
        (["sweep", "s.toml", "--out", "adir"], "--out adir: is a directory"),
    ],
)
def test_unwritable_outputs_are_refused_before_the_work(here, capsys, argv, fragment):
    (here / "afile").write_text("")
    (here / "adir").mkdir()
    (here / "s.toml").write_text(SWEEP.format(sweep="", params=GAP))
    _fails(capsys, argv, fragment)
    assert sorted(p.name for p in here.iterdir()) == ["adir", "afile", "s.toml"]
    assert not any((here / "adir").iterdir())


@pytest.mark.parametrize(
    ("sweep", "params", "fragment"),
    [
        ("seed = -1", GAP, "seed = -1: must be an integer in [0, "),
        ("", "gap_mm = {min = 0.3, max = 0.5, count = 200000}\n"
             "zone_length_mm = {min = 4, max = 8, count = 200000}", "must be <= 1e+08"),
        ("", "n_drums = {min = 1, max = 3000}", "n_drums.max = 3000: must be an integer in [1, 20"),
        ("", "n_drums = {min = 0.5, max = 2.5}", "n_drums.min = 0.5: must be an integer"),
        ("", "n_drums = {values = [1, 2.5]}", "n_drums.values = 2.5: must be an integer"),
    ],
)  # fmt: skip
def test_bad_sweep_specs_leave_no_csv(here, capsys, sweep, params, fragment):
    (here / "s.toml").write_text(SWEEP.format(sweep=sweep, params=params))
    _fails(capsys, ["sweep", "s.toml", "--out", "r.csv", "--no-progress"], fragment)
    assert not Path("r.csv").exists() and not Path("r.csv.meta.json").exists()


def test_non_utf8_sweep_spec(here, capsys):
    (here / "s.toml").write_bytes(SWEEP.format(sweep="", params=GAP).encode() + b"# \xff\n")
    _fails(capsys, ["sweep", "s.toml", "--out", "r.csv"], "s.toml: not UTF-8 text")


@pytest.mark.parametrize("meta", [b"{not json", b"\xff\xfe", b""])
def test_corrupt_meta_refuses_the_resume(here, capsys, meta):
    (here / "s.toml").write_text(SWEEP.format(sweep="", params=GAP))
    argv = ["sweep", "s.toml", "--out", "r.csv", "--no-progress"]
    assert main(argv) == 0
    capsys.readouterr()
    csv = Path("r.csv").read_bytes()
    Path("r.csv.meta.json").write_bytes(meta)
    _fails(capsys, [*argv, "--resume"], "r.csv.meta.json: unreadable")
    assert Path("r.csv").read_bytes() == csv  # the results are untouched


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["torque", "--preset", "paper", "--speed-rpm", "abc"],
         "mrclutch torque: error: argument --speed-rpm: invalid float value: 'abc'"),
        (["haptic", "--lever-mm", "x"], "mrclutch haptic: error: argument --lever-mm"),
        (["evaluate", "--bogus"], "mrclutch: error: unrecognized arguments: --bogus"),
        ([], "the following arguments are required: COMMAND"),
    ],
)  # fmt: skip
def test_argparse_usage_errors_are_one_line(capsys, argv, fragment):
    """argparse's own errors (a word for a number, an unknown choice or option) are one
    line and exit 2 like every other bad input, not its usage block and then the error."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert fragment in err and "usage:" not in err, err
    assert err.count("\n") == 1 and "--help" in err, err
