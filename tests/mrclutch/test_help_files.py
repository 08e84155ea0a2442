"""What a newcomer reads is what the tool does (issue 34): every command is in the README's
tour, and every file a command writes is named in its ``--help`` and in the README.

Each command runs once here in a scratch folder (small inputs; in this process, as ``main``
from that folder); the files it leaves are the files it writes. The CAD's export and the 3D
view are checked on the runs test_cli_geometry.py makes of them (build123d, VTK). A file in
an output folder is named by its own name (per-part STLs as ``<part>.stl``); a file written
beside a results file the user names (``r.csv`` → ``r.csv.meta.json``) by the same suffix on
the help's metavar (``RESULTS.csv.meta.json``).
The report's own files are checked against the module's report in test_report.py's fixture.
"""

from __future__ import annotations

import io
import re
from contextlib import redirect_stdout
from pathlib import Path

import pytest

from mrclutch.cli.main import COMMANDS, main

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text()
TINY_SWEEP = """\
[sweep]
mode = "grid"
base = "paper"
[parameters]
gap_mm = {min = 0.5, max = 0.7, count = 2}
"""

#: command → (arguments, the user-named paths (relative), the documented name of a derived
#: file's stem: the help's metavar for the user's path, slow?)
CASES: dict[str, tuple[list[str], dict[str, str], bool]] = {
    "haptic": ([], {}, False),  # no output option: it writes nothing
    "compare": (["--plot", "cmp.png"], {"cmp.png": "FILE.png"}, False),
    "export": (["--out", "cad"], {}, True),  # test_cli_geometry.py
    "inertia": ([], {}, False),
    "view": (["--screenshot", "v.png"], {"v.png": "FILE.png"}, True),  # test_cli_geometry.py
    "torque": (["--current", "0:7:3.5", "--plot", "t.png"], {"t.png": "FILE.png"}, False),
    "field": (["--current", "4", "--size-mm", "1", "--plot", "f.png"], {"f.png": "FILE.png"},
              False),
    "evaluate": ([], {}, False),
    "report": ([], {}, False),  # test_report.py: test_every_report_file_is_in_help_and_readme
    "sweep": (["spec.toml", "--out", "r.csv", "--pareto", "p.png", "--verify-top", "1",
               "--no-progress"], {"r.csv": "RESULTS.csv", "p.png": "FILE.png"}, False),
    "optimize": (["--drums", "2", "--no-verify", "--designs", "set", "--plot", "front.png"],
                 {"set": "DIR", "front.png": "FILE.png"}, True),
    "scale": ([], {}, False),
    "fidelity": ([], {}, True),  # the docs' figures' run, shared: test_fidelity_files_…
    "tables": (["--export", "mat"], {"mat": "DIR"}, False),
    "device": (["--out", "d.json"], {"d.json": "FILE.json"}, False),
}  # fmt: skip


#: optimize's Pareto search made small (a population of 16 for 4 generations, 2 members):
#: the files it writes do not depend on how long it searched, and the default search
#: (100 × 100) took a minute here.
SMALL_SEARCH = {"pop_size": 16, "generations": 4, "members": 2}


def _help(command: str) -> str:
    """``mrclutch COMMAND --help`` (in this process, 80 columns as a terminal's default)."""
    out = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, redirect_stdout(out):
        mp.setenv("COLUMNS", "80")
        with pytest.raises(SystemExit) as done:
            main([command, "--help"])
    assert done.value.code == 0
    return " ".join(out.getvalue().split())  # argparse wraps lines


def documented_names(written: list[Path], user: dict[str, str]) -> set[str]:
    """The names under which the written files must appear in the help and the README."""
    names = set()
    for rel in written:
        top = rel.parts[0]
        if top in user:  # the user's own path: its metavar names it
            names.add(user[top])
            continue
        stems = [u for u in user if top.startswith(u + ".")]
        if stems:  # beside a user-named file: RESULTS.csv.verified.csv
            names.add(user[stems[0]] + top[len(stems[0]) :])
        elif rel.suffix == ".stl":
            names.add("<part>.stl")
        else:
            names.add(rel.name)
    return names


def test_every_command_is_in_the_readme_tour_and_has_a_case():
    tour = README.split("## A tour of the command line", 1)[1].split("\n## ", 1)[0]
    for command in COMMANDS:
        assert f"`mrclutch {command}" in tour, f"{command} is not in the README's tour"
    assert set(CASES) == set(COMMANDS), "a new command needs its case here"


#: Cases checked elsewhere, on a run those tests make anyway: the report's files
#: (test_report.py), fidelity's (below, on two methods), view's and export's
#: (test_cli_geometry.py: its screenshot process and its module's export call
#: ``_check_named``).
ELSEWHERE = ("report", "fidelity", "view", "export")


def _params():
    return [pytest.param(c, marks=[pytest.mark.slow] if CASES[c][2] else [], id=c)
            for c in CASES if c not in ELSEWHERE]  # fmt: skip


def _check_named(command: str, written: list[Path], user: dict[str, str]) -> None:
    help_text = _help(command)
    for name in documented_names(written, user):
        assert name in help_text, f"`mrclutch {command} --help` does not name {name}"
        assert name in README, f"README does not name {name} (written by {command})"


def _run(command: str, args: list[str], folder: Path, monkeypatch, capsys) -> None:
    """``mrclutch COMMAND ARGS`` from ``folder``, without progress bars: exit 0 (or 3, a
    verdict that fails)."""
    import mrclutch.cli.commands.optimize_pareto as op

    real = op.pareto
    monkeypatch.setattr(op, "pareto", lambda *a, **k: real(*a, **{**k, **SMALL_SEARCH}))
    monkeypatch.setenv("MRCLUTCH_NO_PROGRESS", "1")
    monkeypatch.chdir(folder)
    code = main([command, *args])
    assert code in (0, 3), capsys.readouterr().err[-1000:]


@pytest.mark.parametrize("command", _params())
def test_every_written_file_is_named_in_help_and_readme(command, tmp_path, monkeypatch, capsys):
    args, user, _ = CASES[command]
    if not args:  # no output option at all: it writes nothing
        assert not re.search(r"--(out|plot|screenshot)\b", _help(command))
        return
    (tmp_path / "spec.toml").write_text(TINY_SWEEP)
    before = set(tmp_path.rglob("*"))
    _run(command, args, tmp_path, monkeypatch, capsys)
    written = sorted(p.relative_to(tmp_path) for p in set(tmp_path.rglob("*")) - before
                     if p.is_file())  # fmt: skip
    if user:
        assert written, f"{command} wrote nothing"
    _check_named(command, written, user)


def test_fidelity_files_are_named_in_help_and_readme(tmp_path, monkeypatch):
    """`mrclutch fidelity --out DIR` writes its three files whatever methods it measures:
    run here in-process on the registry's two bandwidth methods (milliseconds; the full run,
    a minute, is the docs' figures' own, on whichever worker runs them)."""
    import mrclutch.cli.commands.fidelity as cmd
    from mrclutch.cli.main import main
    from mrclutch.fidelity import registry

    ms = tuple(m for m in registry() if m.quantity == "bandwidth")
    monkeypatch.setattr(cmd, "registry", lambda: ms)
    out = tmp_path / "fidelity"
    assert main(["fidelity", "--preset", "paper", "--out", str(out), "--repeats", "1"]) == 0
    written = sorted(p.relative_to(out) for p in out.rglob("*") if p.is_file())
    assert {p.name for p in written} == {"fidelity.png", "fidelity.csv", "fidelity.json"}
    _check_named("fidelity", written, {})


def test_documented_names_rules():
    written = [Path("r.csv"), Path("r.csv.meta.json"), Path("cad/rotor.stl"),
               Path("cad/clutch.step"), Path("p.png")]  # fmt: skip
    assert documented_names(written, {"r.csv": "RESULTS.csv", "p.png": "FILE.png"}) == {
        "RESULTS.csv", "RESULTS.csv.meta.json", "<part>.stl", "clutch.step", "FILE.png"
    }  # fmt: skip
    assert re.search(r"<part>\.stl", _help("export"))
