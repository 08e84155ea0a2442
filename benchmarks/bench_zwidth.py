"""Cost of the Z-width next to the numeric metrics. Run from the repository root:
``python -m benchmarks.bench_zwidth``. 10⁴ random designs (seed 0; m1 0.3–50 g, m2 1–50 g,
b1 0.03–5 N·s/m, k 500–20 000 N/m, b 0.05–30 N·s/m, delay 0–2 ms), K uniform 50–800 N/m;
times ``metrics_batch(p, K, limits=False)`` alone and with ``zwidth(p)`` added, median of
3 runs each, in the same process. ``--no-timing``: the Z-width figures alone (one call; what
the docs' value figures read)."""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import metrics_batch
from mrclutch.haptics.zwidth import zwidth

N = 10_000


def designs(n: int = N) -> tuple[HapticParams, np.ndarray]:
    rng = np.random.default_rng(0)
    p = HapticParams(
        m1=rng.uniform(0.3e-3, 50e-3, n),
        m2=rng.uniform(1e-3, 50e-3, n),
        b1=rng.uniform(0.03, 5.0, n),
        k=rng.uniform(500.0, 20_000.0, n),
        b=rng.uniform(0.05, 30.0, n),
        delay=rng.uniform(0.0, 2e-3, n),
    )
    return p, rng.uniform(50.0, 800.0, n)


def median_time(f, repeats: int = 3) -> float:  # type: ignore[no-untyped-def]
    out = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return statistics.median(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--no-timing", action="store_true", help="the Z-width figures alone")
    a = ap.parse_args()
    p, K = designs()
    print(f"designs: {N}")
    if not a.no_timing:
        base = median_time(lambda: metrics_batch(p, K, limits=False))

        def both() -> None:
            metrics_batch(p, K, limits=False)
            zwidth(p)

        full = median_time(both)
        print(f"metrics_batch(limits=False):           {base:8.3f} s (median of 3)")
        print(f"metrics_batch(limits=False) + zwidth:  {full:8.3f} s (median of 3)")
        print(f"ratio:                                 {full / base:8.1f}x")
    r = zwidth(p)
    area = r["zwidth_area_N2_s_per_m2"]
    gap = r["zwidth_area_upper_N2_s_per_m2"] / area - 1.0
    print(f"Z-width area median: {np.median(area):.4g} N²·s/m²; upper/lower − 1: "
          f"median {np.median(gap):.2%}, max {np.max(gap):.2%}")  # fmt: skip


if __name__ == "__main__":
    main()
