"""Speed of the haptic model (issue 2). Run:
``python -m pytest benchmarks/bench_haptic.py --benchmark-enable`` (pytest-benchmark), or
``python -m benchmarks.bench_haptic`` (from the repository root) for a one-screen
summary against the goals: one closed-loop response at 1000 frequencies < 1 ms;
1000 designs × 1000 frequencies < 100 ms; metrics_batch ≥ 1e5 designs/s on the
numeric keys; CLI start < 1.5 s."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np

from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.model import closed_loop_impedance, metrics_batch

W = 2 * np.pi * np.logspace(-1, 4, 1000)


def _designs(n: int, column: bool = False) -> tuple[HapticParams, np.ndarray]:
    rng = np.random.default_rng(0)
    shape = (n, 1) if column else (n,)
    p = HapticParams(
        m1=rng.uniform(1e-3, 0.04, shape),
        b1=rng.uniform(0.1, 2.0, shape),
        k=rng.uniform(2e3, 8e3, shape),
        b=rng.uniform(1.0, 25.0, shape),
        m2=0.014,
        delay=rng.uniform(0.0, 2e-3, shape),
    )
    return p, rng.uniform(50.0, 800.0, shape)


def _start_time(argv: list[str]) -> float:
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mrclutch", *argv], check=True, capture_output=True)
    return time.perf_counter() - t


def test_one_response(benchmark):
    benchmark(closed_loop_impedance, TABLE2_MR, 300.0, W)


def test_1000_designs_x_1000_frequencies(benchmark):
    p, K = _designs(1000, column=True)
    benchmark(closed_loop_impedance, p, K, W)


def test_metrics_batch_numeric_1e5(benchmark):
    p, K = _designs(100_000)
    benchmark.pedantic(metrics_batch, (p, K), {"limits": False}, rounds=3, iterations=1)


def test_metrics_batch_with_limits_100(benchmark):
    p, K = _designs(100)
    benchmark.pedantic(metrics_batch, (p, K), rounds=1, iterations=1)


def test_cli_start(benchmark):
    benchmark.pedantic(_start_time, (["haptic", "--json"],), rounds=3, iterations=1)


def _best(f, *a, repeat: int = 5, **kw) -> float:
    return min(_timed(f, *a, **kw) for _ in range(repeat))


def _timed(f, *a, **kw) -> float:
    t = time.perf_counter()
    f(*a, **kw)
    return time.perf_counter() - t


def main() -> None:
    one = _best(closed_loop_impedance, TABLE2_MR, 300.0, W, repeat=50)
    p, K = _designs(1000, column=True)
    grid = _best(closed_loop_impedance, p, K, W)
    p5, K5 = _designs(100_000)
    mb = _best(metrics_batch, p5, K5, limits=False, repeat=3)
    p2, K2 = _designs(100)
    lim = _best(metrics_batch, p2, K2, repeat=1)
    helps = min(_start_time(["--help"]) for _ in range(3))
    hap = min(_start_time(["haptic", "--json"]) for _ in range(3))
    rows = [
        ("one response, 1000 frequencies", one * 1e3, "ms", 1.0),
        ("1000 designs x 1000 frequencies", grid * 1e3, "ms", 100.0),
        ("metrics_batch numeric keys, 1e5 designs", mb, "s", 1.0),
        ("metrics_batch with limits, 100 designs", lim, "s", None),
        ("mrclutch --help", helps, "s", 1.5),
        ("mrclutch haptic --json", hap, "s", 1.5),
    ]
    for name, v, unit, goal in rows:
        verdict = (
            "" if goal is None else ("ok" if v < goal else "SLOW") + f" (goal < {goal} {unit})"
        )
        print(f"{name:42s} {v:9.3f} {unit:2s} {verdict}")
    print(f"metrics_batch numeric keys: {1e5 / mb:,.0f} designs/s (goal >= 100,000)")
    print(f"metrics_batch with limits: {100 / lim:,.0f} designs/s")


if __name__ == "__main__":
    main()
