"""Cost and accuracy of the torque-delay sweep column (issue 14), printed as figures.

    python benchmarks/bench_dynamics.py [N] [--no-timing]

* throughput cost: ``evaluate_batch`` of N random designs (default 20 000), and the time
  its ``torque_delay_s`` column takes (``torque_response`` on the same region tables);
  the ratio is the column's extra cost over the rest of the row (target ≤ 20 %);
* accuracy of the fast model's quadrature (3 + 3 Gauss nodes, as in the sweep) against
  64 + 64 nodes on the same designs: the largest relative error of τ_eq.

``--no-timing``: the accuracy alone (each column computed once, nothing timed): what
docs/figures.toml reads of it without the timed batches (≈ 4× the CPU).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from geometry import regions
from geometry.params import broadcast_fields, valid
from magnetics.circuit import path_from_regions
from magnetics.dynamics import torque_response
from magnetics.torque import yield_torque_and_flux
from mrclutch.design import current_limit, design_preset
from mrclutch.pipeline import evaluate_batch

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from bench_pipeline import random_fields


def _best(fn, repeat: int = 3):  # type: ignore[no-untyped-def]
    """(fastest wall time of ``repeat`` calls, the result): the machine's cores are shared."""
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(n: int, timing: bool = True) -> None:
    base = design_preset("paper")
    fields = random_fields(n)
    if timing:
        evaluate_batch(random_fields(100, seed=1), base)  # warm-up
        t_total, out = _best(lambda: evaluate_batch(fields, base))
    p = broadcast_fields(fields, base.clutch)
    ok = valid(p)
    cur = current_limit(base.operating, p["wire_diameter"])
    paths = regions.per_topology(p, ok, lambda rg, rows: {"x": np.zeros(rows.size)})  # warm
    del paths
    cache: dict[int, object] = {}
    spent = [0.0]

    def delay(nodes: int):  # type: ignore[no-untyped-def]
        def fn(rg, rows):  # type: ignore[no-untyped-def]
            path = cache.setdefault(rg.n, path_from_regions(rg))
            _, flux = yield_torque_and_flux(path, cur[rows])  # the sweep row has it already
            t0 = time.perf_counter()
            d = torque_response(
                rg,
                cur[rows],
                base.amplifier,
                base.laminations,
                path=path,
                nodes=nodes,
                flux_peak=flux[:, 0],
            ).equivalent_delay
            spent[0] += time.perf_counter() - t0
            return {"d": d}

        return fn

    fast = regions.per_topology(p, ok, delay(3))["d"]  # builds the paths (the sweep has them)
    times = []
    for _ in range(3 if timing else 0):
        spent[0] = 0.0
        fast = regions.per_topology(p, ok, delay(3))["d"]
        times.append(spent[0])
    ref = regions.per_topology(p, ok, delay(64))["d"]
    fin = np.isfinite(ref)
    err = np.max(np.abs(fast[fin] / ref[fin] - 1))
    print(f"designs: {n} ({int(ok.sum())} valid)")
    if not timing:
        print(f"τ_eq, 3+3 nodes vs 64+64: max |rel. error| = {err:.2e}")
        return
    t_col = min(times)
    print(f"evaluate_batch with the column: {t_total:.3f} s ({n / t_total:,.0f} designs/s)")
    print(f"torque_delay_s column alone:    {t_col:.3f} s")
    print(f"extra cost of the column:       {t_col / (t_total - t_col) * 100:.1f} %")
    print(f"τ_eq, 3+3 nodes vs 64+64: max |rel. error| = {err:.2e}")
    d = out["torque_delay_s"][ok]
    print(
        f"τ_eq over the designs: {np.min(d) * 1e3:.3g} … {np.max(d) * 1e3:.3g} ms, "
        f"median {np.median(d) * 1e3:.3g} ms"
    )


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--no-timing"]
    main(int(args[0]) if args else 20_000, timing="--no-timing" not in sys.argv[1:])
