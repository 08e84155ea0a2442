"""Speed of the reluctance network against the single loop: yield torque of 10⁵ random
designs (the sweep's ranges, 1–6 drums) at 3 currents, designs per second on one core, and
the ratios, measured in one run (alternating rounds; the best of each). The loop is timed
two ways: solved at each current (``max_torque_batch``, its fastest path, the issue's
"~6·10⁴/s") and through its torque table (``torque_grid_batch``, what sweeps used).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_network.py [--designs 100000] [--rounds 3]
        [--skip-table]

``--skip-table`` leaves the torque table out (it takes 30× the others' time). The network's
compiled kernels are loaded (or compiled, once per machine) before the clock starts.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def designs(n: int, seed: int = 1) -> dict[str, np.ndarray]:
    from mrclutch.design import design_preset

    base = vars(design_preset("paper").clutch)
    rng = np.random.default_rng(seed)
    f = {k: np.full(n, float(v)) for k, v in base.items()}
    f["n_drums"] = rng.integers(1, 7, n).astype(float)
    f["gap"] = rng.uniform(0.2e-3, 1.0e-3, n)
    f["zone_length"] = rng.uniform(3e-3, 9e-3, n)
    f["drum_inner_diameter"] = rng.uniform(6e-3, 18e-3, n)
    f["drum_thickness"] = rng.uniform(0.1e-3, 0.6e-3, n)
    return f


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--designs", type=int, default=100_000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--skip-table", action="store_true", help="leave the torque table out")
    a = ap.parse_args()
    from magnetics.torque import max_torque_batch, network_torque_batch, torque_grid_batch

    f = designs(a.designs)
    cur = [2.0, 4.0, 7.0]
    network_torque_batch(designs(10, 2), cur)  # the kernels loaded (compiled once a machine)

    def loop_solved(fields, currents):  # type: ignore[no-untyped-def]
        return np.stack([max_torque_batch(fields, c) for c in currents], axis=1)

    runs = (("network", network_torque_batch), ("loop, solved per current", loop_solved),
            ("loop, torque table", torque_grid_batch))[: 2 if a.skip_table else 3]  # fmt: skip
    best = {name: np.inf for name, _ in runs}
    for _ in range(a.rounds):
        for name, fn in runs:
            t0 = time.perf_counter()
            out = fn(f, cur)
            best[name] = min(best[name], time.perf_counter() - t0)
            assert np.isfinite(out).mean() > 0.9
    for name, t in best.items():
        print(f"{name}: {t:.2f} s, {a.designs / t:.0f} designs/s (× 3 currents)")
    for name, _ in runs[1:]:
        print(f"ratio network/{name} time: {best['network'] / best[name]:.2f}")


if __name__ == "__main__":
    main()
