"""Fast-path throughput of the design pipeline (issue 5 acceptance), printed as figures.

    python benchmarks/bench_pipeline.py

* ``evaluate_batch`` of 10^5 random designs in this process (mass + torque + drag +
  haptic metrics), designs per second;
* the same 10^5 designs through ``run_sweep`` with a 2-process pool (CSV written);
* the CLI: ``mrclutch sweep`` of 10^5 designs, wall time including start-up;
* the parts of one batch call, so a regression points at its source.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from mrclutch.design import design_preset
from mrclutch.outputs import SWEEP_COLUMNS
from mrclutch.pipeline import BatchEvaluator, evaluate_batch
from mrclutch.sweep import ParamRange, SweepSpec, run_sweep

N = 100_000


def random_fields(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "gap": rng.uniform(0.2e-3, 1.0e-3, n),
        "drum_thickness": rng.uniform(0.1e-3, 0.5e-3, n),
        "n_drums": rng.integers(1, 5, n),
        "drum_inner_diameter": rng.uniform(8e-3, 16e-3, n),
    }


def best_of(fn, repeats: int = 3) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def parts(fields: dict[str, np.ndarray]) -> dict[str, float]:
    from geometry.mass import analytic_batch
    from magnetics.torque import max_torque_batch, viscous_batch
    from mrclutch.haptics.actuator import HapticParams
    from mrclutch.haptics.model import metrics_batch

    d = design_preset("paper")
    hp = HapticParams(m1=np.full(N, 1e-3), b1=np.full(N, 0.2), k=4000.0, b=20.0, m2=14e-3,
                      delay=1e-3, f_max=np.full(N, 20.0))  # fmt: skip
    return {
        "analytic mass": best_of(lambda: analytic_batch(fields)),
        "circuit torque": best_of(lambda: max_torque_batch(fields, 7.0)),
        "viscous drag": best_of(lambda: viscous_batch(fields, d.operating.input_speed)),
        "haptic metrics": best_of(lambda: metrics_batch(hp, limits=False)),
    }


def main() -> None:
    fields = random_fields(N)
    base = design_preset("paper")
    evaluate_batch({k: v[:100] for k, v in fields.items()}, base)  # warm imports
    t1 = best_of(lambda: evaluate_batch(fields, base))
    print(f"evaluate_batch, 1 process: {N / t1:,.0f} designs/s ({t1:.2f} s per 10^5)")
    for name, t in parts(fields).items():
        print(f"  {name:<16} {t * 1e3:7.0f} ms per 10^5")

    spec = SweepSpec(
        (ParamRange("gap", 0.2e-3, 1.0e-3, 0), ParamRange("n_drums", 1, 4, 0),
         ParamRange("drum_thickness", 0.1e-3, 0.5e-3, 0)),
        mode="random", samples=N, seed=1, chunk_size=25_000,
    )  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(2) as pool:
        list(pool.map(BatchEvaluator(base), [{"gap": [0.3e-3]}] * 2))  # warm workers
        t = time.perf_counter()
        run_sweep(spec, Path(tmp) / "r.csv", BatchEvaluator(base), SWEEP_COLUMNS,
                  executor=pool, progress=False)  # fmt: skip
        t2 = time.perf_counter() - t
    print(f"run_sweep, 2 processes, CSV: {N / t2:,.0f} designs/s ({t2:.2f} s per 10^5)")

    spec_file = Path(__file__).resolve().parent.parent / "examples" / "random_sweep.toml"
    with tempfile.TemporaryDirectory() as tmp:
        for workers in ("0", "2"):
            out = Path(tmp) / f"r{workers}.csv"
            t = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "mrclutch", "sweep", str(spec_file), "--out", str(out),
                 "--no-progress", "--workers", workers],
                check=True, capture_output=True, env={**os.environ},
            )  # fmt: skip
            t3 = time.perf_counter() - t
            rows = len(out.read_text().splitlines()) - 1
            print(f"CLI mrclutch sweep of {rows:,} designs, --workers {workers}: {t3:.2f} s "
                  f"(goal < 10 s)")  # fmt: skip


if __name__ == "__main__":
    main()
