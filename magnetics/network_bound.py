"""How far the reluctance network's torque can be from the FEM on ANY design inside the
measured design space: an error estimate and a bound with a stated coverage, read from the
data file `magnetics/data/network_bound.json` (written by
`python benchmarks/measure_network_bound.py` from the FEM design of experiments in
`benchmarks/data/fem_doe.json`, `benchmarks/measure_fem_doe.py`).

The design of experiments varies every section dimension the FEM sees (15 lengths and the
drum count) and the coil's ampere-turns N·I, over the ranges stored with the bound. The
inputs x are each of those 17 scaled to [0, 1] over its range (the lengths and N·I on a log
axis, x = ln(v/lo)/ln(hi/lo): the errors follow ratios of dimensions), then 11 features of
the network's own solution at that N·I (``FEATURES``, ``solution_features``: the shares
of the coil's flux in the window, the outer air, the end leaks and the sheaths, the inner
over the outer film's flux, and the flux densities of the back iron, the pole, the core,
the drum walls and the films), each as ln(v + FEATURE_FLOOR) scaled to [0, 1] over the
build designs' span and clipped to it (a derived input, not a range of the design space:
the design's own inputs say whether it is on the map). Where the network misses the FEM
is where its elements' assumptions strain (saturated steel, flux leaving the films for
the leaks and sheaths), and the solution says so better than the dimensions alone:


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
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.materials import MRF, STEEL
from geometry.params import broadcast_fields, valid
from geometry.regions import per_topology
from magnetics.network import Network, network_from_regions, solve_network

DATA_FILE = Path(__file__).parent / "data" / "network_bound.json"
#: The key of a material set: the steel of the yoke and drums, then the fluid (the
#: materials that shape the network's error; the stainless parts are μ0 in both models).
DEFAULT_MATERIALS = f"{STEEL}+{MRF}"
#: The operating input of the bound beside the design's fields: N·I [A].
AMPERE_TURNS = "ampere_turns"
#: The inputs of the bound read from the network's solution (``solution_features``).
FEATURES = (
    "window_share", "air_share", "leak_share", "sheath_share", "inner_outer",
    "b_back", "b_pole", "b_core", "b_drum", "b_film_max", "b_film_min",
)  # fmt: skip
#: v + FEATURE_FLOOR under the log: a feature that is 0 (no drum wall on one drum) stays finite.
FEATURE_FLOOR = 1e-6


def solution_features(net: Network, x: np.ndarray) -> dict[str, np.ndarray]:
    """The bound's features (``FEATURES``; each (S, C)) of the network ``net`` at its loop
    fluxes ``x`` (S, C, ``Network.unknowns``, magnetics.network.solve_network): with
    Φ = |x_{m−1} + x_w| the coil's flux (the outer film's loop and the window's), the
    window's, the outer air's, the end leaks' and the sheaths' share of Φ; the inner film's
    flux over the outer film's; and flux over section (T) in the back iron and the pole
    (Φ, the pole at its smallest radius), the core (the inner film's flux over the core's
    section in zone A), the drum walls (the largest difference of neighbouring films'
    fluxes over the wall's section in zone A; 0 on one drum) and the films (the largest and
    the smallest flux over 2π·r·L_eff in zone A, the end leak's flux taken off)."""
    m = net.m
    xa = np.abs(x)
    phi = np.abs(x[..., m - 1] + x[..., m])  # the coil's flux: outer film loop + window
    # flux density B = Φ/A of a flux tube ([roters1941] ch. 1)
    out = {
        "window_share": xa[..., m] / phi,
        "air_share": xa[..., m + 1] / phi,
        "leak_share": xa[..., net.leaks].sum(-1) / phi,
        "sheath_share": xa[..., net.sheaths].sum(-1) / phi,
        "inner_outer": xa[..., 0] / xa[..., m - 1],
        "b_back": phi * net.back_k[:, :1],
        "b_pole": phi * net.shell_k.max(-1)[:, None],
        "b_core": xa[..., 0] * net.rung_k[:, None, 0, 0, 0],
    }
    drum = np.abs(np.diff(x[..., :m], axis=-1)) * net.rung_k[:, None, 1:, 0, 0]
    out["b_drum"] = drum.max(-1) if m > 1 else np.zeros_like(phi)
    eff = net.gap_eff[..., 0]  # (S, m): zone A
    area = 2 * np.pi * 0.5 * (net.gap_r0 + net.gap_r1) * eff
    ok = (eff > 0)[:, None, :]
    film = np.abs(x[..., :m] - x[..., net.leaks][..., :1]) / np.where(ok, area[:, None], 1.0)
    out["b_film_max"] = np.where(ok, film, -np.inf).max(-1)
    out["b_film_min"] = np.where(ok, film, np.inf).min(-1)
    return out


def network_features(p: Mapping[str, Any], ampere_turns: Any) -> dict[str, np.ndarray]:
    """``solution_features`` (each (P,)) of designs ``p`` (DrumClutch fields, 1-D arrays of
    P or scalars) at N·I ``ampere_turns`` (P,): the network built and solved once per drum
    count (NaN where a design fails DrumClutch's validation)."""
    q = broadcast_fields({k: p[k] for k in p})
    ni = np.broadcast_to(np.asarray(ampere_turns, dtype=float), q["n_drums"].shape)

    def one(rg, rows):  # type: ignore[no-untyped-def]
        return solved_features(network_from_regions(rg), ni[rows])

    return per_topology(q, valid(q), one)


def solved_features(net: Network, ampere_turns: np.ndarray, flux: np.ndarray | None = None
                    ) -> dict[str, np.ndarray]:  # fmt: skip
    """``solution_features`` (each (S,)) of the network ``net`` of S designs solved at N·I
    ``ampere_turns`` (S,), one current a design; ``flux``: its loop fluxes (S, 1, ·) at
    that N·I if already solved (``solve_network``), else solved here."""
    x = solve_network(net, np.asarray(ampere_turns, dtype=float)[:, None]) if flux is None else flux
    return {k: v[:, 0] for k, v in solution_features(net, x).items()}


def material_key(steel: str = STEEL, fluid: str = MRF) -> str:
    """The data file's key of a material set (``DEFAULT_MATERIALS`` for the paper's)."""
    return f"{steel}+{fluid}"


@dataclass(frozen=True)
class NetworkBound:
    """One material set's fitted bound (module docstring): the inputs' ranges (design
    fields, SI, then AMPERE_TURNS) and which are on a log axis, the estimate's c, b, A and
    the scale's d, g on the scaled inputs, the conformal quantile q of the normalised
    score at ``coverage``, and what the check set (fresh designs never used to fit it)
    measured. ``features``: each solution feature's span (of ln(v + FEATURE_FLOOR)) over
    the build designs, the last inputs (none: the bound reads the dimensions only)."""

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
    features: Mapping[str, tuple[float, float]] = field(
        default_factory=lambda: MappingProxyType({})
    )

    def feature_columns(self, features: Mapping[str, Any]) -> np.ndarray:
        """The scaled feature inputs (P, len(self.features)) of ``features`` (each (P,),
        ``solution_features``): ln(v + FEATURE_FLOOR) over its stored span, clipped to
        [0, 1]; NaN stays NaN."""
        cols = []
        for name, (lo, hi) in self.features.items():
            v = np.log(np.abs(np.ravel(np.asarray(features[name], dtype=float))) + FEATURE_FLOOR)
            cols.append(np.clip((v - lo) / (hi - lo), 0.0, 1.0))
        return np.stack(cols, axis=1) if cols else np.zeros((0, 0))

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
        """ê at scaled inputs ``x`` (P, k). Row by row in elementwise products and sums,
        not BLAS products, so a row's value does not depend on the batch it comes in."""
        a = np.asarray(self.a)
        xt = np.ascontiguousarray(x.T)  # (k, P): each product below runs along the designs
        xa = np.zeros_like(xt)
        for i in range(xt.shape[0]):
            xa += a[i][:, None] * xt[i]  # (xᵀA)_j = Σ_i x_i A_ij, i ascending
        quad = np.ascontiguousarray((xa * xt).T).sum(axis=1)  # each row's k terms, as before
        return self.c + np.sum(x * np.asarray(self.b), axis=1) + quad

    def scale(self, x: np.ndarray) -> np.ndarray:
        """σ̂ = exp(d + g·x) > 0 at scaled inputs ``x`` (P, k): the residual's local size."""
        return np.exp(self.d + np.sum(x * np.asarray(self.g), axis=1))

    def bound(self, x: np.ndarray, estimate: np.ndarray | None = None) -> np.ndarray:
        """|ê| + q·σ̂ at scaled inputs ``x`` (P, k) (``estimate``: ê there, if computed)."""
        est = self.estimate(x) if estimate is None else estimate
        # normalised conformal interval (Lei et al., JASA 113 (2018) 1094, §5.2)
        return np.abs(est) + self.q * self.scale(x)


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
        features=MappingProxyType({k: (float(v[0]), float(v[1]))
                                   for k, v in d.get("features", {}).items()}),
    )  # fmt: skip


def measured_sets() -> tuple[str, ...]:
    """The material sets the data file holds a bound for."""
    return tuple(_data()["material_sets"])


def _shaped(v: Any, shape: tuple[int, ...]) -> np.ndarray:
    """``v`` broadcast to ``shape``; one value per design in another layout (a (1,) array
    for a scalar design) reshaped."""
    v = np.asarray(v, dtype=float)
    return v.reshape(shape) if v.size == math.prod(shape) else np.broadcast_to(v, shape)


def network_bound(
    p: Mapping[str, Any], current: Any, material_set: str = DEFAULT_MATERIALS,
    features: Mapping[str, Any] | None = None,
) -> tuple[Any, Any, tuple[str, ...]]:  # fmt: skip
    """(estimate, bound, why not) of the network's relative torque error against the FEM on
    designs ``p`` (DrumClutch fields, scalars or arrays) at ``current`` [A] (N·I =
    coil_turns × current). ``features``: the network's ``solution_features`` at that
    current, broadcastable to the result (a caller that solved the network already hands
    them over); without them the network is solved here, on the designs inside the ranges.
    Outside the measured ranges, or for a material set never measured: NaN estimate,
    infinite bound, and ``why`` names the inputs outside (or "unmeasured"); a design whose
    network has no solution features (it fails DrumClutch's validation) has a NaN estimate
    and an infinite bound too ("not a valid design")."""
    m = load(material_set)
    turns = np.asarray(p["coil_turns"], dtype=float)
    with np.errstate(over="ignore"):  # an absurd N·I is off the map, not an error
        ni = turns * np.asarray(current, dtype=float)
    shape = np.broadcast_shapes(np.shape(ni), *(np.shape(p[k]) for k in p))
    if m is None:
        est, bound = np.full(shape, np.nan), np.full(shape, np.inf)
        why: tuple[str, ...] = ("unmeasured",)
    else:
        x, inside, why = m.scaled(p, ni)
        if m.features:
            if features is None:
                rows = np.flatnonzero(inside)
                flat = {k: np.broadcast_to(np.asarray(v, float), shape).ravel()[rows]
                        for k, v in p.items()}  # fmt: skip
                got = network_features(flat, np.broadcast_to(ni, shape).ravel()[rows])
                features = {}
                for k in m.features:
                    col = np.full(inside.size, np.nan)
                    col[rows] = got[k]
                    features[k] = col.reshape(shape)
            feats = {k: _shaped(features[k], shape) for k in m.features}
            xf = m.feature_columns(feats)
            solved = np.isfinite(xf).all(axis=1)
            if not solved[inside].all():
                why = (*why, "not a valid design")
            inside &= solved
            x = np.concatenate([x, xf], axis=1)
        x0 = np.where(inside[:, None], x, 0.0)
        e = m.estimate(x0)
        est = np.where(inside, e, np.nan).reshape(shape)
        bound = np.where(inside, m.bound(x0, e), np.inf).reshape(shape)
    if not shape:
        return float(est), float(bound), why
    return est, bound, why
