"""Verdicts that hold over what we do not know (docs/verdicts.md).

The uncertain inputs of a design (:class:`mrclutch.uncertainty.Uncertainty`: viscosity,
fluid temperature, gap and drum tolerances, runout, delay, bench damping, yield-stress and
B–H lot spreads) become, per design, a box of the haptic model's parameters at the hand:
m1 ∈ [m1⁻, m1⁺], b1 ∈ [b1⁻, b1⁺], τ ∈ [τ⁻, τ⁺] and the rendered K_max = F_max/d ∈ [K⁻, K⁺]
(:func:`hand_box_batch`). Each verdict is then reported nominal, worst and best over the
box:

* largest passive K — *corners*: non-increasing in m1, increasing in b1, decreasing in τ
  (tested by hypothesis in tests/mrclutch/test_robust.py), so the worst is at (m1⁺, b1⁻, τ⁺)
  and the best at (m1⁻, b1⁺, τ⁻);
* largest stable K — monotone in none of m1, b1, τ (a heavier m1 can stabilise; where
  the transmission's own damping b is light, more b1 can destabilise: tested
  counter-examples), so a *bounded global search* over (m1, b1, τ) (:func:`box_search`:
  a 3 × 3 × 3 grid of the box, then grids half as wide on the best point, five times for
  the worst case), each point by :func:`stable_stiffness_batch` (the
  D-subdivision of ``haptics.model`` on arrays of designs, equal to
  ``max_stable_stiffness`` to 1e-9: tested);
* bandwidth at the rendered K_max — monotone in none of m1, b1, τ, K (tests show
  counter-examples for each): the same search over all four.

The searches are checked against 1000 random samples of the ranges of 200 random designs
(the reported worst is never above the sampled one, and within 2 % of it).
The box is conservative: its edges are the hull of what the inputs give, so the worst
case over the box is never above the worst over the inputs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.materials import SLOTS, MaterialChoice
from geometry.numerics import illinois
from magnetics.drag import drag_terms, totals
from magnetics.torque import torque_curve
from mrclutch.design import ClutchDesign
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import (
    _num_coeffs,
    bandwidth,
    max_passive_stiffness,
    max_stable_stiffness,
    rendering_area,
)
from mrclutch.haptics.zwidth import zwidth as zwidth_of
from mrclutch.pipeline import BatchEvaluator, batch_fields, evaluate_batch, mr_at_hand
from mrclutch.uncertainty import Uncertainty, default_uncertainty

TWO_PI = 2.0 * math.pi
#: Points of the log grid over [1e-4 ω_a, ω_end] in the vectorised crossing search.
_LOG_POINTS = 300
#: Phase step (rad) of the linear grid against the delay, ωτ per point.
_PHASE_STEP = 0.25
#: Most linear points a batch may take before designs go to the exact kernel one by one.
_MAX_LINEAR = 4000


def stable_stiffness_batch(p: HapticParams) -> np.ndarray:
    """``haptics.model.max_stable_stiffness`` of each design of a 1-D vectorised set, in one
    vectorised pass: the smallest gain K_c = Re X(ω_c) over the imaginary-axis crossings of
    the free loop, X(ω) = −jω Num(jω) e^{jωτ}/(k + jbω) real and positive (D-subdivision,
    ``haptics.model``'s docstring). For K → 0⁺ every root is in the left half-plane, so the
    first crossing met as K grows is destabilising: the stability limit is min K_c.

    Crossings are the sign changes of Im X on a grid of each design (log-spaced over
    [1e-4 ω_a, ω_end], ω_a the largest |zero| of Num, ω_end = max(4 ω_a, 4/τ), merged with a
    linear grid of step 0.25/τ), refined by Illinois regula falsi. Where the bound
    |X(ω_end)| (increasing beyond ω_a) does not exceed the smallest K_c found, where no
    crossing is found, or where a sample-and-hold is modelled, the design is handed to the
    exact kernel. Returns inf where no crossing destabilises."""
    shape = p.shape
    f = {n: np.ravel(np.broadcast_to(np.asarray(getattr(p, n), float), shape))
         for n in ("m1", "b1", "k", "b", "m2", "delay", "sample_period")}  # fmt: skip
    n = f["m1"].size
    out = np.full(n, np.nan)
    if n == 0:
        return out.reshape(shape)
    a3, a2, a1, a0 = (np.ravel(np.broadcast_to(c, shape)) for c in _num_coeffs(p))
    # largest |zero| of Num: companion matrices of the monic cubic, batched
    comp = np.zeros((n, 3, 3))
    comp[:, 0, :] = -np.stack([a2 / a3, a1 / a3, a0 / a3], axis=1)
    comp[:, 1, 0] = comp[:, 2, 1] = 1.0
    w_a = np.max(np.abs(np.linalg.eigvals(comp)), axis=1)
    tau, k, b = f["delay"], f["k"], f["b"]
    exact = (f["sample_period"] > 0) | (tau <= 0)
    with np.errstate(divide="ignore"):
        w_end = np.maximum(4.0 * w_a, np.where(tau > 0, 4.0 / tau, 0.0))
    n_lin = np.ceil(w_end * tau / _PHASE_STEP) + 2
    exact |= n_lin > _MAX_LINEAR
    rows = np.nonzero(~exact)[0]
    rows = rows[np.argsort(n_lin[rows], kind="stable")]  # chunks of like grid sizes
    if rows.size:
        c = [x[rows] for x in (a3, a2, a1, a0, k, b, tau)]

        def X(sel: np.ndarray, ww: np.ndarray) -> np.ndarray:
            c3, c2, c1, c0, kk, bb, tt = (x[sel] for x in c)
            if ww.ndim == 2:
                c3, c2, c1, c0, kk, bb, tt = (x[:, None] for x in (c3, c2, c1, c0, kk, bb, tt))
            s = 1j * ww
            num = ((c3 * s + c2) * s + c1) * s + c0
            return -s * num * np.exp(1j * ww * tt) / (kk + bb * s)

        def im_x(sel: np.ndarray, ww: np.ndarray) -> np.ndarray:
            """Im X·|k + jbω|² in real arithmetic: −jω Num(jω) = P + jQ, times (k − jbω)
            = Gr + jGi, times e^{jωτ}."""
            c3, c2, c1, c0, kk, bb, tt = (x[sel] for x in c)
            if ww.ndim == 2:
                c3, c2, c1, c0, kk, bb, tt = (x[:, None] for x in (c3, c2, c1, c0, kk, bb, tt))
            w2 = ww * ww
            P = (c1 - c3 * w2) * w2
            Q = (c2 * w2 - c0) * ww
            bw = bb * ww
            th = ww * tt
            return (P * kk + Q * bw) * np.sin(th) + (Q * kk - P * bw) * np.cos(th)

        best = np.full(rows.size, np.inf)
        t = np.linspace(0.0, 1.0, _LOG_POINTS)
        for a in range(0, rows.size, 256):
            sl = np.arange(a, min(a + 256, rows.size))
            r = rows[sl]
            m = int(np.max(n_lin[r]))
            lo, hi = np.log(1e-4 * w_a[r]), np.log(w_end[r])
            w_log = np.exp(lo[:, None] + (hi - lo)[:, None] * t)
            w_lin = w_end[r, None] * np.linspace(0.0, 1.0, m)[1:]  # step ≤ 0.25/τ
            w = np.sort(np.concatenate([w_log, w_lin], axis=1), axis=1)
            im = im_x(sl, w)
            d, j = np.nonzero(np.sign(im[:, :-1]) * np.sign(im[:, 1:]) < 0)
            if d.size == 0:
                continue
            g = sl[d]
            root = illinois(lambda act, x, g=g: im_x(g[act], x), w[d, j], w[d, j + 1],
                            im[d, j], im[d, j + 1], 1e-12)  # fmt: skip
            xr = X(g, root)
            ok = (xr.real > 0) & (np.abs(xr.imag) <= 1e-6 * np.abs(xr))
            np.minimum.at(best, g[ok], xr.real[ok])
        # beyond ω_end, |X| ≥ ω|Num(jω)|/|k + jbω| rises: no smaller K_c once it exceeds best
        s_end = 1j * w_end[rows]
        c3, c2, c1, c0 = (x[rows] for x in (a3, a2, a1, a0))
        bound = np.abs(s_end * (((c3 * s_end + c2) * s_end + c1) * s_end + c0)) / np.abs(
            k[rows] + b[rows] * s_end
        )
        done = np.isfinite(best) & (bound > best)
        out[rows[done]] = best[done]
        exact[rows[~done]] = True
    for i in np.nonzero(exact)[0]:
        out[i] = max_stable_stiffness(
            HapticParams(
                *(f[x][i] for x in ("m1", "b1", "k", "b", "m2")),
                delay=f["delay"][i],
                sample_period=f["sample_period"][i],
            )
        )
    return out.reshape(shape)


# ---- a bounded search over a box, vectorised over designs ------------------------------


def box_search(
    fn: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    sense: int = -1,
    points: int = 5,
    zooms: int = 3,
) -> tuple[np.ndarray, np.ndarray]:
    """The smallest (``sense`` −1) or largest (+1) of ``fn`` over the box [lo, hi] of each
    design (lo, hi: (N, d)): a grid of ``points``^d (corners included), then ``zooms``
    grids of the same size centred on the best point so far, each half as wide (5 points:
    the two cells beside it; 3 points: half a cell each side), within the box. ``fn(x)``
    takes points x of shape (N, M, d) and returns (N, M); NaN counts as no value.
    Returns (value (N,), argument (N, d))."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    n, d = lo.shape
    t = np.linspace(0.0, 1.0, points)
    unit = np.stack(np.meshgrid(*([t] * d), indexing="ij"), axis=-1).reshape(-1, d)  # (M, d)
    best = np.full(n, np.inf)
    seen = np.zeros(n, dtype=bool)
    arg = 0.5 * (lo + hi)
    a, b = lo.copy(), hi.copy()
    for _ in range(zooms + 1):
        x = a[:, None, :] + (b - a)[:, None, :] * unit[None]
        v = -sense * np.asarray(fn(x), dtype=float)  # the smallest of −sense·fn
        seen |= ~np.all(np.isnan(v), axis=1)
        v = np.where(np.isnan(v), np.inf, v)
        j = np.argmin(v, axis=1)
        vj = v[np.arange(n), j]
        better = vj < best
        best = np.where(better, vj, best)
        arg = np.where(better[:, None], x[np.arange(n), j], arg)
        half = (b - a) / 4  # (points − 1)/4 cells: each zoom halves the cell
        a, b = np.maximum(arg - half, lo), np.minimum(arg + half, hi)
    return np.where(seen, -sense * best, np.nan), arg


# ---- from the uncertain inputs to a box of the haptic parameters -----------------------


@dataclass(frozen=True)
class HandBox:
    """Per design (1-D arrays of S), the haptic parameters at the hand: nominal and the
    (low, high) hull over the uncertain inputs. ``K`` is the rendered K_max = F_max/d
    (Eq. 4); ``k``, ``b``, ``m2`` (the transmission) are certain."""

    m1: tuple[np.ndarray, np.ndarray, np.ndarray]  # (nominal, low, high) kg
    b1: tuple[np.ndarray, np.ndarray, np.ndarray]  # N·s/m
    delay: tuple[np.ndarray, np.ndarray, np.ndarray]  # s
    K: tuple[np.ndarray, np.ndarray, np.ndarray]  # N/m
    k: np.ndarray
    b: np.ndarray
    m2: np.ndarray
    valid: np.ndarray  # bool

    def params(self, m1: Any, b1: Any, delay: Any) -> HapticParams:
        """HapticParams at these values (arrays broadcasting against (S, …) rows)."""
        extra = np.ndim(m1) - 1
        sh = (-1,) + (1,) * max(extra, 0)
        return HapticParams(m1, b1, self.k.reshape(sh), self.b.reshape(sh),
                            self.m2.reshape(sh), delay=delay)  # fmt: skip

    @property
    def nominal(self) -> HapticParams:
        return self.params(self.m1[0], self.b1[0], self.delay[0])


def _hand_of(rows: Mapping[str, np.ndarray], base: Any) -> tuple[np.ndarray, ...]:
    """(m1, b1, f_max, τ_eq, valid) at the hand of evaluate_batch's rows (``mr_at_hand``)."""
    ok = rows["valid"] > 0
    out = [np.full(ok.shape, np.nan) for _ in range(4)]
    if ok.any():
        inertia = rows["rotor_inertia_kg_m2"][ok] + rows["fluid_inertia_kg_m2"][ok]
        hp = mr_at_hand(base, inertia, rows["drag_damping_N_m_s"][ok], rows["max_torque_N_m"][ok],
                        rows["clutch_mass_kg"][ok], rows["torque_delay_s"][ok])  # fmt: skip
        for o, v in zip(out, (hp.m1, hp.b1, hp.f_max, rows["torque_delay_s"][ok]), strict=True):
            o[ok] = np.broadcast_to(v, (int(ok.sum()),))
    return (*out, ok)


def _temperature_factors(p: Mapping[str, np.ndarray], ok: np.ndarray, base: Any,
                         temps: tuple[float, float],
                         mats: MaterialChoice | np.ndarray | None = None,
                         ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(low, high) of the drag damping over the fluid temperature range, relative to its
    value at the operating temperature (η(T) monotone: the range's ends bound it);
    ``mats``: the rows' materials (None: the base design's)."""
    op = base.operating

    def fn(rg: Any, rows: np.ndarray) -> dict[str, Any]:
        d = [totals(drag_terms(rg, op.input_speed, t, base.support))[1]
             for t in (op.fluid_temperature, *temps)]  # fmt: skip
        return {"lo": d[1] / d[0], "hi": d[2] / d[0]}

    f = regions.per_topology(p, ok, fn, base.materials if mats is None else mats)
    return np.fmin(f["lo"], f["hi"]), np.fmax(f["lo"], f["hi"])


def hand_box_batch(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign | None = None,
    uncertainty: Uncertainty | None = None,
    nominal: Mapping[str, np.ndarray] | None = None,
) -> HandBox:
    """The :class:`HandBox` of S designs (the field arrays ``evaluate_batch`` takes) over
    ``uncertainty`` (None: ``default_uncertainty(base)``).

    * geometry: the fast path (``evaluate_batch``) at the four corners of gap ± tolerance
      × drum thickness ± tolerance besides the nominal; m1, b1, F_max and τ_eq take the
      hull of the five (interior points lie inside it: tested);
    * b1 × (1 ± viscosity spread) × the drag's range over the fluid temperatures
      (``_temperature_factors``); its top × g/√(g² − e²) for a runout e (the mean of
      1/(g − e cos θ) around the drum: (1/2π)∫dθ/(g − e cos θ) = 1/√(g² − e²), by residues),
      then + bench damping;
    * τ: the declared range, or the typed delay to the geometry's τ_eq (all corners);
    * K = F_max/d × the torque factor (yield stress and B–H lot spreads).

    ``nominal``: ``evaluate_batch(fields, base)``'s rows if already computed."""
    base = base if base is not None else ClutchDesign()
    unc = uncertainty if uncertainty is not None else default_uncertainty(base)
    p, mats = batch_fields(fields, base)  # a material column: per row (issue 45)
    names = {}  # the material columns, one name a row, for the corners' fast-path runs
    if not isinstance(mats, MaterialChoice):
        names = {k: np.array([getattr(m, k) for m in mats], object) for k in SLOTS if k in fields}
    rows0 = nominal if nominal is not None else evaluate_batch({**p, **names}, base)
    m1_0, b1_0, f_0, teq_0, ok = _hand_of(rows0, base)
    stack = [x[None] for x in (m1_0, b1_0, f_0, teq_0)]
    if unc.gap_tolerance > 0 or unc.drum_thickness_tolerance > 0:
        # the four corners as one batch of 4 S designs (one fast-path call, not four)
        corners = [
            (dg, dt)
            for dg in (-unc.gap_tolerance, unc.gap_tolerance)
            for dt in (-unc.drum_thickness_tolerance, unc.drum_thickness_tolerance)
        ]
        q = {k: np.tile(v, 4) for k, v in {**p, **names}.items()}
        q["gap"] = np.concatenate([p["gap"] + dg for dg, _ in corners])
        q["drum_thickness"] = np.concatenate([p["drum_thickness"] + dt for _, dt in corners])
        hand = _hand_of(evaluate_batch(q, base), base)[:4]
        stack = [np.concatenate([s, c.reshape(4, -1)]) for s, c in zip(stack, hand, strict=True)]
    # hull over the corners; a corner the validation refuses (NaN) is left out
    (m1_lo, b1_lo, f_lo, teq_lo), (m1_hi, b1_hi, f_hi, teq_hi) = (
        [np.where(ok, fn.reduce(s, axis=0), np.nan) for s in stack] for fn in (np.fmin, np.fmax)
    )
    op = base.operating
    t_lo, t_hi = unc.fluid_temperature if unc.fluid_temperature is not None else (
        op.fluid_temperature, op.fluid_temperature)  # fmt: skip
    ft_lo, ft_hi = _temperature_factors(p, ok, base, (t_lo, t_hi), mats)
    g = p["gap"]
    runout = g / np.sqrt(np.maximum(g * g - unc.runout**2, 1e-30))  # e < g: the drums clear
    b1_lo = b1_lo * (1 - unc.viscosity_spread) * ft_lo + unc.bench_damping[0]
    b1_hi = b1_hi * (1 + unc.viscosity_spread) * ft_hi * runout + unc.bench_damping[1]
    d0 = teq_0 if op.delay_source == "geometry" else np.full(ok.shape, op.delay)
    if unc.delay is not None:
        tau_lo, tau_hi = np.full(ok.shape, unc.delay[0]), np.full(ok.shape, unc.delay[1])
    else:
        tau_lo, tau_hi = np.fmin(teq_lo, op.delay), np.fmax(teq_hi, op.delay)
    w = base.transmission.workspace
    c_lo, c_hi = unc.torque_factor
    tr = base.transmission
    n = ok.shape
    # a corner with no finite figure (a torque response that never settles: τ_eq = inf)
    # leaves the design unjudged (NaN) rather than judged on a part of its ranges
    for x in (m1_lo, m1_hi, b1_lo, b1_hi, f_lo, f_hi, tau_lo, tau_hi):
        ok = ok & np.isfinite(x)
    return HandBox(
        m1=(m1_0, m1_lo, m1_hi),
        b1=(b1_0, b1_lo, b1_hi),
        delay=tuple(np.where(ok, x, np.nan) for x in (d0, tau_lo, tau_hi)),
        K=(f_0 / w, f_lo * c_lo / w, f_hi * c_hi / w),
        k=np.full(n, tr.k), b=np.full(n, tr.b), m2=np.full(n, tr.m2), valid=ok,
    )  # fmt: skip


# ---- the verdicts over the box ----------------------------------------------------------

#: The keys :func:`robust_columns_batch` returns (``outputs.SWEEP_OPTIONAL`` names them).
ROBUST_COLUMNS: tuple[str, ...] = (
    "max_stable_K_worst_N_per_m",
    "max_passive_K_worst_N_per_m",
    "bandwidth_worst_hz",
)


def robust_limits(
    box: HandBox,
    *,
    points: int = 3,
    zooms: int = 3,
    cases: tuple[str, ...] = ("nominal", "worst", "best"),
) -> dict[str, np.ndarray]:
    """Nominal, worst and best of the largest stable K, the largest passive K [N/m] and the
    bandwidth at the rendered K_max [Hz] over ``box`` (module docstring: corners where the
    verdict is monotone, a bounded search elsewhere). Keys ``<quantity>_<case>`` with
    quantity in (max_stable_K, max_passive_K, bandwidth) and case in ``cases`` (of nominal,
    worst, best); NaN for invalid designs."""
    ok = box.valid
    n = ok.size
    out = {f"{q}_{c}": np.full(n, np.nan) for q in ("max_stable_K", "max_passive_K",
                                                     "bandwidth") for c in cases}  # fmt: skip
    if not ok.any():
        return out
    sub = HandBox(*(tuple(x[ok] for x in f) if isinstance(f, tuple) else f[ok]
                    for f in (box.m1, box.b1, box.delay, box.K, box.k, box.b, box.m2,
                              box.valid)))  # fmt: skip
    (_, mlo, mhi), (_, blo, bhi), (_, tlo, thi), (k0, klo, khi) = sub.m1, sub.b1, sub.delay, sub.K
    res: dict[str, np.ndarray] = {}
    nom = sub.nominal
    if "nominal" in cases:
        res["max_stable_K_nominal"] = stable_stiffness_batch(nom)
        res["max_passive_K_nominal"] = max_passive_stiffness(nom)
        res["bandwidth_nominal"] = bandwidth(nom, k0)
    # passive K: corners (non-increasing in m1, increasing in b1, decreasing in τ)
    if "worst" in cases:
        res["max_passive_K_worst"] = max_passive_stiffness(sub.params(mhi, blo, thi))
    if "best" in cases:
        res["max_passive_K_best"] = max_passive_stiffness(sub.params(mlo, bhi, tlo))
    # stable K: monotone in none of m1, b1, τ (a transmission resonance makes more b1
    # destabilise: tests), a search over all three
    for case, sense, z in (x for x in (("worst", -1, zooms + 2), ("best", 1, zooms))
                           if x[0] in cases):  # fmt: skip
        res[f"max_stable_K_{case}"], _ = box_search(
            lambda x: stable_stiffness_batch(sub.params(x[..., 0], x[..., 1], x[..., 2])),
            np.stack([mlo, blo, tlo], 1), np.stack([mhi, bhi, thi], 1), sense=sense,
            points=points, zooms=z)  # fmt: skip
    # bandwidth at the rendered K: not monotone in any input (tests): a search over all four
    for case, sense in (x for x in (("worst", -1), ("best", 1)) if x[0] in cases):
        res[f"bandwidth_{case}"], _ = box_search(
            lambda x: bandwidth(sub.params(x[..., 0], x[..., 1], x[..., 2]), x[..., 3]),
            np.stack([mlo, blo, tlo, klo], 1), np.stack([mhi, bhi, thi, khi], 1),
            sense=sense, points=points, zooms=zooms + 1)  # fmt: skip
    for key, v in res.items():
        out[key][ok] = v
    return out


CASES = ("nominal", "worst", "best")


def robust_columns_batch(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign | None = None,
    uncertainty: Uncertainty | None = None,
    *,
    nominal: Mapping[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """robust_columns_batch(fields, base=None, uncertainty=None, *, nominal=None)
    -> dict[str, np.ndarray]

    The worst case, over ``uncertainty`` (an :class:`mrclutch.uncertainty.Uncertainty`;
    None: ``base.ranges``, its declared uncertainty or the defaults), of the largest stable K
    and the largest passive K [N/m] and of the bandwidth at the rendered K_max [Hz], for S
    designs at once.
    ``fields``: the DrumClutch field arrays ``pipeline.evaluate_batch`` takes (missing
    fields from ``base.clutch``); ``base``: the ClutchDesign giving the operating point and
    transmission (None: ``ClutchDesign()``). Returns 1-D arrays of S under
    ``ROBUST_COLUMNS``: ``max_stable_K_worst_N_per_m``, ``max_passive_K_worst_N_per_m``,
    ``bandwidth_worst_hz``; NaN for designs DrumClutch's validation refuses. Never above
    the worst over a dense sampling of the ranges (tests/mrclutch/test_robust.py).
    ``nominal``: ``evaluate_batch(fields, base)``'s rows where already computed (saves one
    fast-path evaluation)."""
    base = base if base is not None else ClutchDesign()
    unc = uncertainty if uncertainty is not None else base.ranges
    lim = robust_limits(hand_box_batch(fields, base, unc, nominal), cases=("worst",))
    return {
        "max_stable_K_worst_N_per_m": lim["max_stable_K_worst"],
        "max_passive_K_worst_N_per_m": lim["max_passive_K_worst"],
        "bandwidth_worst_hz": lim["bandwidth_worst"],
    }


# ---- one design: the robust read-out of an Evaluation ----------------------------------

#: Inputs whose one-at-a-time threshold is root-found (others nominal): HapticParams field,
#: label, unit, display scale.
THRESHOLD_INPUTS: tuple[tuple[str, str, str, float], ...] = (
    ("b1", "b1", "N·s/m", 1.0),
    ("delay", "the delay", "ms", 1e3),
)
#: The verdicts at K that a threshold decides, and the exact kernel of each limit.
_LIMITS: dict[str, Callable[[HapticParams], Any]] = {
    "stable": max_stable_stiffness,
    "passive": max_passive_stiffness,
}


def _holds(worst: float, best: float, K: float) -> str:
    """ "always" (K within the limit at every value of the ranges), "never", or "depends"."""
    if K <= worst:
        return "always"
    if K > best:
        return "never"
    return "depends"


def threshold(p: HapticParams, K: float, verdict: str, field: str) -> dict[str, Any] | None:
    """The value x* of ``field`` (others as in ``p``) at which ``verdict`` ("stable" or
    "passive") at K flips: the limit's exact kernel equals K there (Brent's root-find on
    log x over 10⁻³–10³ × the value in ``p``, the delay up to 1 s). ``sense`` "≥" when the
    verdict holds above x*, "≤" below. None where no value of this input alone flips it."""
    from scipy.optimize import brentq

    limit = _LIMITS[verdict]
    x0 = float(getattr(p, field))
    if x0 <= 0:
        return None

    def g(u: float) -> float:
        v = float(limit(replace(p, **{field: math.exp(u)})))
        return math.log(min(v, 1e12) / K)

    lo, hi = math.log(x0 * 1e-3), math.log(min(x0 * 1e3, 1.0) if field == "delay" else x0 * 1e3)
    us = np.linspace(lo, hi, 13)
    gs = [g(u) for u in us]
    # the crossing nearest the value in p
    u0 = math.log(x0)
    best = None
    for a, b, ga, gb in zip(us[:-1], us[1:], gs[:-1], gs[1:], strict=True):
        if ga == 0 or ga * gb < 0:
            r = a if ga == 0 else brentq(g, a, b, xtol=1e-12, rtol=1e-10)
            if best is None or abs(r - u0) < abs(best[0] - u0):
                best = (r, ga, gb)
    if best is None:
        return None
    r, ga, gb = best
    return {"value": math.exp(r), "sense": "≥" if gb > ga else "≤"}


def _rescaled(box: HandBox, p: HapticParams, K: float, bench: tuple[float, float]) -> HandBox:
    """The box of the fast path moved onto the evaluated pair ``p`` (another fidelity, or
    measured values): each range keeps its ratio to the nominal; the bench damping is
    additive; a nominal of 0 (a typed delay of 0) moves its range by the new value.
    Measured quantities (a range of one value) stay as they are."""

    def scale(t: tuple[np.ndarray, ...], v: float, add: tuple[float, float] = (0.0, 0.0)
              ) -> tuple[np.ndarray, ...]:  # fmt: skip
        nom, lo, hi = (float(x[0]) for x in t)
        if nom == 0.0:  # no ratio to keep (a typed delay of 0): the range moves by v
            return tuple(np.array([x]) for x in (v, lo + v, hi + v))
        r_lo, r_hi = (lo - add[0]) / nom, (hi - add[1]) / nom
        return tuple(np.array([x]) for x in (v, v * r_lo + add[0], v * r_hi + add[1]))

    return replace(box, m1=scale(box.m1, float(p.m1)), b1=scale(box.b1, float(p.b1), bench),
                   delay=scale(box.delay, float(p.delay)), K=scale(box.K, K))  # fmt: skip


@dataclass(frozen=True)
class RobustBox:
    """What ``robust_verdicts`` reads of an evaluation before it looks at K (the costly
    fast-path corners): the hand box over the ranges, the fields a bench fixed, the
    limits over the box (``robust_limits``) and the ranges. It does not depend on the K
    rendered, so a K chosen from its limits (``verdict.rendered_K``) reuses it."""

    box: HandBox
    fixed: tuple[str, ...]
    limits: dict[str, np.ndarray]
    uncertainty: Uncertainty


def robust_box(ev: Any, uncertainty: Uncertainty | None = None) -> RobustBox:
    """The :class:`RobustBox` of an ``Evaluation`` over ``uncertainty`` (None: the
    design's ``ranges``). Quantities a bench measured and the model uses are not varied."""
    design = ev.design
    unc = uncertainty if uncertainty is not None else design.ranges
    fields = {f: np.array([v]) for f, v in vars(design.clutch).items()}
    box = hand_box_batch(fields, design, unc)
    mr = ev.mr
    box = _rescaled(box, mr, float(mr.k_max), unc.bench_damping)
    meas = design.measured
    fixed: tuple[str, ...] = ()  # the HandBox fields a bench measured: no range, no threshold
    if meas is not None and meas.use_in_model:
        fix = {"m1": meas.m1, "b1": meas.b1, "delay": meas.step_delay}
        fixed = tuple(f for f, v in fix.items() if v is not None)
        box = replace(box, **{f: tuple(np.array([float(getattr(mr, f))]) for _ in range(3))
                              for f in fixed})  # fmt: skip
    return RobustBox(box, fixed, robust_limits(box), unc)


def robust_verdicts(ev: Any, uncertainty: Uncertainty | None = None,
                    prepared: RobustBox | None = None) -> dict[str, Any]:  # fmt: skip
    """The robust read-out of an ``Evaluation`` (docs/verdicts.md): per verdict nominal,
    worst and best over ``uncertainty`` (None: the design's ``ranges``), whether each
    verdict at K holds always / never / depending on the inputs, the thresholds of b1 and
    the delay that decide it (one at a time, the others nominal), the box and a one-
    sentence headline. ``prepared``: its ``robust_box`` if already made (same pair)."""
    rb = prepared if prepared is not None else robust_box(ev, uncertainty)
    box, fixed, lim, unc = rb.box, rb.fixed, rb.limits, rb.uncertainty
    K = float(ev.haptic["K_N_per_m"])
    mr = ev.mr
    out: dict[str, Any] = {"K_N_per_m": K}
    pairs = (("max_stable_K", "max_stable_K_N_per_m"), ("max_passive_K", "max_passive_K_N_per_m"),
             ("bandwidth", "bandwidth_hz"))  # fmt: skip
    for q, key in pairs:
        out[key] = {c: float(lim[f"{q}_{c}"][0]) for c in CASES}
    # the rendering area at K and the Z-width area: searched (3³ grids, two zooms)
    lo3 = np.array([[box.m1[1][0], box.b1[1][0], box.delay[1][0]]])
    hi3 = np.array([[box.m1[2][0], box.b1[2][0], box.delay[2][0]]])

    def area(x: np.ndarray) -> np.ndarray:
        return rendering_area(box.params(x[..., 0], x[..., 1], x[..., 2]), K)

    def zw(x: np.ndarray) -> np.ndarray:
        return zwidth_of(box.params(x[..., 0], x[..., 1], x[..., 2]))["zwidth_area_N2_s_per_m2"]

    nom = box.nominal
    for key, fn, nominal in (
        ("rendering_area_dB_decade", area, rendering_area(nom, K)),
        ("zwidth_area_N2_s_per_m2", zw, zwidth_of(nom)["zwidth_area_N2_s_per_m2"]),
    ):
        w, _ = box_search(fn, lo3, hi3, sense=-1, points=3, zooms=2)
        b, _ = box_search(fn, lo3, hi3, sense=1, points=3, zooms=2)
        out[key] = {"nominal": float(np.ravel(nominal)[0]), "worst": float(w[0]),
                    "best": float(b[0])}  # fmt: skip
    verdicts: dict[str, Any] = {}
    for verdict, key in (("stable", "max_stable_K_N_per_m"), ("passive", "max_passive_K_N_per_m")):
        v = out[key]
        holds = _holds(v["worst"], v["best"], K)
        th = {}
        if holds == "depends":
            for field, *_ in THRESHOLD_INPUTS:
                if field in fixed:
                    continue
                t = threshold(mr, K, verdict, field)
                if t is not None:
                    rng = getattr(box, field)  # THRESHOLD_INPUTS' fields are HandBox's
                    t["range"] = [float(rng[1][0]), float(rng[2][0])]
                    t["at_nominal_of_others"] = True
                    th[field] = t
        verdicts[verdict] = {"nominal": bool(K <= v["nominal"] * (1 + 1e-9)), "holds": holds,
                             "thresholds": th}  # fmt: skip
    out["verdicts"] = verdicts
    out["ranges"] = {
        "m1_kg": [float(box.m1[1][0]), float(box.m1[2][0])],
        "b1_N_s_per_m": [float(box.b1[1][0]), float(box.b1[2][0])],
        "delay_s": [float(box.delay[1][0]), float(box.delay[2][0])],
        "K_max_N_per_m": [float(box.K[1][0]), float(box.K[2][0])],
    }
    out["nominal"] = {"m1_kg": float(mr.m1), "b1_N_s_per_m": float(mr.b1),
                      "delay_s": float(mr.delay)}  # fmt: skip
    out["uncertainty"] = {k: v for k, v in vars(unc).items()}
    out["headline"] = headline(out)
    return out


def _fmt_threshold(field: str, t: dict[str, Any]) -> str:
    label, unit, scale = next((lb, u, s) for f, lb, u, s in THRESHOLD_INPUTS if f == field)
    lo, hi = (x * scale for x in t["range"])
    inside = t["range"][0] <= t["value"] <= t["range"][1]
    where = "range" if inside else "outside its range"
    value = f"{t['value'] * scale:.3g} {unit}"
    return f"{label} {t['sense']} {value} ({where} {lo:.3g}–{hi:.3g} {unit})"


def headline(r: dict[str, Any]) -> str:
    """The robust verdict of ``robust_verdicts`` in one sentence."""
    K = r["K_N_per_m"]
    v = r["verdicts"]
    ks, kp = r["max_stable_K_N_per_m"], r["max_passive_K_N_per_m"]
    words = {"stable": ("stable", "unstable"), "passive": ("passive", "not passive")}
    always = [n for n in ("stable", "passive") if v[n]["holds"] == "always"]
    never = [n for n in ("stable", "passive") if v[n]["holds"] == "never"]
    parts = []
    if always:
        parts.append(" and ".join(words[n][0] for n in always) + " for every value of the ranges")
    if never:
        parts.append(" and ".join(words[n][1] for n in never) + " for every value of the ranges")
    for n in ("stable", "passive"):
        if v[n]["holds"] != "depends":
            continue
        th = v[n]["thresholds"]
        cond = " or ".join(_fmt_threshold(f, t) for f, t in th.items()) or "jointly decided"
        nominal = words[n][0] if v[n]["nominal"] else words[n][1]
        parts.append(f"{nominal} at nominal values, {words[n][0]} only if {cond}")
    return (f"Robust verdict at K = {K:.4g} N/m: " + "; ".join(parts)
            + f" (each input alone, the others nominal); over the ranges the largest stable K "
            f"is {ks['worst']:.4g}–{ks['best']:.4g} N/m, the largest passive K "
            f"{kp['worst']:.4g}–{kp['best']:.4g} N/m.")  # fmt: skip


# ---- model against a bench --------------------------------------------------------------


def measured_comparison(ev: Any) -> list[dict[str, Any]]:
    """Every quantity the design's ``[measured]`` holds, model against measurement: rows of
    quantity, unit, model, measured, error (model/measured − 1) and how the model got it.
    The model's torque at the current limit is the evaluation's (its own method); at other
    currents the reluctance network's (the fast model)."""
    meas = ev.design.measured
    if meas is None or meas.empty:
        return []
    op = ev.design.operating
    model = ev.model_mr if ev.model_mr is not None else ev.mr
    rows: list[dict[str, Any]] = []

    def row(q: str, unit: str, m: float, x: float, how: str) -> None:
        rows.append({"quantity": q, "unit": unit, "model": m, "measured": x,
                     "error": m / x - 1.0, "model_source": how})  # fmt: skip

    limit = ev.clutch.max_current
    other = [p.current for p in meas.torque if not math.isclose(p.current, limit, rel_tol=1e-9)]
    curve = {}
    if other:
        c = torque_curve(ev.design.clutch, other, method="network",
                         speed_rpm=op.input_speed_rpm, temperature=op.fluid_temperature,
                         support=ev.design.support)  # fmt: skip
        curve = dict(zip(other, (float(t) for t in c.torque), strict=True))
    for p in meas.torque:
        if p.current in curve:
            row(f"torque at {p.current:g} A", "N·m", curve[p.current], p.torque, "fast model")
        else:
            row(f"torque at {p.current:g} A", "N·m", ev.clutch.max_torque, p.torque,
                f"torque by {ev.clutch.methods['torque']}")  # fmt: skip
    if meas.step_delay is not None:
        row("delay of a torque step", "s", float(ev.response["torque_delay_s"]),
            meas.step_delay, "equivalent delay (magnetics.dynamics)")  # fmt: skip
    if meas.m1 is not None:
        row("m1 at the hand", "kg", float(model.m1), meas.m1, "Eq. 3 of the rotor and fluid")
    if meas.b1 is not None:
        row("b1 at the hand", "N·s/m", float(model.b1), meas.b1, "Eq. 3 of the drag terms")
    if meas.off_state_torque is not None:
        row("off-state torque", "N·m", ev.clutch.off_state_torque, meas.off_state_torque,
            "drag terms (magnetics.drag)")  # fmt: skip
    return rows


@dataclass(frozen=True)
class RobustBatchEvaluator(BatchEvaluator):
    """``pipeline.BatchEvaluator`` that also computes the robust columns (``ROBUST_COLUMNS``,
    ``outputs.SWEEP_OPTIONAL``) over ``uncertainty`` (None: the base design's ``ranges``):
    what ``sweep --with max_stable_K_worst_N_per_m`` runs. Picklable."""

    uncertainty: Uncertainty | None = None

    def __call__(self, fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        on = set(self.optional)
        plain = tuple(k for k in self.optional if k not in ROBUST_COLUMNS)
        rows = dict(BatchEvaluator(self.base, plain)(fields))
        if on & set(ROBUST_COLUMNS):
            rows.update(robust_columns_batch(fields, self.base, self.uncertainty, nominal=rows))
        return {k: rows[k] for k in self.columns}
