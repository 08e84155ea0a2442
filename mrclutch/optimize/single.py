"""The best design for one objective on the fast path (``optimize``), with ranked
candidates for the check at reference fidelity.

Maximise an objective (``OBJECTIVES``: rendering bandwidth at K_max, rendering area, Z-width
area, or transparency — the least backdrive force in free motion) over continuous
DrumClutch dimensions for each drum count, subject to a torque floor, a mass limit, an
envelope and, by default, a closed loop that is stable and passive at the design's own
K = K_max (Eq. 4). The search is scipy's differential evolution with ``vectorized=True``:
each generation is one call of the batch evaluator (mrclutch.pipeline.evaluate_batch).
Constraints enter as a penalty proportional to the relative violation, so the search is
pushed back into the feasible set rather than blocked at its edge.

**Stability strategy.** The largest stable K is computed design by design (about ×8 the
cost of the rest of the fast path), the largest passive K on arrays (×1.7). So:

* passivity required (the default): the search penalises passivity only; then the whole
  final population is checked for stability in one batch and the best design meeting
  every limit wins. Passive at K implies stable at K on every design seen so far, so this
  almost always keeps DE's best; if no member of the final population is stable, the
  search is run again for that drum count with stability in the penalty (below).
* stability required without passivity (``--allow-active``): stability is in the
  penalty, computed only for the designs that meet every other limit.

The stability and Z-width columns are computed only where needed; the Z-width objective
(about ×7 the cost) only when it is chosen.

**Candidates.** Besides the optimum, ``Optimum.candidates`` ranks up to MAX_CANDIDATES
designs meeting every limit on the fast path (the best of each drum count, then the other
members of the final populations): the CLI re-checks them in order at reference fidelity
and reports the first that passes there (docs/optimize.md).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from geometry.validation import check_choice, check_int
from mrclutch.design import ClutchDesign
from mrclutch.optimize.box import search_box
from mrclutch.optimize.limits import Constraints, evaluate_rows

#: objective → the evaluate_batch column it reads.
OBJECTIVES = {
    "bandwidth": "bandwidth_hz",
    "area": "rendering_area_dB_decade",
    "zwidth": "zwidth_area_N2_s_per_m2",
    "transparency": "backdrive_force_N",
}
#: objectives whose column is minimised (the search maximises its negative).
MINIMISED = frozenset({"transparency"})


#: How many ranked candidates ``optimize`` keeps for a check at higher fidelity.
MAX_CANDIDATES = 8


@dataclass(frozen=True)
class Candidate:
    """A design meeting every limit on the fast path, and its objective column."""

    design: ClutchDesign
    value: float


@dataclass(frozen=True)
class Optimum:
    design: ClutchDesign
    objective: str
    value: float  # fast-path objective column at the optimum (OBJECTIVES; -inf: none)
    evaluations: int
    feasible: bool
    per_drum_count: dict[int, float]  # best feasible objective column for each drum count
    stability_searches: int = 0  # drum counts searched again with stability in the penalty
    #: the fields searched (DrumClutch lengths, m) besides n_drums
    varied: tuple[str, ...] = ()
    #: the designs to fall back on, best first (``candidates[0]`` is the optimum): the best
    #: of each drum count, then the other feasible members of the final populations
    candidates: tuple[Candidate, ...] = ()


def optimize(
    base: ClutchDesign,
    *,
    objective: str = "bandwidth",
    constraints: Constraints | None = None,
    bounds: dict[str, tuple[float, float]] | None = None,
    drum_counts: Sequence[int] = (1, 2, 3, 4),
    seed: int = 0,
    maxiter: int = 60,
    popsize: int = 24,
    robust: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> Optimum:
    """Best design on the fast path (see module docstring). ``robust``: as ``pareto``'s, a
    limit on the final populations' members that meet every other limit. ``progress``:
    called (generations done, ``maxiter`` × the drum counts) after each generation and when
    a drum count's search ends (it may end early, converged)."""
    from scipy.optimize import differential_evolution

    check_choice("objective", objective, tuple(OBJECTIVES))
    cons = (constraints if constraints is not None else Constraints()).resolved(base)
    box, _ = search_box(base, bounds)
    for n in drum_counts:
        check_int("drum_counts", n, 1, 20)
    names = list(box)
    key = OBJECTIVES[objective]
    sign = -1.0 if objective in MINIMISED else 1.0
    evaluations = 0
    generations, total = 0, maxiter * len(drum_counts)

    def reached(n: int) -> None:
        nonlocal generations
        generations = max(generations, min(n, total))
        if progress is not None:
            progress(generations, total)

    def generation_done(intermediate_result: Any) -> None:  # scipy's, after each generation
        reached(generations + 1)

    def _pop_fields(x: np.ndarray, n: int) -> dict[str, np.ndarray]:
        fields = {k: x[i] for i, k in enumerate(names)}
        fields["n_drums"] = np.full(x.shape[1], n, dtype=np.int64)
        return fields

    def results(x: np.ndarray, n: int, stability: bool = False) -> dict[str, np.ndarray]:
        nonlocal evaluations
        fields = _pop_fields(x, n)
        evaluations += x.shape[1]
        r = evaluate_rows(fields, base, cons, stability=stability, zwidth=objective == "zwidth")
        if robust is not None:
            r.update(robust.proxy(fields, base, r))
        return r  # fmt: skip

    def violation(x: np.ndarray, n: int, r: dict[str, np.ndarray], stability: bool) -> np.ndarray:
        v = cons.violation(r)
        if stability:  # the stability limit only where every other limit holds
            ok = np.nonzero(v == 0)[0]
            if ok.size:
                v[ok] = cons.violation(results(x[:, ok], n, stability=True))
        return v

    def search(n: int, stability: bool) -> np.ndarray:
        def cost(x: np.ndarray) -> np.ndarray:
            x = x if x.ndim == 2 else x[:, None]
            r = results(x, n)
            value = np.asarray(r[key], dtype=float)
            value = sign * np.where(np.isfinite(value), value, 0.0)  # unbounded: no credit
            # penalty: any violation costs more than the best objective can gain
            scale = 1e3 * (1.0 + np.abs(value).max(initial=1.0))
            return -value + scale * violation(x, n, r, stability)

        res = differential_evolution(
            cost,
            [box[k] for k in names],
            vectorized=True,
            updating="deferred",
            seed=seed,
            maxiter=maxiter,
            popsize=popsize,
            tol=1e-8,
            polish=False,
            **({} if progress is None else {"callback": generation_done}),
        )
        return res.population[np.argsort(res.population_energies)].T

    def feasible_of(pop: np.ndarray, n: int) -> tuple[list[tuple[float, np.ndarray]], bool]:
        """The members of a population meeting every limit, stability included, best first,
        and whether some member met every limit but stability."""
        r = results(pop, n, stability=cons.stable)
        v = cons.violation(r)
        if robust is not None and np.any(v == 0):
            ok = np.flatnonzero(v == 0)
            sub = {k: a[ok] for k, a in r.items()}
            sub.update(robust.full(_pop_fields(pop[:, ok], n), base, sub))
            v[ok] = cons.violation(sub)
            for k in (key, "K_N_per_m"):
                r[k][ok] = sub[k]
        value = sign * np.asarray(r[key], dtype=float)
        score = np.where((v == 0) & ~np.isnan(value), value, -np.inf)
        order = [int(j) for j in np.argsort(-score, kind="stable") if np.isfinite(score[j])]
        unstable = bool(np.any(replace(cons, stable=False).violation(r) == 0))
        return [(float(r[key][j]), pop[:, j]) for j in order], unstable

    firsts: list[tuple[float, int, np.ndarray]] = []
    rest: list[tuple[float, int, np.ndarray]] = []
    per_count: dict[int, float] = {}
    again = 0
    stability_in_search = cons.stable and not cons.passive
    for i, n in enumerate(drum_counts):
        found, rest_met = feasible_of(search(n, stability_in_search), n)
        reached((i + 1) * maxiter)
        if not found and rest_met and cons.stable and not stability_in_search:
            # members meet every other limit but none is stable: search again with
            # stability in the penalty
            again += 1
            found = feasible_of(search(n, True), n)[0]
        if not found:
            continue
        per_count[n] = found[0][0]
        firsts.append((found[0][0], n, found[0][1]))
        rest += [(val, n, x) for val, x in found[1:]]
    if not firsts:
        return Optimum(base, objective, -np.inf, evaluations, False, per_count, again,
                       tuple(names))  # fmt: skip
    ranked: list[tuple[float, int, np.ndarray]] = []
    for group in (firsts, rest):
        for val, n, x in sorted(group, key=lambda t: -sign * t[0]):
            if len(ranked) < MAX_CANDIDATES and not any(
                n == m and np.allclose(x, y, rtol=1e-6, atol=0) for _, m, y in ranked
            ):
                ranked.append((val, n, x))

    def design_of(n: int, x: np.ndarray) -> ClutchDesign:
        fields = {name: float(v) for name, v in zip(names, x, strict=True)}
        clutch = replace(base.clutch, n_drums=n, **fields)
        return replace(base, clutch=clutch, name=f"{base.name}-optimum")

    cands = tuple(Candidate(design_of(n, x), val) for val, n, x in ranked)
    return Optimum(cands[0].design, objective, cands[0].value, evaluations, True, per_count,
                   again, tuple(names), cands)  # fmt: skip
