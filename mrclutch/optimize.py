"""Design optimisation on the fast path, with the winner checked at reference fidelity.

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

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from geometry.params import INTEGER_FIELDS, LENGTH_FIELDS
from geometry.validation import ParameterError, check_choice, check_int, check_positive
from mrclutch.design import ClutchDesign
from mrclutch.pipeline import evaluate_batch

#: objective → the evaluate_batch column it reads.
OBJECTIVES = {
    "bandwidth": "bandwidth_hz",
    "area": "rendering_area_dB_decade",
    "zwidth": "zwidth_area_N2_s_per_m2",
    "transparency": "backdrive_force_N",
}
#: objectives whose column is minimised (the search maximises its negative).
MINIMISED = frozenset({"transparency"})

#: Default search box (m): what a drum clutch of the paper's size can vary.
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "gap": (0.2e-3, 1.0e-3),
    "drum_thickness": (0.1e-3, 0.6e-3),
    "drum_inner_diameter": (6e-3, 18e-3),
    "zone_length": (3e-3, 9e-3),
}


@dataclass(frozen=True)
class Constraints:
    """Limits the optimum must meet (SI)."""

    min_torque: float = 0.4  # N·m, Table 1's rated torque
    max_mass: float = 0.100  # kg, whole clutch
    max_diameter: float = 0.030  # m, Table 1 envelope
    max_length: float = 0.040  # m
    passive: bool = True  # a passive closed loop at K = K_max (Eq. 4)
    stable: bool = True  # a stable free closed loop at K = K_max

    def __post_init__(self) -> None:
        check_positive("min_torque", self.min_torque, " N·m")
        check_positive("max_mass", self.max_mass, " kg")
        check_positive("max_diameter", self.max_diameter, " m")
        check_positive("max_length", self.max_length, " m")
        for name in ("passive", "stable"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"{name} = {getattr(self, name)!r}: must be True or False")

    def violation(self, r: Mapping[str, np.ndarray]) -> np.ndarray:
        """Sum of relative violations (0 where every limit holds; inf for invalid designs).
        Passivity needs the ``max_passive_K_N_per_m`` column; stability is checked where
        ``max_stable_K_N_per_m`` is present (the search may leave it out: module docstring).
        """
        v = np.maximum(0, 1 - r["max_torque_N_m"] / self.min_torque)
        v += np.maximum(0, r["clutch_mass_kg"] / self.max_mass - 1)
        v += np.maximum(0, r["diameter_m"] / self.max_diameter - 1)
        v += np.maximum(0, r["length_m"] / self.max_length - 1)
        if self.passive:
            v += np.maximum(0, r["K_N_per_m"] / r["max_passive_K_N_per_m"] - 1)
        if self.stable and "max_stable_K_N_per_m" in r:
            # stable for K below the first destabilising crossing (model.max_stable_stiffness)
            v += np.maximum(0, r["K_N_per_m"] / r["max_stable_K_N_per_m"] - (1 - 1e-9))
        return np.where(r["valid"] == 1, np.nan_to_num(v, nan=np.inf), np.inf)


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
) -> Optimum:
    """Best design on the fast path (see module docstring)."""
    from scipy.optimize import differential_evolution

    check_choice("objective", objective, tuple(OBJECTIVES))
    cons = constraints if constraints is not None else Constraints()
    box = dict(DEFAULT_BOUNDS if bounds is None else bounds)
    for name, (lo, hi) in box.items():
        if name not in LENGTH_FIELDS:
            raise ParameterError(f"bounds: {name}: not a DrumClutch length")
        if not 0 < lo < hi:
            raise ParameterError(f"bounds: {name} = [{lo}, {hi}]: need 0 < min < max")
    for n in drum_counts:
        check_int("drum_counts", n, 1, 20)
    names = list(box)
    key = OBJECTIVES[objective]
    sign = -1.0 if objective in MINIMISED else 1.0
    evaluations = 0

    def results(x: np.ndarray, n: int, stability: bool = False) -> dict[str, np.ndarray]:
        nonlocal evaluations
        fields = {k: x[i] for i, k in enumerate(names)}
        fields["n_drums"] = np.full(x.shape[1], n, dtype=np.int64)
        evaluations += x.shape[1]
        return evaluate_batch(
            fields,
            base,
            passivity=cons.passive,
            stability=stability,
            zwidth=objective == "zwidth",
        )

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
        )
        return res.population[np.argsort(res.population_energies)].T

    def feasible_of(pop: np.ndarray, n: int) -> tuple[list[tuple[float, np.ndarray]], bool]:
        """The members of a population meeting every limit, stability included, best first,
        and whether some member met every limit but stability."""
        r = results(pop, n, stability=cons.stable)
        v = cons.violation(r)
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
    for n in drum_counts:
        found, rest_met = feasible_of(search(n, stability_in_search), n)
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


def parse_bounds(specs: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``NAME_mm=LO:HI`` strings (CLI) into SI bounds."""
    out: dict[str, tuple[float, float]] = {}
    for s in specs:
        name, _, rng = s.partition("=")
        lo, _, hi = rng.partition(":")
        if not name.endswith("_mm") or name[:-3] not in LENGTH_FIELDS or name in INTEGER_FIELDS:
            raise ParameterError(f"--vary {s!r}: give NAME_mm=LO:HI with a DrumClutch length")
        try:
            a, b = float(lo), float(hi)
        except ValueError:
            raise ParameterError(f"--vary {s!r}: LO and HI must be numbers (mm)") from None
        if not (math.isfinite(a) and math.isfinite(b) and 0 < a < b):
            raise ParameterError(f"--vary {s!r}: need finite 0 < LO < HI (mm)")
        out[name[:-3]] = (a * 1e-3, b * 1e-3)
    return out
