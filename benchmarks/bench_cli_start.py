"""``mrclutch --help`` start-up against a bare interpreter, measured in one run (issue 31:
the CLI parses its arguments before it imports numpy or any physics; goal ≤ 0.1 s over
``python -c pass``).

    python benchmarks/bench_cli_start.py [--rounds 20]

Alternates fresh subprocesses of ``python -c pass``, ``python -m mrclutch --help`` and
``python -m mrclutch haptic --help`` (a command's module loaded: numpy and the haptic
model) and prints the median and the minimum wall time of each, and the medians' excess
over ``python -c pass`` (the time the tool adds), and the median CPU time (user + system of
the child: what a loaded machine inflates least). Alternating rounds keep the comparison
honest on a shared, noisy machine. Bytecode is cached in a temporary ``PYTHONPYCACHEPREFIX``
(``PYTHONDONTWRITEBYTECODE`` dropped), as an installed package has its ``.pyc`` files.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
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
    times: dict[str, list[float]] = {k: [] for k in RUNS}
    cpus: dict[str, list[float]] = {k: [] for k in RUNS}
    with tempfile.TemporaryDirectory(prefix="mrclutch-start-") as pyc:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", PYTHONPYCACHEPREFIX=pyc)
        for args in RUNS.values():  # the bytecode written, untimed
            subprocess.run([sys.executable, *args], env=env, cwd=ROOT, check=True,
                           stdout=subprocess.DEVNULL)  # fmt: skip
        for _ in range(a.rounds):
            for name, args in RUNS.items():
                t, c = time.perf_counter(), _cpu()
                subprocess.run([sys.executable, *args], env=env, cwd=ROOT, check=True,
                               stdout=subprocess.DEVNULL)  # fmt: skip
                times[name].append(time.perf_counter() - t)
                cpus[name].append(_cpu() - c)
    base = statistics.median(times["python -c pass"])
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"{name:24s} median {med * 1e3:6.1f} ms  min {min(ts) * 1e3:6.1f} ms  "
              f"over python -c pass {(med - base) * 1e3:+6.1f} ms  "
              f"CPU {statistics.median(cpus[name]) * 1e3:6.1f} ms")  # fmt: skip


def _cpu() -> float:
    """CPU seconds (user + system) of this process's finished children so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


if __name__ == "__main__":
    main()
