"""Cost of the default Pareto search next to the single-objective search (issue 30: target
≤ 3×). Run from the repository root: ``python -m benchmarks.bench_optimize``. The paper
preset, the default box, drums 1–4, seed 0: ``pareto`` (NSGA-II, its defaults, on the
worst case as the CLI runs it by default, and on the nominal verdict) against
``optimize(objective="bandwidth")`` (differential evolution, its defaults), both under the
same default limits, in the same process; wall-clock and CPU time of each (the CPU time
is the steadier figure on a shared machine). The reference re-check of the members that
the CLI runs afterwards is not in either (it is timed by ``mrclutch optimize``'s output).
Set OPENBLAS_NUM_THREADS=1.

``--hypervolume`` (issue 40): the default Pareto search's population × generations against
others of about the same 10⁴ designs (and 100 × 50, half of them), each on seeds 0–2 on the
worst case as the CLI runs it: CPU seconds, front size and the hypervolume of the front
(pymoo's, over the four objectives scaled to [0, 1] by the union of every run's fronts,
reference point 1.1 in each), and each hypervolume over the old default's (100 × 100) on
its seed. The default (``pareto.DEFAULT_POP_SIZE`` × ``DEFAULT_GENERATIONS``) was chosen
on it: 200 × 50 the fewest CPU seconds of those whose hypervolume matched 100 × 100's on
every seed (100 × 50 fell short on each)."""

from __future__ import annotations

import argparse
import functools
import time

import numpy as np

from mrclutch.design import design_preset
from mrclutch.optimize import (
    DEFAULT_GENERATIONS,
    DEFAULT_POP_SIZE,
    optimize,
    pareto,
    robust_verdict,
)

#: (population, generations) compared by ``--hypervolume``; the first is the reference.
SHAPES = ((100, 100), (DEFAULT_POP_SIZE, DEFAULT_GENERATIONS), (400, 25), (100, 50))


def timed(f):  # type: ignore[no-untyped-def]
    w, c = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - c


def hypervolumes(seeds: tuple[int, ...] = (0, 1, 2)) -> None:
    """``--hypervolume``: the table of the module docstring."""
    from pymoo.indicators.hv import HV

    base = design_preset("paper")
    wc = robust_verdict(base)
    pareto(base, pop_size=8, generations=1)  # imports and first-call caches out of the way
    runs = {}
    for seed in seeds:
        for pop, gens in dict.fromkeys(SHAPES):
            run = functools.partial(pareto, base, robust=wc, seed=seed, pop_size=pop,
                                    generations=gens)  # fmt: skip
            ps, _, cpu = timed(run)
            f = np.stack([-sense * ps.front[col] for _, col, sense in ps.objectives], -1)
            runs[seed, pop, gens] = (f, cpu, ps.front_size)
    every = np.concatenate([f for f, _, _ in runs.values()])
    lo, span = every.min(0), np.ptp(every, 0)
    hv = HV(ref_point=np.full(every.shape[1], 1.1))
    print(f"{'seed':>4} {'pop':>4} {'gens':>4} {'CPU s':>7} {'front':>6} {'hypervolume':>11} "
          f"{'/ 100x100':>9}")  # fmt: skip
    for (seed, pop, gens), (f, cpu, size) in runs.items():
        h = float(hv((f - lo) / np.where(span > 0, span, 1.0)))
        runs[seed, pop, gens] = (f, cpu, h)
        ref = runs[(seed, *SHAPES[0])][2]
        print(f"{seed:4d} {pop:4d} {gens:4d} {cpu:7.1f} {size:6d} {h:11.5f} {h / ref:9.4f}")


def main() -> None:
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_optimize")
    p.add_argument("--hypervolume", action="store_true",
                   help="compare population x generations on seeds 0-2 (docstring)")  # fmt: skip
    if p.parse_args().hypervolume:
        hypervolumes()
        return
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
