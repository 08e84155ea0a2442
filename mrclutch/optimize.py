"""Design optimisation on the fast path, with the winner checked at reference fidelity.

Maximise the rendering bandwidth at K_max (or the rendering area) over continuous
DrumClutch dimensions for each drum count, subject to a torque floor, a mass limit, an
envelope and optionally passivity at K_max. The search is scipy's differential
evolution with ``vectorized=True``: each generation is one call of the batch evaluator
(mrclutch.pipeline.evaluate_batch), so thousands of designs cost well under a second.
Constraints enter as a penalty proportional to the relative violation, so the search
is pushed back into the feasible set rather than blocked at its edge.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from geometry.params import INTEGER_FIELDS, LENGTH_FIELDS
from geometry.validation import ParameterError, check_choice, check_int, check_positive
from mrclutch.design import ClutchDesign
from mrclutch.pipeline import evaluate_batch

OBJECTIVES = {"bandwidth": "bandwidth_hz", "area": "rendering_area_dB_decade"}

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
    passive: bool = False  # require a passive closed loop at K_max

    def __post_init__(self) -> None:
        check_positive("min_torque", self.min_torque, " N·m")
        check_positive("max_mass", self.max_mass, " kg")
        check_positive("max_diameter", self.max_diameter, " m")
        check_positive("max_length", self.max_length, " m")

    def violation(self, r: dict[str, np.ndarray]) -> np.ndarray:
        """Sum of relative violations (0 where every limit holds; inf for invalid designs)."""
        v = np.maximum(0, 1 - r["max_torque_N_m"] / self.min_torque)
        v += np.maximum(0, r["clutch_mass_kg"] / self.max_mass - 1)
        v += np.maximum(0, r["diameter_m"] / self.max_diameter - 1)
        v += np.maximum(0, r["length_m"] / self.max_length - 1)
        if self.passive:
            v += np.maximum(0, r["K_N_per_m"] / r["max_passive_K_N_per_m"] - 1)
        return np.where(r["valid"] == 1, np.nan_to_num(v, nan=np.inf), np.inf)


@dataclass(frozen=True)
class Optimum:
    design: ClutchDesign
    objective: str
    value: float  # fast-path objective at the optimum
    evaluations: int
    feasible: bool
    per_drum_count: dict[int, float]  # best feasible objective for each drum count


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
    evaluations = 0

    def results(x: np.ndarray, n: int) -> dict[str, np.ndarray]:
        nonlocal evaluations
        fields = {k: x[i] for i, k in enumerate(names)}
        fields["n_drums"] = np.full(x.shape[1], n, dtype=np.int64)
        r = evaluate_batch(fields, base, passivity=cons.passive)
        evaluations += x.shape[1]
        return r

    best: tuple[float, int, np.ndarray] | None = None
    per_count: dict[int, float] = {}
    for n in drum_counts:

        def cost(x: np.ndarray, n: int = n) -> np.ndarray:
            r = results(x if x.ndim == 2 else x[:, None], n)
            value = np.nan_to_num(r[key], nan=0.0)
            # penalty: any violation costs more than the best objective can gain
            return -value + 1e3 * (1.0 + np.abs(value).max(initial=1.0)) * cons.violation(r)

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
        r = results(res.x[:, None], n)
        feasible = bool(cons.violation(r)[0] == 0)
        value = float(r[key][0])
        if feasible:
            per_count[n] = value
        score = value if feasible else -np.inf
        if best is None or score > best[0]:
            best = (score, n, res.x)
    assert best is not None
    score, n, x = best
    clutch = replace(base.clutch, n_drums=n, **{k: float(v) for k, v in zip(names, x, strict=True)})
    design = replace(base, clutch=clutch, name=f"{base.name}-optimum")
    return Optimum(design, objective, float(score), evaluations, np.isfinite(score), per_count)


def parse_bounds(specs: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``NAME_mm=LO:HI`` strings (CLI) into SI bounds."""
    out: dict[str, tuple[float, float]] = {}
    for s in specs:
        name, _, rng = s.partition("=")
        lo, _, hi = rng.partition(":")
        if not name.endswith("_mm") or name[:-3] not in LENGTH_FIELDS or name in INTEGER_FIELDS:
            raise ParameterError(f"--vary {s!r}: give NAME_mm=LO:HI with a DrumClutch length")
        try:
            out[name[:-3]] = (float(lo) * 1e-3, float(hi) * 1e-3)
        except ValueError:
            raise ParameterError(f"--vary {s!r}: LO and HI must be numbers (mm)") from None
    return out
