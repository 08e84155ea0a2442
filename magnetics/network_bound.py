"""How far the reluctance network's torque can be from the FEM on ANY design inside the
measured design space: an error estimate and a bound with a stated coverage, read from the
data file `magnetics/data/network_bound.json` (written by
`python benchmarks/measure_network_bound.py` from the FEM design of experiments in
`benchmarks/data/fem_doe.json`, `benchmarks/measure_fem_doe.py`).

The design of experiments varies every section dimension the FEM sees (15 lengths and the
drum count) and the coil's ampere-turns N·I, over the ranges stored with the bound. On
x = each of those 17 inputs scaled to [0, 1] over its range (the lengths and N·I on a log
axis, x = ln(v/lo)/ln(hi/lo): the errors follow ratios of dimensions):

* estimate ê(x) = c + b·x + xᵀAx, the signed network/FEM − 1 (a ridge-regularised
  quadratic, least squares on the build designs);
* scale σ̂(x) = exp(d + g·x) > 0, how large the residual e − ê tends to be there (a ridge
  fit of ln(|e − ê| + δ) on the same scaled inputs, the residuals out of fold);
* bound |ê(x)| + q·σ̂(x): normalised (locally weighted) conformal prediction (Papadopoulos
  et al., J. Artif. Intell. Res. 40 (2011) 815; Lei et al., JASA 113 (2018) 1094, §5.2).
  q is the cross-conformal quantile at the stated coverage of the score (|e| − |ê|)/σ̂ over
  the build designs, each scored by an ê and a σ̂ fitted without its fold (Vovk, Ann. Math.
  Artif. Intell. 74 (2015) 9, cross-conformal predictors; Barber et al., Ann. Statist. 49
  (2021) 486, CV+: with exchangeable designs the coverage is ≥ 1 − 2α in theory, ≈ 1 − α
  in practice). The fresh check designs stored with it measure what it covers. The form
  (estimate, scale, their ridge weights, δ) was chosen by cross-validation on the build
  designs alone (``measure_network_bound.py --compare``); the check designs were looked at
  in the previous round (a constant-q bound, |ê| + q), so they are fresh to this form's
  fit but not to its authors.

A design with any input outside its range is off the map: NaN estimate, infinite bound,
the fields named. A material set without measurements is "unmeasured" (the same), never
given another set's bound. Fields the FEM does not see (the hub holes, the wire, which
acts only through N·I) are not inputs.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.materials import MRF, STEEL

DATA_FILE = Path(__file__).parent / "data" / "network_bound.json"
#: The key of a material set: the steel of the yoke and drums, then the fluid (the
#: materials that shape the network's error; the stainless parts are μ0 in both models).
DEFAULT_MATERIALS = f"{STEEL}+{MRF}"
#: The operating input of the bound beside the design's fields: N·I [A].
AMPERE_TURNS = "ampere_turns"


def material_key(steel: str = STEEL, fluid: str = MRF) -> str:
    """The data file's key of a material set (``DEFAULT_MATERIALS`` for the paper's)."""
    return f"{steel}+{fluid}"


@dataclass(frozen=True)
class NetworkBound:
    """One material set's fitted bound (module docstring): the inputs' ranges (design
    fields, SI, then AMPERE_TURNS) and which are on a log axis, the estimate's c, b, A and
    the scale's d, g on the scaled inputs, the conformal quantile q of the normalised
    score at ``coverage``, and what the check set (fresh designs never used to fit it)
    measured."""

    material_set: str
    ranges: Mapping[str, tuple[float, float]]
    log_scaled: tuple[str, ...]
    c: float
    b: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]
    d: float
    g: tuple[float, ...]
    q: float
    coverage: float
    check: Mapping[str, float]

    def scaled(
        self, p: Mapping[str, Any], ampere_turns: Any
    ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
        """(x (P, k) in [0, 1] where inside, inside (P,), names of the inputs outside
        their range somewhere) of designs ``p`` (fields, scalars or arrays) at N·I."""
        cols = [np.asarray(p[k], dtype=float) for k in self.ranges if k != AMPERE_TURNS]
        cols.append(np.asarray(ampere_turns, dtype=float))
        cols = [c.ravel() for c in np.broadcast_arrays(*cols)]
        x = np.empty((cols[0].size, len(cols)))
        inside = np.ones(cols[0].size, bool)
        outside = []
        for j, (name, (lo, hi)) in enumerate(self.ranges.items()):
            v = cols[j]
            tol = 1e-9 * (hi - lo)
            ok = (v >= lo - tol) & (v <= hi + tol)  # NaN is outside
            if not ok.all():
                outside.append(name)
            inside &= ok
            if name in self.log_scaled:
                # (overflow: a value near the float limit, off the map whatever x is)
                with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                    x[:, j] = np.log(v / lo) / np.log(hi / lo)
            else:
                x[:, j] = (v - lo) / (hi - lo)
        return x, inside, tuple(outside)

    def estimate(self, x: np.ndarray) -> np.ndarray:
        """ê at scaled inputs ``x`` (P, k)."""
        a = np.asarray(self.a)
        return self.c + x @ np.asarray(self.b) + np.sum((x @ a) * x, axis=1)

    def scale(self, x: np.ndarray) -> np.ndarray:
        """σ̂ = exp(d + g·x) > 0 at scaled inputs ``x`` (P, k): the residual's local size."""
        return np.exp(self.d + x @ np.asarray(self.g))

    def bound(self, x: np.ndarray) -> np.ndarray:
        """|ê| + q·σ̂ at scaled inputs ``x`` (P, k)."""
        # normalised conformal interval (Lei et al., JASA 113 (2018) 1094, §5.2)
        return np.abs(self.estimate(x)) + self.q * self.scale(x)


@functools.lru_cache(maxsize=1)
def _data() -> Mapping[str, Any]:
    return MappingProxyType(json.loads(DATA_FILE.read_text()))


@functools.lru_cache(maxsize=8)
def load(material_set: str = DEFAULT_MATERIALS) -> NetworkBound | None:
    """The bound measured for ``material_set``, or None if that set was never measured."""
    sets = _data()["material_sets"]
    if material_set not in sets:
        return None
    d = sets[material_set]
    return NetworkBound(
        material_set=material_set,
        ranges=MappingProxyType({k: (float(v[0]), float(v[1])) for k, v in d["ranges"].items()}),
        log_scaled=tuple(d["log_scaled"]),
        c=float(d["estimate"]["c"]),
        b=tuple(map(float, d["estimate"]["b"])),
        a=tuple(tuple(map(float, r)) for r in d["estimate"]["a"]),
        d=float(d["scale"]["d"]),
        g=tuple(map(float, d["scale"]["g"])),
        q=float(d["q"]),
        coverage=float(d["coverage"]),
        check=MappingProxyType({k: float(v) for k, v in d["check"].items()}),
    )


def measured_sets() -> tuple[str, ...]:
    """The material sets the data file holds a bound for."""
    return tuple(_data()["material_sets"])


def network_bound(
    p: Mapping[str, Any], current: Any, material_set: str = DEFAULT_MATERIALS
) -> tuple[Any, Any, tuple[str, ...]]:
    """(estimate, bound, why not) of the network's relative torque error against the FEM on
    designs ``p`` (DrumClutch fields, scalars or arrays) at ``current`` [A] (N·I =
    coil_turns × current). Outside the measured ranges, or for a material set never
    measured: NaN estimate, infinite bound, and ``why`` names the inputs outside (or
    "unmeasured")."""
    m = load(material_set)
    turns = np.asarray(p["coil_turns"], dtype=float)
    ni = turns * np.asarray(current, dtype=float)
    shape = np.broadcast_shapes(np.shape(ni), *(np.shape(p[k]) for k in p))
    if m is None:
        est, bound = np.full(shape, np.nan), np.full(shape, np.inf)
        why: tuple[str, ...] = ("unmeasured",)
    else:
        x, inside, why = m.scaled(p, ni)
        x0 = np.where(inside[:, None], x, 0.0)
        est = np.where(inside, m.estimate(x0), np.nan).reshape(shape)
        bound = np.where(inside, m.bound(x0), np.inf).reshape(shape)
    if not shape:
        return float(est), float(bound), why
    return est, bound, why
