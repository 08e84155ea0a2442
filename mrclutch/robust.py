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
* largest stable K — increasing in b1 (tested): b1 at its corner; m1 and τ are not
  monotone (a heavier m1 can stabilise), so a *bounded global search* over (m1, τ)
  (:func:`box_search`: a 3 × 3 grid of the box, then grids half as wide on the best point,
  five times for the worst case), each point by :func:`stable_stiffness_batch` (the
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
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.numerics import illinois
from geometry.params import broadcast_fields
from magnetics.drag import drag_terms, totals
from mrclutch.design import ClutchDesign
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import (
    bandwidth,
    max_passive_stiffness,
    max_stable_stiffness,
)
from mrclutch.pipeline import evaluate_batch, mr_at_hand
from mrclutch.uncertainty import Uncertainty, default_uncertainty

TWO_PI = 2.0 * math.pi
#: Points of the log grid over [1e-4 ω_a, ω_end] in the vectorised crossing search.
_LOG_POINTS = 300
#: Phase step (rad) of the linear grid against the delay, ωτ per point.
_PHASE_STEP = 0.25
#: Most linear points a batch may take before designs go to the exact kernel one by one.
_MAX_LINEAR = 4000


def _num_coeffs(m1: Any, b1: Any, k: Any, b: Any, m2: Any) -> tuple[Any, Any, Any, Any]:
    """Eq. 2 numerator coefficients (s³, s², s¹, s⁰) [lebel]."""
    return (m1 * m2, m2 * b1 + m1 * b + m2 * b, b1 * b + m1 * k + m2 * k, b1 * k)


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
    a3, a2, a1, a0 = _num_coeffs(f["m1"], f["b1"], f["k"], f["b"], f["m2"])
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
                         temps: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(low, high) of the drag damping over the fluid temperature range, relative to its
    value at the operating temperature (η(T) monotone: the range's ends bound it)."""
    op = base.operating

    def fn(rg: Any, rows: np.ndarray) -> dict[str, Any]:
        d = [totals(drag_terms(rg, op.input_speed, t, base.support))[1]
             for t in (op.fluid_temperature, *temps)]  # fmt: skip
        return {"lo": d[1] / d[0], "hi": d[2] / d[0]}

    f = regions.per_topology(p, ok, fn)
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
      1/(g − e cos θ) around the drum [gradshteyn-ryzhik] 2.553.3), then + bench damping;
    * τ: the declared range, or the typed delay to the geometry's τ_eq (all corners);
    * K = F_max/d × the torque factor (yield stress and B–H lot spreads).

    ``nominal``: ``evaluate_batch(fields, base)``'s rows if already computed."""
    base = base if base is not None else ClutchDesign()
    unc = uncertainty if uncertainty is not None else default_uncertainty(base)
    p = broadcast_fields(fields, base.clutch)
    rows0 = nominal if nominal is not None else evaluate_batch(p, base)
    m1_0, b1_0, f_0, teq_0, ok = _hand_of(rows0, base)
    m1s, b1s, fs, teqs = [m1_0], [b1_0], [f_0], [teq_0]
    if unc.gap_tolerance > 0 or unc.drum_thickness_tolerance > 0:
        for dg in (-unc.gap_tolerance, unc.gap_tolerance):
            for dt in (-unc.drum_thickness_tolerance, unc.drum_thickness_tolerance):
                q = {**p, "gap": p["gap"] + dg, "drum_thickness": p["drum_thickness"] + dt}
                m1c, b1c, fc, teqc, _ = _hand_of(evaluate_batch(q, base), base)
                m1s.append(m1c), b1s.append(b1c), fs.append(fc), teqs.append(teqc)
    stack = [np.stack(x) for x in (m1s, b1s, fs, teqs)]
    # hull over the corners; a corner the validation refuses (NaN) is left out
    (m1_lo, b1_lo, f_lo, teq_lo), (m1_hi, b1_hi, f_hi, teq_hi) = (
        [np.where(ok, fn.reduce(s, axis=0), np.nan) for s in stack] for fn in (np.fmin, np.fmax)
    )
    op = base.operating
    t_lo, t_hi = unc.fluid_temperature if unc.fluid_temperature is not None else (
        op.fluid_temperature, op.fluid_temperature)  # fmt: skip
    ft_lo, ft_hi = _temperature_factors(p, ok, base, (t_lo, t_hi))
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


def _rows(x: np.ndarray) -> np.ndarray:
    return x[:, None]


def robust_limits(box: HandBox, *, points: int = 3, zooms: int = 3) -> dict[str, np.ndarray]:
    """Nominal, worst and best of the largest stable K, the largest passive K [N/m] and the
    bandwidth at the rendered K_max [Hz] over ``box`` (module docstring: corners where the
    verdict is monotone, a bounded search elsewhere). Keys ``<quantity>_<case>`` with
    quantity in (max_stable_K, max_passive_K, bandwidth) and case in (nominal, worst,
    best); NaN for invalid designs."""
    ok = box.valid
    n = ok.size
    out = {f"{q}_{c}": np.full(n, np.nan) for q in ("max_stable_K", "max_passive_K",
                                                     "bandwidth") for c in CASES}  # fmt: skip
    if not ok.any():
        return out
    sub = HandBox(*(tuple(x[ok] for x in f) if isinstance(f, tuple) else f[ok]
                    for f in (box.m1, box.b1, box.delay, box.K, box.k, box.b, box.m2,
                              box.valid)))  # fmt: skip
    (_, mlo, mhi), (_, blo, bhi), (_, tlo, thi), (k0, klo, khi) = sub.m1, sub.b1, sub.delay, sub.K
    res: dict[str, np.ndarray] = {}
    nom = sub.nominal
    res["max_stable_K_nominal"] = stable_stiffness_batch(nom)
    res["max_passive_K_nominal"] = max_passive_stiffness(nom)
    res["bandwidth_nominal"] = bandwidth(nom, k0)
    # passive K: corners (non-increasing in m1, increasing in b1, decreasing in τ)
    res["max_passive_K_worst"] = max_passive_stiffness(sub.params(mhi, blo, thi))
    res["max_passive_K_best"] = max_passive_stiffness(sub.params(mlo, bhi, tlo))
    # stable K: b1 at its corner (increasing in b1), a search over (m1, τ)
    for case, b1, sense, z in (("worst", blo, -1, zooms + 2), ("best", bhi, 1, zooms)):
        res[f"max_stable_K_{case}"], _ = box_search(
            lambda x, b1=b1: stable_stiffness_batch(sub.params(x[..., 0], _rows(b1), x[..., 1])),
            np.stack([mlo, tlo], 1), np.stack([mhi, thi], 1), sense=sense, points=points,
            zooms=z)  # fmt: skip
    # bandwidth at the rendered K: not monotone in any input (tests): a search over all four
    for case, sense in (("worst", -1), ("best", 1)):
        res[f"bandwidth_{case}"], _ = box_search(
            lambda x: bandwidth(sub.params(x[..., 0], x[..., 1], x[..., 2]), x[..., 3]),
            np.stack([mlo, blo, tlo, klo], 1), np.stack([mhi, bhi, thi, khi], 1),
            sense=sense, points=points, zooms=zooms + 1)  # fmt: skip
    for key, v in res.items():
        out[key][ok] = v
    return out


CASES = ("nominal", "worst", "best")


def robust_columns_batch(
    fields: Mapping[str, ArrayLike], base: Any = None, uncertainty: Any = None
) -> dict[str, np.ndarray]:
    """robust_columns_batch(fields, base=None, uncertainty=None) -> dict[str, np.ndarray]

    The worst case, over ``uncertainty`` (an :class:`mrclutch.uncertainty.Uncertainty`;
    None: ``default_uncertainty(base)``), of the largest stable K and the largest passive
    K [N/m] and of the bandwidth at the rendered K_max [Hz], for S designs at once.
    ``fields``: the DrumClutch field arrays ``pipeline.evaluate_batch`` takes (missing
    fields from ``base.clutch``); ``base``: the ClutchDesign giving the operating point and
    transmission (None: ``ClutchDesign()``). Returns 1-D arrays of S under
    ``ROBUST_COLUMNS``: ``max_stable_K_worst_N_per_m``, ``max_passive_K_worst_N_per_m``,
    ``bandwidth_worst_hz``; NaN for designs DrumClutch's validation refuses. Never above
    the worst over a dense sampling of the ranges (tests/mrclutch/test_robust.py)."""
    lim = robust_limits(hand_box_batch(fields, base, uncertainty))
    return {
        "max_stable_K_worst_N_per_m": lim["max_stable_K_worst"],
        "max_passive_K_worst_N_per_m": lim["max_passive_K_worst"],
        "bandwidth_worst_hz": lim["bandwidth_worst"],
    }
