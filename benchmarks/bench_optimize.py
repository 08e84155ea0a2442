"""Cost of the default Pareto search next to the single-objective search (issue 30: target
≤ 3×). Run from the repository root: ``python -m benchmarks.bench_optimize``. The paper
preset, the default box, drums 1–4, seed 0: ``pareto`` (NSGA-II, its defaults, on the
worst case as the CLI runs it by default, and on the nominal verdict) against
``optimize(objective="bandwidth")`` (differential evolution, its defaults), both under the
same default limits, in the same process; wall-clock and CPU time of each (the CPU time
is the steadier figure on a shared machine). The reference re-check of the members that
the CLI runs afterwards is not in either (it is timed by ``mrclutch optimize``'s output).
Set OPENBLAS_NUM_THREADS=1."""

from __future__ import annotations

import time

from mrclutch.design import design_preset
from mrclutch.optimize import optimize, pareto, robust_verdict


def timed(f):  # type: ignore[no-untyped-def]
    w, c = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    base = design_preset("paper")
    pareto(base, pop_size=8, generations=1)  # imports and first-call caches out of the way
    single, w1, c1 = timed(lambda: optimize(base))
    ps, w2, c2 = timed(lambda: pareto(base, robust=robust_verdict(base)))
    nom, w3, c3 = timed(lambda: pareto(base))
    print(f"single objective (DE):  {single.evaluations:6d} designs  {w1:7.2f} s wall  "
          f"{c1:7.2f} s CPU  (bandwidth {single.value:.2f} Hz)")  # fmt: skip
    print(f"Pareto set (NSGA-II):   {ps.evaluations:6d} designs  {w2:7.2f} s wall  "
          f"{c2:7.2f} s CPU  (front {ps.front_size}, {len(ps.members)} members)")  # fmt: skip
    print(f"  nominal verdict:      {nom.evaluations:6d} designs  {w3:7.2f} s wall  "
          f"{c3:7.2f} s CPU  (front {nom.front_size})")  # fmt: skip
    print(
        f"ratio Pareto / single:  {w2 / w1:.2f}x wall, {c2 / c1:.2f}x CPU (the default, "
        f"worst case); nominal {w3 / w1:.2f}x wall, {c3 / c1:.2f}x CPU"
    )


if __name__ == "__main__":
    main()
