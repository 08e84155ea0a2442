"""The sweep's Pareto plot on 10⁵ rows (issue 40: ≤ 2 s), and what its samples save.

    python benchmarks/bench_sweep_plot.py [--csv RESULTS.csv] [--rounds 3] [--against DIR]

Without ``--csv`` it first runs ``mrclutch sweep examples/random_sweep.toml`` (10⁵ random
designs, minutes) into a temporary folder. Then, each in a fresh process (imports
included: what ``sweep --pareto`` adds after its rows), ``pareto_plot`` on those rows:

- as shipped: the scatter panels past ``MAX_POINTS`` designs binned (``BINS`` cells), the
  parallel-coordinates panel at most ``MAX_LINES`` lines of the front over a random sample
  of ``MAX_REST_LINES`` of the other designs;
- everything drawn (the three limits set past the row count: every point and every line of
  the valid designs, what a plot without samples draws).

Prints the median wall and CPU time (user + system of the child, what a loaded machine
inflates least) of ``--rounds`` runs, the CPU of the plot's own thread (its critical path:
the rows are read and their fronts found on a second thread beside matplotlib's import),
each step's share (the module's import; matplotlib's import with the rows read and their
fronts found beside it; drawing; PNG) and the ratio of the two, with the machine and its
load average: times are this machine's. Bytecode is cached in a temporary
``PYTHONPYCACHEPREFIX`` (``PYTHONDONTWRITEBYTECODE`` dropped; an untimed first run of each
checkout writes it), as an installed package has its ``.pyc`` files: without it every
round compiles the project's modules again (~0.3 s of CPU here).
Then the shipped plot as ``sweep --pareto`` waits for it after its bar: in a process that
has first loaded what that command has (its module, and through it the plot's), the plot's
own wall and CPU, from the plot module's import to the PNG.
``--against DIR`` (another checkout) times its shipped plot beside this one's, each round
alternating between the two, so that both see the same load.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GOAL_S = 2.0

#: One plot in a fresh process: its steps' times as JSON on stdout.
CHILD = r"""
import json, sys, time
if sys.argv[4] == "command":  # what sweep --pareto has loaded when its rows are written
    import mrclutch.cli.commands.sweep
t0, c0, m0 = time.perf_counter(), time.process_time(), time.thread_time()
import mrclutch.cli.plots.design as d
if sys.argv[3] == "all":
    d.MAX_POINTS = d.MAX_LINES = d.MAX_REST_LINES = 10**9
marks = [time.perf_counter()]
d.pareto_plot(sys.argv[1], sys.argv[2], progress=lambda n: marks.append(time.perf_counter()))
print(json.dumps({"import": marks[0] - t0, "steps": [b - a for a, b in zip(marks, marks[1:])],
                  "total": marks[-1] - t0, "cpu": time.process_time() - c0,
                  "main_cpu": time.thread_time() - m0, "file": d.__file__}))
"""
STEPS = ("matplotlib's import and the rows' data", "", "drawing", "PNG")


def _child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def plot_once(csv: Path, png: Path, mode: str, root: Path = ROOT, start: str = "fresh",
              pyc: Path | None = None) -> tuple[float, float, dict]:  # fmt: skip
    """(wall s, CPU s, the child's step times) of one plot in a fresh process, with the
    checkout ``root`` first on the path; ``start="command"``: the child first imports what
    ``sweep --pareto`` has loaded before its plot (its command module), and the wall and
    CPU are the plot's own (from its module's import to the PNG), as that command waits;
    ``pyc``: the folder of the bytecode cache (``PYTHONPYCACHEPREFIX``)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = f"{root}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"
    if pyc is not None:
        env["PYTHONPYCACHEPREFIX"] = str(pyc)
    cpu0, t0 = _child_cpu(), time.perf_counter()
    # run in ``root``: ``python -c`` puts the working folder first on the path, before
    # PYTHONPATH (from elsewhere, --against timed this checkout twice)
    out = subprocess.run([sys.executable, "-c", CHILD, str(csv), str(png), mode, start],
                         env=env, cwd=root, capture_output=True, text=True, check=True)  # fmt: skip
    wall = time.perf_counter() - t0
    got = json.loads(out.stdout.strip().splitlines()[-1])
    if start == "command":
        wall, cpu = got["total"], got["cpu"]
        return wall, cpu, got
    if not Path(got["file"]).resolve().is_relative_to(Path(root).resolve()):
        raise SystemExit(f"timed {got['file']}, not the checkout {root}")
    return wall, _child_cpu() - cpu0, got


def sweep_rows(tmp: Path) -> Path:
    """The 10⁵ rows of examples/random_sweep.toml, swept here."""
    csv = tmp / "random_sweep.csv"
    print("sweeping examples/random_sweep.toml (10^5 designs) ...", file=sys.stderr)
    subprocess.run([sys.executable, "-m", "mrclutch", "sweep",
                    str(ROOT / "examples" / "random_sweep.toml"), "--out", str(csv),
                    "--no-progress"], check=True)  # fmt: skip
    return csv


def _median(runs: list[tuple[float, float, dict]]) -> tuple[float, float, float]:
    """Median wall, CPU and the plot thread's own CPU of ``plot_once`` runs."""
    return (statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs),
            statistics.median(r[2]["main_cpu"] for r in runs))  # fmt: skip


def _against(csv: Path, tmp: Path, other: Path, rounds: int) -> None:
    """The shipped plot here and in ``other``, the rounds alternating (both on one load):
    median wall and CPU of each and their ratio (each checkout's bytecode written first,
    untimed)."""
    runs: dict[Path, list[tuple[float, float, dict]]] = {ROOT: [], other: []}
    for root in runs:
        plot_once(csv, tmp / "ab.png", "shipped", root, pyc=tmp / "pyc")
    for _ in range(rounds):
        for root in runs:
            runs[root].append(plot_once(csv, tmp / "ab.png", "shipped", root, pyc=tmp / "pyc"))
    med = {root: _median(rs) for root, rs in runs.items()}
    for root, (wall, cpu, main_cpu) in med.items():
        print(f"as shipped, {str(root)[-28:]:>28s}: wall {wall:6.2f} s  CPU {cpu:6.2f} s "
              f"(the plot's thread {main_cpu:.2f} s)")  # fmt: skip
    (w1, c1, _), (w0, c0, _) = med[ROOT], med[other]
    print(f"this checkout / {other.name}: wall ratio {w1 / w0:.2f}, CPU ratio {c1 / c0:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", type=Path, help="a sweep's results (default: sweep 10^5 rows)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--against", type=Path, default=None, metavar="DIR",
                    help="another checkout (git worktree add /tmp/before REV): its shipped "
                    "plot timed beside this one's, the rounds alternating")  # fmt: skip
    args = ap.parse_args()
    if args.against is not None and not (args.against / "mrclutch" / "__main__.py").is_file():
        raise SystemExit(f"--against {args.against}: not a checkout of mrclutch")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"Python {platform.python_version()}; load average before: "
          f"{os.getloadavg()[0]:.2f}")  # fmt: skip
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        csv = args.csv if args.csv is not None else sweep_rows(tmp)
        rows = sum(1 for _ in csv.open()) - 1
        print(f"rows: {rows} ({csv})")
        pyc = tmp / "pyc"
        plot_once(csv, tmp / "warm.png", "shipped", pyc=pyc)  # the bytecode written, untimed
        result = {}
        for mode, what in (("shipped", "as shipped (binned)"), ("all", "everything drawn")):
            runs = [plot_once(csv, tmp / f"{mode}.png", mode, pyc=pyc)
                    for _ in range(args.rounds)]  # fmt: skip
            wall, cpu, main_cpu = _median(runs)
            mid = sorted(runs, key=lambda r: r[0])[len(runs) // 2][2]
            steps = "; ".join(f"{n} {s:.2f}" for n, s in zip(STEPS, mid["steps"], strict=False)
                              if n)  # fmt: skip
            result[mode] = (wall, cpu)
            goal = f"  (goal <= {GOAL_S:g} s)" if mode == "shipped" else ""
            print(f"{what:24s} wall {wall:6.2f} s  CPU {cpu:6.2f} s, the plot's thread "
                  f"{main_cpu:.2f} s{goal}\n"
                  f"{'':24s} steps (wall, s): the module's import {mid['import']:.2f}; "
                  f"{steps}")  # fmt: skip
        (w1, c1), (w2, c2) = result["shipped"], result["all"]
        print(f"everything drawn / as shipped: wall ratio {w2 / w1:.1f}, CPU ratio {c2 / c1:.1f}")
        runs = [plot_once(csv, tmp / "command.png", "shipped", start="command", pyc=pyc)
                for _ in range(args.rounds)]  # fmt: skip
        wall, cpu, _ = _median(runs)
        print(
            f"{'in sweep --pareto':24s} wall {wall:6.2f} s  CPU {cpu:6.2f} s  (the plot "
            f"alone, after the modules the sweep has loaded: what it waits after its bar)"
        )
        if args.against is not None:
            _against(csv, tmp, args.against.resolve(), args.rounds)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
