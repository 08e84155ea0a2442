"""The CLI parses its arguments before it imports numpy or any physics (issue 31): the
command table names each command's module, which is imported only when that command runs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mrclutch.cli.main import COMMANDS, build_parser, command_of, main

ROOT = Path(__file__).resolve().parents[2]
#: The only project modules ``mrclutch --help`` may import.
LIGHT = {"mrclutch", "mrclutch.__main__", "mrclutch.cli", "mrclutch.cli.main",
         "mrclutch.cli.errors", "mrclutch.cli.paths"}  # fmt: skip


def _imported(*args: str) -> tuple[subprocess.CompletedProcess[str], set[str]]:
    """Run ``python -X importtime -m mrclutch ARGS``; (the process, the modules imported)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-X", "importtime", "-m", "mrclutch", *args]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT, timeout=120)
    names = {line.rsplit("|", 1)[1].strip() for line in p.stderr.splitlines()
             if line.startswith("import time:") and "|" in line}  # fmt: skip
    return p, names


def _loaded(*args: str) -> set[str]:
    """sys.modules after ``main(ARGS)`` in a fresh interpreter (importlib.import_module's
    own module is not timed by -X importtime, so this sees what that cannot)."""
    code = (
        "import sys\nfrom mrclutch.cli.main import main\ntry:\n    main(sys.argv[1:])\n"
        "except SystemExit:\n    pass\nprint('\\n'.join(sys.modules), file=sys.stderr)"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                       env=env, cwd=ROOT, timeout=120)  # fmt: skip
    return set(p.stderr.split())


def _ours(names: set[str]) -> set[str]:
    return {n for n in names if n.split(".")[0] in ("geometry", "magnetics", "mrclutch")}


def test_help_imports_neither_numpy_nor_any_physics_module() -> None:
    p, names = _imported("--help")
    assert p.returncode == 0
    for name in COMMANDS:  # every command listed, with its summary's start
        assert f"    {name} " in p.stdout
    assert "numpy" not in names
    assert _ours(names) and _ours(names) <= LIGHT, sorted(_ours(names) - LIGHT)
    loaded = _loaded("--help")
    assert "numpy" not in loaded and "argparse" in loaded
    assert _ours(loaded) <= LIGHT, sorted(_ours(loaded) - LIGHT)


def test_a_command_imports_its_own_module_only() -> None:
    """``mrclutch haptic --help`` loads the haptic commands, not the FEM's or the design's."""
    loaded = _loaded("haptic", "--help")
    assert {COMMANDS["haptic"][0], "numpy"} <= loaded
    assert COMMANDS["torque"][0] not in loaded and COMMANDS["evaluate"][0] not in loaded


def test_the_table_says_what_each_module_registers() -> None:
    """The full parser (every module loaded) has exactly the table's commands, and each
    module's own summary is the table's (one text, two places: they must not drift)."""
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert list(sub.choices) == list(COMMANDS)
    helps = {a.dest: a.help for a in sub._choices_actions}
    assert helps == {name: summary for name, (_, summary) in COMMANDS.items()}


def test_the_lazy_parser_registers_the_command_in_full() -> None:
    """Parsing with only the command's module loaded gives the same options as the full
    parser; the other commands are stubs with no options of their own."""
    full = build_parser()
    full_sub = next(a for a in full._actions if a.dest == "command").choices
    for name in COMMANDS:
        lazy_sub = next(a for a in build_parser([name])._actions if a.dest == "command").choices
        opts = lambda p: sorted(o for a in p._actions for o in a.option_strings)  # noqa: E731
        assert opts(lazy_sub[name]) == opts(full_sub[name])
        other = next(n for n in COMMANDS if COMMANDS[n][0] != COMMANDS[name][0])
        assert opts(lazy_sub[other]) == []


@pytest.mark.parametrize(
    ("argv", "command"),
    [([], None), (["--help"], None), (["torque", "--json"], "torque"),
     (["--version"], None), (["evaluate", "x.toml"], "evaluate")],
)  # fmt: skip
def test_command_of_finds_the_first_word(argv: list[str], command: str | None) -> None:
    assert command_of(argv) == command


def test_an_unknown_command_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["torqeu"])
    assert e.value.code == 2
    assert "invalid choice: 'torqeu'" in capsys.readouterr().err


def test_version_is_read_when_asked(capsys: pytest.CaptureFixture[str]) -> None:
    from importlib.metadata import version

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.strip() == f"mrclutch {version('mrclutch')}"


#: What a single design's answer must not load (issue 40: interactive commands in well under
#: a second): each of these costs ≈ 0.3–1 s to import (scipy.optimize alone ≈ 0.9 s of CPU,
#: numba with a cached kernel ≈ 1 s).
HEAVY = ("scipy", "numba", "llvmlite", "matplotlib", "build123d", "OCP", "pyvista",
         "trimesh", "pandas", "pyarrow", "dask")  # fmt: skip


def test_the_interactive_commands_load_nothing_heavy(fresh_python) -> None:
    """``haptic``, ``torque``, ``compare``, ``evaluate`` (with its uncertainty) and the
    analytic ``inertia`` on the paper preset, one after another in one interpreter: not one
    of them imports scipy, numba, matplotlib or a CAD kernel (the network's single-design
    solve runs its kernels uncompiled, magnetics.network; the verdict's thresholds use
    geometry.numerics' root-find)."""
    code = (
        "import sys\nfrom mrclutch.cli.main import main\n"
        "for argv in (['haptic'], ['torque', '--preset', 'paper'], ['compare'],\n"
        "             ['evaluate', '--preset', 'paper'],\n"
        "             ['inertia', '--preset', 'paper', '--method', 'analytic']):\n"
        "    assert main(argv) == 0, argv\n"
        "print('\\n'.join(sys.modules), file=sys.stderr)"
    )
    p = fresh_python(code)
    loaded = set(p.stderr.split())
    assert "numpy" in loaded and "mrclutch.pipeline" in loaded  # the commands ran
    assert not {n for n in loaded if n.split(".")[0] in HEAVY}, sorted(
        {n.split(".")[0] for n in loaded if n.split(".")[0] in HEAVY}
    )


def test_a_torque_curve_loads_no_report_module(fresh_python) -> None:
    """``torque`` builds the design's section itself (geometry.section) and reads the current
    notes beside the limit (mrclutch.design): neither the report's data module and the CAD
    export it imports nor the clutch's figures (mrclutch.clutch, its trust maps and masses)
    are loaded for a torque curve (issue 40 item 1)."""
    code = (
        "import sys\nfrom mrclutch.cli.main import main\n"
        "assert main(['torque', '--preset', 'paper']) == 0\n"
        "print('\\n'.join(sys.modules), file=sys.stderr)"
    )
    loaded = set(fresh_python(code).stderr.split())
    assert "mrclutch.torque_curves" in loaded and "geometry.section" in loaded  # it ran
    assert "mrclutch.report_data" not in loaded and "geometry.export" not in loaded
    assert "mrclutch.clutch" not in loaded and "mrclutch.trust" not in loaded
    assert "mrclutch.duty" not in loaded and "magnetics.hot" not in loaded  # no thermal march


#: The duty's figures and the "duty" range's resolution: the thermal march, the network's
#: yield torque and the haptic model behind them (mrclutch.duty, mrclutch.hot_range).
DUTY_MODELS = ("mrclutch.duty", "mrclutch.hot_range", "magnetics.hot", "magnetics.life",
               "magnetics.torque", "magnetics.network", "mrclutch.haptics.model")  # fmt: skip


def test_a_design_loads_without_the_duty_model(fresh_python, tmp_path) -> None:
    """A design file with a ``[duty]`` table and its fluid temperature range declared
    ``"duty"`` is read, and weighed analytically, without loading the duty's thermal model
    or the network (``mrclutch.duty_spec`` holds the table; the range is resolved only by
    ``mrclutch.hot_range.resolved_ranges``, when a verdict asks for it). Issue 40 item 1."""
    f = tmp_path / "hot.toml"
    f.write_text('[clutch]\nbase = "paper"\n\n[duty]\ntorque_N_m = 0.2\ntime_s = 60\n\n'
                 '[uncertainty]\nfluid_temperature_C = "duty"\n')  # fmt: skip
    code = (
        "import sys\nfrom mrclutch.cli.main import main\n"
        f"assert main(['inertia', {str(f)!r}, '--method', 'analytic']) == 0\n"
        "from mrclutch.design import load_design\n"
        f"d = load_design({str(f)!r})\n"
        "print(d.duty.torque, d.uncertainty.fluid_temperature_from)\n"
        "print('\\n'.join(sys.modules), file=sys.stderr)"
    )
    p = fresh_python(code)
    loaded = set(p.stderr.split())
    assert p.stdout.splitlines()[-1] == "0.2 duty"  # the table and the range were read
    assert "mrclutch.duty_spec" in loaded and "mrclutch.inertia" in loaded
    assert not loaded & set(DUTY_MODELS), sorted(loaded & set(DUTY_MODELS))
