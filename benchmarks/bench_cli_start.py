"""``mrclutch --help`` start-up against a bare interpreter, measured in one run (issue 31:
the CLI parses its arguments before it imports numpy or any physics; goal ≤ 0.1 s over
``python -c pass``).

    python benchmarks/bench_cli_start.py [--rounds 20]

Alternates fresh subprocesses of ``python -c pass``, ``python -m mrclutch --help`` and
``python -m mrclutch haptic --help`` (a command's module loaded: numpy and the haptic
model) and prints the median and the minimum wall time of each, and the medians' excess
over ``python -c pass`` (the time the tool adds). Alternating rounds keep the comparison
honest on a shared, noisy machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUNS = {
    "python -c pass": ["-c", "pass"],
    "mrclutch --help": ["-m", "mrclutch", "--help"],
    "mrclutch haptic --help": ["-m", "mrclutch", "haptic", "--help"],
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=20)
    a = ap.parse_args()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    times: dict[str, list[float]] = {k: [] for k in RUNS}
    for _ in range(a.rounds):
        for name, args in RUNS.items():
            t = time.perf_counter()
            subprocess.run([sys.executable, *args], env=env, cwd=ROOT, check=True,
                           stdout=subprocess.DEVNULL)  # fmt: skip
            times[name].append(time.perf_counter() - t)
    base = statistics.median(times["python -c pass"])
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"{name:24s} median {med * 1e3:6.1f} ms  min {min(ts) * 1e3:6.1f} ms  "
              f"over python -c pass {(med - base) * 1e3:+6.1f} ms")  # fmt: skip


if __name__ == "__main__":
    main()
