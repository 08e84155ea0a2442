"""Every wait a designer notices, measured in one run (issue 40): the wall time of each
command a designer runs, against its goal.

    python benchmarks/bench_waits.py [--rounds 3] [--skip-install] [--skip-long]
                                     [--against DIR]

Runs each command in a fresh subprocess (this checkout first on ``PYTHONPATH``, the
user's numba cache as it is: run it once before to measure the "after the first run"
times; bytecode written to a temporary ``PYTHONPYCACHEPREFIX`` and
``PYTHONDONTWRITEBYTECODE`` dropped, as an installed package has its ``.pyc`` files: without
them every run compiles the project's sources, ≈ 0.3 s more; the long jobs' third-party
packages, ``WARM``, imported once before they are timed) and prints the median of
``--rounds`` runs (one for the long jobs), its CPU time (user + system of the child: what a
loaded machine inflates least) and the goal:

- interactive (≤ 0.5 s after the first run): ``evaluate --preset paper`` with and without
  its uncertainty, ``haptic``, ``torque``, ``compare``, ``inertia --method analytic``;
- ``report`` (≤ 8 s), ``optimize`` (default Pareto set, ≤ 30 s with progress), ``scale``
  (progress past 2 s), ``fidelity`` (progress past 2 s), ``sweep
  examples/random_sweep.toml --pareto`` (its plot ≤ 2 s: the plot step timed alone on the
  sweep's CSV in a fresh process);
- the first run after a fresh ``pip install .`` into a temporary venv
  (``--system-site-packages``: the dependencies of this environment; the project with
  ``--no-deps``; an empty numba cache), ``evaluate --preset paper --no-uncertainty`` and a
  solve of 10³ designs (which compiles the kernels), each run twice: the first run's excess
  over the second (goal ≤ 5 s), and the compile notice's estimate beside the time the
  compile took.

Times depend on the machine and its load: the script prints the load average beside them.
``--against DIR`` (another checkout, e.g. ``git worktree add /tmp/before HEAD~3``) times its
interactive commands in the same run, each round of a command alternating between the two
checkouts, so both columns see the same load: a before/after that a changing load does not
fake.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

INTERACTIVE = {
    "evaluate --preset paper": "evaluate --preset paper",
    "evaluate --preset paper --no-uncertainty": "evaluate --preset paper --no-uncertainty",
    "haptic": "haptic",
    "torque --preset paper": "torque --preset paper",
    "compare": "compare",
    "inertia --preset paper --method analytic": "inertia --preset paper --method analytic",
}
LONG = {
    "report --preset paper": ("report --preset paper --out {tmp}/report", 8.0),
    "optimize --preset paper": ("optimize --preset paper", 30.0),
    "scale --preset paper": ("scale --preset paper", None),
    "fidelity --preset paper --repeats 1": (
        "fidelity --preset paper --repeats 1 --out {tmp}/fidelity",
        None,
    ),
    "sweep random_sweep.toml --pareto": (
        "sweep examples/random_sweep.toml --out {tmp}/sweep.csv --pareto {tmp}/pareto.png "
        "--overwrite --yes",
        None,
    ),
}

#: The third-party packages the long jobs import (the report's and optimize's CAD process:
#: build123d, which pulls scipy, sklearn, ezdxf; VTK; matplotlib; the sweep's Parquet),
#: imported once before they are timed, so their bytecode is in the temporary
#: ``PYTHONPYCACHEPREFIX`` as an installed package has its ``.pyc`` files: without it the
#: first long job compiles them (≈ 18 s CPU more on the report, r41's measurement).
WARM = (
    "import build123d, pyvista, matplotlib.pyplot, matplotlib.backends.backend_agg, "
    "pyarrow.parquet, tqdm, scipy.sparse.linalg, vtkmodules.vtkRenderingOpenGL2"
)

#: 10³ designs at two currents: past the uncompiled budget, so the kernels compile.
SOLVE = """
import numpy as np
from geometry.params import preset
from magnetics.torque import network_torque_batch
f = {k: np.full(1000, float(v)) for k, v in vars(preset("paper")).items()}
f["gap"] = np.linspace(0.3e-3, 0.5e-3, 1000)
print(float(network_torque_batch(f, [2.0, 7.0]).sum()))
"""


#: A progress bar with an estimate, as mrclutch.cli.progress draws it (tqdm): "NN%|…| n/N
#: [elapsed<remaining" with a remaining time (not "?", the bar before its first count).
#: Not any "eta" in the text: that word is in "metadata", "details", "beta".
ESTIMATE = re.compile(r"\d+%\|[^|\n]*\| *\d+/\d+ \[[\d:]+<[\d:]+")


def _cpu() -> float:
    """CPU seconds (user + system) of this process's finished children so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(argv: list[str], env: dict[str, str], cwd: Path) -> tuple[float, str, float]:
    """(wall s, stderr, CPU s) of ``argv`` run to its end."""
    t, c = time.perf_counter(), _cpu()
    run = subprocess.run(argv, env=env, cwd=cwd, capture_output=True, text=True)
    took = time.perf_counter() - t
    if run.returncode != 0:
        raise SystemExit(f"{' '.join(argv)}: exit {run.returncode}\n{run.stderr[-2000:]}")
    return took, run.stderr, _cpu() - c


def _mrclutch(cmd: str, tmp: Path) -> list[str]:
    return [sys.executable, "-m", "mrclutch", *cmd.replace("{tmp}", str(tmp)).split()]


#: The sweep's plot alone, on the sweep's results (imports included: what the sweep adds
#: after its last row).
PLOT = """
import sys
from mrclutch.cli.plots.design import pareto_plot
pareto_plot(sys.argv[1], sys.argv[2])
"""


def _plot_wait(tmp: Path, env: dict[str, str]) -> str:
    """The sweep's plot step timed alone on the sweep's CSV, in a fresh process."""
    took, _, _ = _run([sys.executable, "-c", PLOT, str(tmp / "sweep.csv"),
                       str(tmp / "p2.png")], env, ROOT)  # fmt: skip
    return f"{took:.2f} s (≤ 2 s {'met' if took <= 2 else 'NOT met'})"


def install_first_run(tmp: Path) -> list[tuple[str, float, float, str]]:
    """(what, first run s, second run s, CPU s of both and the first run's compile notice)
    in a fresh venv with the project installed from a copy of this working tree and an
    empty numba cache."""
    ls = ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"]
    names = subprocess.run(ls, cwd=ROOT, capture_output=True, check=True).stdout.decode()
    src = tmp / "src"
    for name in filter(None, names.split("\0")):
        if (ROOT / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, src / name)
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)],
                   check=True)  # fmt: skip
    py = str(venv / "bin" / "python")
    drop = ("NUMBA_CACHE_DIR", "PYTHONPATH", "PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX")
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update(XDG_CACHE_HOME=str(tmp / "cache"), PATH=f"{venv / 'bin'}:{env['PATH']}",
               PIP_DISABLE_PIP_VERSION_CHECK="1")  # fmt: skip
    subprocess.run([py, "-m", "pip", "install", "-q", "--no-deps", str(src)], env=env,
                   check=True)  # fmt: skip
    out = []
    for what, argv in (
        ("evaluate --preset paper --no-uncertainty",
         ["mrclutch", "evaluate", "--preset", "paper", "--no-uncertainty"]),
        ("a solve of 10^3 designs (compiles)", [py, "-c", SOLVE]),
    ):  # fmt: skip
        first, err, cpu1 = _run(argv, env, tmp)
        second, _, cpu2 = _run(argv, env, tmp)
        lines = [ln for ln in err.splitlines() if "compiling" in ln]  # the estimate's last
        said = (lines[-1] if lines else "").strip()
        said += _estimate(err)
        out.append((what, first, second, f"CPU {cpu1:.2f} s then {cpu2:.2f} s; {said}"))
    return out


def _estimate(err: str) -> str:
    """The compile notice's estimate beside the time the compile took (its stderr)."""
    said = re.search(r"left of ~(\d+) s", err)
    took = re.search(r"compiled in ([\d.]+) s", err)
    if not (said and took):
        return ""
    est, real = float(said.group(1)), float(took.group(1))
    return f"\n    estimate ~{est:.0f} s, the compile took {real:.1f} s (x{est / real:.2f})"


def _interactive(rounds: int, tmp: Path, roots: list[Path]) -> None:
    """The floor and the interactive commands: median wall and CPU of ``rounds`` runs in
    each checkout of ``roots`` (its first the one judged against the goal), the rounds
    alternating between them."""
    envs = []
    for root in roots:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1",
                   PYTHONPYCACHEPREFIX=str(tmp / "pyc"))  # fmt: skip
        envs.append(env)
        for cmd in ("evaluate --preset paper", *INTERACTIVE.values()):  # the first runs
            _run(_mrclutch(cmd, tmp), env, root)
    head = "".join(f" {'median s':>9s} {'CPU s':>6s}" for _ in roots)
    print(f"{'command':44s}{head}  goal")
    if len(roots) > 1:
        print(f"{'':44s}" + "".join(f" {str(r)[-16:]:>16s}" for r in roots))

    def row(name: str, argv: list[str], goal: bool) -> None:
        runs: list[list[tuple[float, str, float]]] = [[] for _ in roots]
        for _ in range(rounds):
            for i, (env, root) in enumerate(zip(envs, roots, strict=True)):
                runs[i].append(_run(argv, env, root))
        meds = [(statistics.median(r[0] for r in rs), statistics.median(r[2] for r in rs))
                for rs in runs]  # fmt: skip
        cells = "".join(f" {w:9.2f} {c:6.2f}" for w, c in meds)
        verdict = f"  ≤ 0.5 s {'met' if meds[0][0] <= 0.5 else 'NOT met'}" if goal else ""
        print(f"{name:44s}{cells}{verdict}")

    # the floor under every command: the interpreter and numpy (on the same load)
    row("(floor) python -c 'import numpy'", [sys.executable, "-c", "import numpy"], False)
    for name, cmd in INTERACTIVE.items():
        row(name, _mrclutch(cmd, tmp), True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3, help="runs of each interactive command")
    ap.add_argument("--skip-install", action="store_true", help="no fresh-venv first run")
    ap.add_argument("--skip-long", action="store_true", help="interactive commands only")
    ap.add_argument("--against", type=Path, default=None, metavar="DIR",
                    help="another checkout whose interactive commands are timed beside "
                    "this one's, on the same load")  # fmt: skip
    a = ap.parse_args()
    roots = [ROOT]
    if a.against is not None:
        if not (a.against / "mrclutch" / "__main__.py").is_file():
            raise SystemExit(f"--against {a.against}: not a checkout of mrclutch")
        roots.append(a.against.resolve())
    print(f"load average before: {os.getloadavg()[0]:.2f} ({os.cpu_count()} CPUs)")
    with tempfile.TemporaryDirectory(prefix="mrclutch-waits-") as t:
        tmp = Path(t)
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1",
                   PYTHONPYCACHEPREFIX=str(tmp / "pyc"))  # fmt: skip
        _interactive(a.rounds, tmp, roots)
        if not a.skip_long:
            _run([sys.executable, "-c", WARM], env, ROOT)
            for name, (cmd, goal) in LONG.items():
                took, err, cpu = _run(_mrclutch(cmd, tmp), env, ROOT)
                said = "progress on stderr" if ESTIMATE.search(err) else "NO progress on stderr"
                verdict = "" if goal is None else (
                    f"≤ {goal:g} s {'met' if took <= goal else 'NOT met'}")  # fmt: skip
                extra = f"  plot alone: {_plot_wait(tmp, env)}" if name.startswith("sweep") else ""
                print(f"{name:44s} {took:9.2f} {cpu:6.2f}  {verdict} {said}{extra}")
        if not a.skip_install:
            for what, first, second, said in install_first_run(tmp):
                excess = first - second
                print(f"fresh install, {what:30s} first {first:6.2f} s  second "
                      f"{second:6.2f} s  excess {excess:+6.2f} s  ≤ 5 s "
                      f"{'met' if excess <= 5 else 'NOT met'}")  # fmt: skip
                print(f"    {said}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
