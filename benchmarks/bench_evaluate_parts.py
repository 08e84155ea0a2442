"""Where one ``mrclutch evaluate`` spends its CPU (issue 40 item 1): the interpreter and
numpy, the project's imports (and, of them, the creation of its dataclasses), and the
stages of the judgement, measured in one run.

    python benchmarks/bench_evaluate_parts.py [--rounds 5] [--no-uncertainty] [ARGS...]

Each round is a fresh subprocess (this checkout first on ``PYTHONPATH``; bytecode cached in
a temporary ``PYTHONPYCACHEPREFIX``, as an installed package has its ``.pyc`` files) that
wraps the stages' functions in CPU timers (``time.process_time``) before running
``mrclutch evaluate --preset paper`` (or ARGS) in-process, its output discarded. Prints the
median over the rounds of each part's CPU seconds and its share of the whole run. The
stages nest (the Python network kernel runs inside the clutch figures, the feel and the
duty): a part's "of which" rows are inside the row above them, not beside it. The wrappers
cost a few microseconds a call; ratios, not absolute times, are what a loaded machine
keeps.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: (label, module, attribute, depth): the functions timed, as the caller looks them up.
PARTS = (
    ("judge (the whole judgement)", "mrclutch.cli.commands.evaluate", "judge", 0),
    ("clutch figures", "mrclutch.pipeline", "clutch_figures", 1),
    ("torque response (step, lags)", "mrclutch.pipeline", "torque_response", 1),
    ("stable K at the typed and torque delays", "mrclutch.pipeline", "response_figures", 1),
    ("feel (loop, pulse, ripple)", "mrclutch.pipeline", "feel_figures", 1),
    ("hand figures (coupled stability)", "mrclutch.at_hand", "hand_figures", 1),
    ("of which the hands' scans", "mrclutch.haptics.hand", "_limits_hands", 2),
    ("duty (hot holds: the thermal march)", "mrclutch.pipeline", "evaluation_duty", 1),
    ("robust box (hand box, limits)", "mrclutch.verdict", "robust_box", 1),
    ("of which the box's fast path", "mrclutch.hand_box", "evaluate_batch", 2),
    ("of which the limits over the box", "mrclutch.robust", "robust_limits", 2),
    ("robust verdicts (searches, thresholds)", "mrclutch.verdict", "robust_verdicts", 1),
    ("of which the Z-width (nominal, searches)", "mrclutch.robust", "zwidth_of", 2),
    ("of which the thresholds (b1, delay)", "mrclutch.robust", "threshold", 2),
    ("network kernel in Python (_solve_rows)", "magnetics.network.kernels", "_solve_rows", 1),
    ("text", "mrclutch.cli.commands.evaluate", "format_evaluation", 0),
)

CHILD = r"""
import contextlib, dataclasses, importlib, io, json, sys, time
parts = json.loads(sys.argv[1])
t0 = time.process_time()
import numpy
t1 = time.process_time()
made = [0.0]
real = dataclasses._process_class
def timed_class(*a, **k):
    t = time.process_time()
    try:
        return real(*a, **k)
    finally:
        made[0] += time.process_time() - t
dataclasses._process_class = timed_class
import mrclutch.cli.main as main
import mrclutch.cli.commands.evaluate
t2 = time.process_time()
dataclasses._process_class = real
spent = {}
def wrap(label, mod, name):
    m = importlib.import_module(mod)
    f = getattr(m, name)
    def timed(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            spent[label] = spent.get(label, 0.0) + time.process_time() - t
    setattr(m, name, timed)
for label, mod, name, _ in parts:
    wrap(label, mod, name)
with contextlib.redirect_stdout(io.StringIO()):
    main.main(sys.argv[2:])
t3 = time.process_time()
print(json.dumps({"start": t0, "numpy": t1 - t0, "imports": t2 - t1, "dataclasses": made[0],
                  "run": t3 - t2, "total": t3, **spent}))
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("args", nargs="*", help="evaluate's arguments (default --preset paper)")
    a, rest = ap.parse_known_args()
    argv = ["evaluate", *(a.args + rest or ["--preset", "paper"])]
    runs = []
    with tempfile.TemporaryDirectory(prefix="bench_parts_") as tmp:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1",
                   PYTHONPYCACHEPREFIX=str(Path(tmp) / "pyc"))  # fmt: skip
        for i in range(a.rounds + 1):  # the first run writes the bytecode: not counted
            out = subprocess.run([sys.executable, "-c", CHILD, json.dumps(PARTS), *argv],
                                 env=env, cwd=ROOT, capture_output=True, text=True)  # fmt: skip
            if out.returncode != 0:
                raise SystemExit(f"{' '.join(argv)}: exit {out.returncode}\n{out.stderr[-2000:]}")
            if i:
                runs.append(json.loads(out.stdout.splitlines()[-1]))
    med = {k: statistics.median(r.get(k, 0.0) for r in runs) for k in runs[0]}
    total = med["total"]
    print(f"mrclutch {' '.join(argv)}: median CPU of {a.rounds} fresh runs "
          f"(load {os.getloadavg()[0]:.2f}, {os.cpu_count()} CPUs)")  # fmt: skip
    rows = [("interpreter start", med["start"], 0), ("import numpy", med["numpy"], 0),
            ("the command's project imports", med["imports"], 0),
            ("  of which dataclass creation", med["dataclasses"], 1),
            ("the command (parse, judge, print)", med["run"], 0)]  # fmt: skip
    rows += [(("  " * depth) + label, med.get(label, 0.0), depth)
             for label, _, _, depth in PARTS]  # fmt: skip
    for label, sec, _ in rows:
        print(f"{label:44s} {sec * 1e3:8.1f} ms {100 * sec / total:5.1f} %")
    print(f"{'total':44s} {total * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
