"""Z-width of the 2-DOF haptic lever: the virtual spring–damper pairs (K, B) it renders
passively ([colgate-brown1994] coined the term), and the stability of the free loop at
points of the Z-width boundary. SI units: K [N/m], B [N·s/m]. The sampled-data passivity
condition of one rigid mass is ``mrclutch.haptics.sampled``.

**Continuous-time Z-width** (model of ``mrclutch.haptics.impedance``, [lebel] Fig. 4b). The
controller renders F_a = −E(s)(K + B s) x2, E = e^{−sτ} × (zero-order hold's fundamental
when ``sample_period`` > 0, as ``impedance._hold``). Then::

    Z_cl = [s Num + E (K + B s)(bs + k)] / (s D1)
    Re Z_cl(jω) = R(ω) + K gK(ω) + B gB(ω),   R = Re Z_p,
    gK = Re[E (bs + k)/(s D1)],   gB = Re[E (bs + k)/D1]

affine in (K, B), so the passive set P = {K, B ≥ 0 : R + K gK + B gB ≥ 0 ∀ω} is an
intersection of half-planes: convex. At a given B it is the interval [K_min(B), K_max(B)]::

    K_max(B) = inf over {gK < 0} of (R + B gB)/(−gK)    (concave in B)
    K_min(B) = max(0, sup over {gK > 0} of −(R + B gB)/gK)   (convex in B)

(empty, NaN, where K_min > K_max or R + B gB < 0 where gK = 0). Intercepts:
K_max(0) = ``limits.max_passive_stiffness`` and B_max = inf over {gB < 0} of R/(−gB) (the
largest damper passive with K = 0). With a delay, gK > 0 at some frequencies, and P may
extend past B_max with K_min > 0 (about 8 % of random designs): its right end B_top ≥ B_max
is found by bisection on the frequency grid, then regula falsi on the refined bounds.
The Z-width area is ∫_0^{B_top} (K_max − K_min) dB [N²·s/m²] on cosine-spaced nodes:
the trapezoid rule (a lower bound, the width being concave) and the least of the nodes'
tangents (slopes of the active constraints; an upper bound). On 10⁴ random designs with
17 nodes the two differ by 0.8 % (median), 1.4 % (max). Every infimum is a dense log
grid (1e-3 Hz – 1 MHz, 40 per decade, as ``max_passive_stiffness``) zoomed on its
minimum: the same five 41-point zooms for K_max(0) and B_max (so K_max(0) equals
``max_passive_stiffness``), three 21-point zooms at the other B. Like
``max_passive_stiffness`` it is not certified against a dip narrower than the grid step.

**Stability** of the free loop (χ(s) = s Num + E(s)(K + Bs)(bs + k), D-subdivision as
``limits._crossings``, extended to a ray). A point (K, B) is reached from 0 along the ray
(K, B) = ρ (c, σ), c = cos φ, σ = sin φ. For ρ > 0 small the roots are those of s Num (left
half-plane; Num is the passive device's) with the rigid-body root moved to ≈ −ρc/b1 (it
stays at s = 0 when K = 0: marginal, reported stable as ``limits.is_stable`` does for K = 0)
and the delay's roots coming from Re s = −∞. Roots cross the imaginary axis at jω where
ρ = −jω Num(jω)/[(k + jbω) E(jω) (c + jσω)] is real and positive; each crossing moves 2
roots (a conjugate pair) in the direction sign Re(ds/dρ). Without delay or hold the
crossing frequencies are the positive real roots of a polynomial; otherwise sign changes
of the imaginary part on a grid fine against the delay's phase period, from below
``limits.quiet_below`` (no crossing lies lower, ``_ray_crossings``), up to a frequency
beyond which ρ(ω) ≥ m1 m2 ω (ω − ω_a)³ / [(k + bω)(c + σω)] (ω_a the largest |root| of
Num; this bound is increasing for ω > ω_a) exceeds the point's ρ. **Certified**: for a pure
delay, the count is exact up to the grid scan for sign changes of Im ρ(ω) (two crossings
closer than the scan step would be missed, as in ``limits._crossings``); with a zero-order
hold only its fundamental is modelled (aliasing neglected), as in ``model``. **Not
certified**: that the region between the checked boundary points is stable — the stability
boundary is not traced in (K, B), only the points asked for are checked.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from geometry.numerics import illinois
from geometry.validation import ParameterError
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.impedance import _hold, _num_coeffs
from mrclutch.haptics.limits import _poles_and_zeros, _scan_imaginary_axis, quiet_below

__all__ = [
    "ZWIDTH_KEYS",
    "is_stable_spring_damper",
    "max_passive_damping",
    "passive_stiffness_interval",
    "zwidth",
]

TWO_PI = 2.0 * math.pi
U_GRID = np.linspace(-3.0, 6.0, 361)  # log10 f [Hz], 1e-3 Hz – 1 MHz, 40 per decade
ZWIDTH_KEYS = (
    "B_N_s_per_m",
    "K_max_N_per_m",
    "K_min_N_per_m",
    "K_max_at_B0_N_per_m",
    "B_max_at_K0_N_s_per_m",
    "B_top_N_s_per_m",
    "zwidth_area_N2_s_per_m2",
    "zwidth_area_upper_N2_s_per_m2",
)


# --- continuous-time Z-width ---------------------------------------------------------


def _columns(p: HapticParams) -> HapticParams:
    """The designs of ``p`` flattened to a column (n, 1) of scalar-field rows."""
    shape = p.shape
    f = {
        n: np.ravel(np.broadcast_to(np.asarray(getattr(p, n), float), shape))[:, None]
        for n in ("m1", "b1", "k", "b", "m2", "delay", "sample_period")
    }
    return HapticParams._of_checked(**f)  # p's fields, checked when p was made


def _rows(q: HapticParams, idx: np.ndarray) -> HapticParams:
    names = ("m1", "b1", "k", "b", "m2", "delay", "sample_period")
    return HapticParams._of_checked(**{n: getattr(q, n)[idx] for n in names})  # q's rows


def _parts(q: HapticParams, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """R = Re Z_p, gK, gB (module docstring) at log10 f = u [Hz]; q's fields (n, 1)."""
    w = TWO_PI * 10.0**u
    s = 1j * w
    a3, a2, a1, a0 = _num_coeffs(q)
    d1 = (q.m1 * s + (q.b1 + q.b)) * s + q.k  # Eq. 2 denominator [lebel]
    R = ((((a3 * s + a2) * s + a1) * s + a0) / d1).real  # Re Z_p, Eq. 2 [lebel]
    t = _hold(q, w, None) * (q.b * s + q.k) / d1  # E (bs + k)/D1
    return R, t.imag / w, t.real  # gK = Re[t/(jω)] = Im t/ω, gB = Re t


def _lines(
    R: np.ndarray, gK: np.ndarray, gB: np.ndarray, sign: float
) -> tuple[np.ndarray, np.ndarray]:
    """(α, β) with the bound α + B β on K at each ω: sign −1 upper bounds (gK < 0, inf
    elsewhere), sign +1 lower bounds (gK > 0, −inf elsewhere)."""
    g = sign * gK
    ok = g > 0
    den = np.where(ok, g, 1.0)
    fill = np.inf if sign < 0 else -np.inf
    return np.where(ok, -sign * R / den, fill), np.where(ok, -sign * gB / den, 0.0)


def _refine(
    u0: np.ndarray,
    value: np.ndarray,
    ratio: Any,
    zooms: int,
    points: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Minimum over u of ``ratio(rows, u)`` per row, from its values ``value`` on the grid
    rows ``u0``: zoom ``zooms`` times on the current minimum with a ``points`` grid over
    its two neighbouring cells (as ``limits.max_passive_stiffness``). Returns (min, u*)."""
    rows = np.arange(value.shape[0])
    j = np.argmin(value, axis=1)
    best = value[rows, j]
    ubest = u0[rows, j]
    u, zoom = u0, np.linspace(-1.0, 1.0, points)
    for _ in range(zooms):
        live = np.nonzero(np.isfinite(best))[0]
        if live.size == 0:
            break
        du = u[live, 1:2] - u[live, 0:1]
        u_live = u[live, j[live]][:, None] + du * zoom
        r = ratio(live, u_live)
        jl = np.argmin(r, axis=1)
        v = r[np.arange(live.size), jl]
        better = v < best[live]
        best[live] = np.where(better, v, best[live])
        ubest[live] = np.where(better, u_live[np.arange(live.size), jl], ubest[live])
        u = np.empty((value.shape[0], points))
        u[live] = u_live
        j = np.zeros(value.shape[0], dtype=int)
        j[live] = jl
    return best, ubest


def _bound(
    q: HapticParams,
    rows: np.ndarray,
    B: np.ndarray,
    sign: float,
    zooms: int,
    points: int,
    coarse: tuple[np.ndarray, np.ndarray] | None = None,
    chunk: int = 4096,
) -> tuple[np.ndarray, np.ndarray]:
    """Refined K_max (sign −1: inf of the upper bounds) or the unclipped K_min (sign +1:
    sup of the lower bounds) at damping B[i] of design rows[i] (q's fields (n, 1)), and
    its slope dK/dB there (the active line's β). ``coarse``: the designs' lines (α, β) on
    ``U_GRID`` if already computed (only the zooms are then evaluated)."""
    out, slope = np.empty(B.size), np.empty(B.size)
    for a in range(0, B.size, chunk):
        sl = slice(a, a + chunk)
        qc = _rows(q, rows[sl])
        Bc = B[sl, None]
        u0 = np.broadcast_to(U_GRID, (Bc.shape[0], U_GRID.size))

        def ratio(r: np.ndarray, u: np.ndarray, qc: HapticParams = qc, Bc: Any = Bc) -> Any:
            al, be = _lines(*_parts(_rows(qc, r), u), sign)
            return -sign * (al + Bc[r] * be)  # minimised: K_max, or −K_min

        if coarse is None:
            v0 = ratio(np.arange(Bc.shape[0]), u0)
        else:
            v0 = -sign * (coarse[0][rows[sl]] + Bc * coarse[1][rows[sl]])
        best, ub = _refine(u0, v0, ratio, zooms, points)
        out[sl] = -sign * best
        live = np.isfinite(best)
        be = np.zeros(best.size)
        if live.any():
            be[live] = _lines(*_parts(_rows(qc, np.nonzero(live)[0]), ub[live, None]), sign)[1][
                :, 0
            ]
        slope[sl] = be
    return out, slope


def passive_stiffness_interval(p: HapticParams, B: Any) -> tuple[Any, Any]:
    """(K_min(B), K_max(B)) [N/m]: the passive virtual springs at virtual damping B
    [N·s/m] (module docstring); NaN both where no K ≥ 0 is passive. ``p`` fields and ``B``
    broadcast. K_max(0) is ``limits.max_passive_stiffness`` (same grid and zooms)."""
    Ba = np.asarray(B, dtype=float)
    if np.any(~np.isfinite(Ba) | (Ba < 0)):
        raise ParameterError("B: every virtual damping must be finite and >= 0 N·s/m")
    shape = np.broadcast_shapes(p.shape, Ba.shape)
    idx = np.arange(int(np.prod(p.shape))).reshape(p.shape) if p.shape else np.array(0)
    idx = np.ravel(np.broadcast_to(idx, shape))
    Bf = np.ravel(np.broadcast_to(Ba, shape))
    q = _columns(p)
    hi = _bound(q, idx, Bf, -1.0, 5, 41)[0]
    lo = np.maximum(_bound(q, idx, Bf, 1.0, 5, 41)[0], 0.0)
    bad = ~(lo <= hi)
    hi, lo = np.where(bad, np.nan, hi), np.where(bad, np.nan, lo)
    if shape:
        return lo.reshape(shape), hi.reshape(shape)
    return float(lo[0]), float(hi[0])


def max_passive_damping(p: HapticParams) -> Any:
    """B_max [N·s/m]: the largest virtual damper passive with K = 0, inf over {gB < 0} of
    Re Z_p/(−gB) (module docstring; inf if gB ≥ 0 everywhere). Vectorised over designs."""
    q = _columns(p)
    R, _, gB = _parts(q, np.broadcast_to(U_GRID, (q.m1.shape[0], U_GRID.size)))
    best = _damping(q, _damping_ratio(R, gB))
    return best.reshape(p.shape) if p.shape else float(best[0])


def _damping_ratio(R: np.ndarray, gB: np.ndarray) -> np.ndarray:
    """Re Z_p/(−gB) where gB < 0, inf elsewhere: ``max_passive_damping``'s bound per ω."""
    neg = gB < 0
    return np.where(neg, R / np.where(neg, -gB, 1.0), np.inf)


def _damping(q: HapticParams, v0: np.ndarray) -> np.ndarray:
    """``max_passive_damping`` of the rows of ``q`` (fields (n, 1)) from its ratio on
    ``U_GRID`` (``_damping_ratio``), refined: zwidth hands over the grid it computed for
    its own lines instead of this evaluating ``_parts`` on it a second time (issue 40)."""
    u0 = np.broadcast_to(U_GRID, (q.m1.shape[0], U_GRID.size))

    def ratio(rows: np.ndarray, u: np.ndarray) -> np.ndarray:
        R, _, gB = _parts(_rows(q, rows), u)
        return _damping_ratio(R, gB)

    return _refine(u0, v0, ratio, 5, 41)[0]


def _feasible(al_hi, be_hi, al_lo, be_lo, B):  # type: ignore[no-untyped-def]
    """Whether some K ≥ 0 meets every grid bound at damping B (rows, B (n, 1))."""
    hi = np.min(al_hi + B * be_hi, axis=1)
    lo = np.maximum(np.max(al_lo + B * be_lo, axis=1), 0.0)
    return lo <= hi


def _tangent_area(B: np.ndarray, W: np.ndarray, S: np.ndarray) -> np.ndarray:
    """∫ of the least of the two tangents W_i + S_i (B − B_i) on each interval: an upper
    bound on ∫ W dB for W concave with supergradients S (rows of nodes)."""
    h = np.diff(B, axis=1)
    f0, f1, s0, s1 = W[:, :-1], W[:, 1:], S[:, :-1], S[:, 1:]
    ds = s0 - s1
    ok = ds > 1e-300
    x = np.where(ok, (f1 - s1 * h - f0) / np.where(ok, ds, 1.0), 0.5 * h)
    x = np.clip(x, 0.0, h)
    seg = f0 * x + 0.5 * s0 * x * x + f1 * (h - x) - 0.5 * s1 * (h - x) ** 2
    seg = np.where(ok, seg, 0.5 * (f0 + f1) * h)
    return np.maximum(seg, 0.5 * (f0 + f1) * h).sum(axis=1)


def zwidth(p: HapticParams, n_b: int = 17) -> dict[str, np.ndarray]:
    """The Z-width of each design (module docstring), as arrays under ``ZWIDTH_KEYS``:
    ``n_b`` dampings ``B_N_s_per_m`` over [0, B_top] (shape ``p.shape + (n_b,)``,
    B = B_top (1 − (1 − t)²) for t uniform: denser towards B_top, where the width may
    close like √(B_top − B)) with ``K_max_N_per_m``/``K_min_N_per_m`` there (NaN where
    empty); per design the intercepts ``K_max_at_B0_N_per_m`` (= max_passive_stiffness)
    and ``B_max_at_K0_N_s_per_m``, the right end ``B_top_N_s_per_m``, the area
    ``zwidth_area_N2_s_per_m2`` = ∫ (K_max − K_min) dB (trapezoid: a lower bound, the
    width being concave; inf with B_top: unbounded) and ``zwidth_area_upper_N2_s_per_m2``
    (the tangents at the nodes, slopes of the active constraints: an upper bound).
    Vectorised over designs."""
    if n_b < 2:
        raise ParameterError(f"n_b = {n_b}: need at least 2 damping values")
    shape = p.shape
    q = _columns(p)
    n = q.m1.shape[0]
    R, gK, gB = _parts(q, np.broadcast_to(U_GRID, (n, U_GRID.size)))
    hi_lines = _lines(R, gK, gB, -1.0)
    lo_lines = _lines(R, gK, gB, 1.0)

    v0 = _damping_ratio(R, gB)  # max_passive_damping's grid: the same _parts
    b_max = _damping(q, v0)
    b_grid = np.min(v0, axis=1)
    # right end of P: past B_max only where some K > 0 stays feasible (on the grid); then
    # doubling and bisection on the grid's feasibility (P convex: feasible B an interval)
    top = b_max.copy()
    fin = np.nonzero(np.isfinite(b_grid))[0]
    rows = (hi_lines[0][fin], hi_lines[1][fin], lo_lines[0][fin], lo_lines[1][fin])
    lo_b = b_grid[fin]
    hi_b = lo_b * (1.0 + 1e-6)
    ext = _feasible(*rows, hi_b[:, None])
    grow = ext.copy()
    for _ in range(60):  # P is bounded where B_max is finite (gB < 0 somewhere)
        if not grow.any():
            break
        lo_b = np.where(grow, hi_b, lo_b)
        hi_b = np.where(grow, 2.0 * hi_b, hi_b)
        grow &= _feasible(*rows, hi_b[:, None])
    for _ in range(50):
        if not ext.any():
            break
        mid = 0.5 * (lo_b + hi_b)
        ok = _feasible(*rows, mid[:, None])
        lo_b = np.where(ext & ok, mid, lo_b)
        hi_b = np.where(ext & ~ok, mid, hi_b)
    top[fin] = np.where(ext, np.maximum(lo_b, b_max[fin]), b_max[fin])

    t = np.linspace(0.0, 1.0, n_b)
    fin_top = np.where(np.isfinite(top), top, 0.0)  # unbounded rows: NaN nodes (below)
    Bg = fin_top[:, None] * 0.5 * (1.0 - np.cos(math.pi * t[None, :]))
    Bg[:, 0] = 0.0
    K_hi = np.full((n, n_b), np.nan)
    S_hi = np.zeros((n, n_b))
    K_lo = np.zeros((n, n_b))
    S_lo = np.zeros((n, n_b))
    all_rows = np.arange(n)
    # B = 0 with the grid and zooms of max_passive_stiffness
    K_hi[:, 0], S_hi[:, 0] = _bound(q, all_rows, np.zeros(n), -1.0, 5, 41, hi_lines)
    fin_rows = np.isfinite(top)
    d_idx = np.repeat(all_rows, n_b - 1)
    sel = fin_rows[d_idx]
    d_sel = d_idx[sel]
    B_sel = Bg[:, 1:].ravel()[sel]
    kh, sh = _bound(q, d_sel, B_sel, -1.0, 3, 21, hi_lines)
    tmp = np.full((n, n_b - 1), np.nan)
    tmp.ravel()[np.nonzero(sel)[0]] = kh
    K_hi[:, 1:] = tmp
    tmp = np.zeros((n, n_b - 1))
    tmp.ravel()[np.nonzero(sel)[0]] = sh
    S_hi[:, 1:] = tmp
    past = B_sel > b_max[d_sel]  # K_min = 0 up to B_max
    if past.any():
        kl, sl_ = _bound(q, d_sel[past], B_sel[past], 1.0, 3, 21, lo_lines)
        pos = kl > 0
        flat = np.nonzero(sel)[0][past]
        tmp = np.zeros((n, n_b - 1))
        tmp.ravel()[flat] = np.maximum(kl, 0.0)
        K_lo[:, 1:] = tmp
        tmp = np.zeros((n, n_b - 1))
        tmp.ravel()[flat] = np.where(pos, sl_, 0.0)
        S_lo[:, 1:] = tmp
    # where the grid's B_top overshoots the refined set (empty nodes at the end): the
    # refined end, root of the width between the last non-empty node and the next one
    W = K_hi - K_lo
    bad = np.nonzero(fin_rows & ~(W[:, -1] >= 0) & (W[:, 0] > 0))[0]
    if bad.size:
        j = np.argmax(~(W[bad] >= 0), axis=1)  # first empty node (≥ 1)

        def width(act: np.ndarray, x: np.ndarray) -> np.ndarray:
            d = bad[act]
            kh = _bound(q, d, x, -1.0, 3, 21, hi_lines)[0]
            return kh - np.maximum(_bound(q, d, x, 1.0, 3, 21, lo_lines)[0], 0.0)

        lo, hi = Bg[bad, j - 1], Bg[bad, j]
        wl, wh = W[bad, j - 1], np.nan_to_num(W[bad, j], nan=-1.0)
        end = illinois(width, lo, hi, wl, wh, 1e-6)
        top[bad] = end
        Bg[bad, j] = end
        for c in range(1, n_b):  # nodes past the end collapse onto it
            past_end = c > j
            Bg[bad[past_end], c] = end[past_end]
        kl, sl_ = _bound(q, bad, end, 1.0, 3, 21, lo_lines)
        sh = _bound(q, bad, end, -1.0, 3, 21, hi_lines)[1]
        sl_ = np.where(kl > 0, sl_, 0.0)
        kl = np.maximum(kl, 0.0)
        at_end = np.arange(n_b)[None, :] >= j[:, None]  # the closed end: K_min = K_max
        K_lo[bad] = np.where(at_end, kl[:, None], K_lo[bad])
        K_hi[bad] = np.where(at_end, kl[:, None], K_hi[bad])
        S_hi[bad] = np.where(at_end, sh[:, None], S_hi[bad])
        S_lo[bad] = np.where(at_end, sl_[:, None], S_lo[bad])
    # B_top: the set closes there; a rounding-level overlap of the bounds is the closure
    last = K_lo[:, -1] - K_hi[:, -1]
    close = (last > 0) & (last <= 1e-6 * K_hi[:, 0])
    K_hi[close, -1] = K_lo[close, -1]
    W = np.maximum(K_hi - K_lo, 0.0)
    W = np.where(np.isfinite(W), W, 0.0)
    area = np.where(fin_rows, np.trapezoid(W, Bg, axis=1), np.inf)
    upper = np.where(fin_rows, _tangent_area(np.where(fin_rows[:, None], Bg, 0.0), W,
                                             S_hi - S_lo), np.inf)  # fmt: skip
    empty = ~(K_lo <= K_hi)
    K_hi, K_lo = np.where(empty, np.nan, K_hi), np.where(empty, np.nan, K_lo)
    Bg[~fin_rows] = np.nan

    def per(x: np.ndarray) -> np.ndarray:
        return x.reshape(shape) if shape else x.reshape(())

    return {
        "B_N_s_per_m": Bg.reshape(*shape, n_b),
        "K_max_N_per_m": K_hi.reshape(*shape, n_b),
        "K_min_N_per_m": K_lo.reshape(*shape, n_b),
        "K_max_at_B0_N_per_m": per(K_hi[:, 0].copy()),
        "B_max_at_K0_N_s_per_m": per(b_max),
        "B_top_N_s_per_m": per(top),
        "zwidth_area_N2_s_per_m2": per(area),
        "zwidth_area_upper_N2_s_per_m2": per(upper),
    }


# --- stability along a ray (D-subdivision) -------------------------------------------


def _ray_crossings(p: HapticParams, c: float, sg: float, rho_stop: float) -> tuple[Any, Any]:
    """Crossing gains ρ_c (ascending) and directions of χ along (K, B) = ρ (c, sg), every
    crossing with ρ_c ≤ ``rho_stop`` (module docstring)."""
    a = _num_coeffs(p)
    roots = np.roots(a)
    w_a = float(np.max(np.abs(roots)))
    tau = p.delay + 0.5 * p.sample_period

    def X(w: Any) -> Any:  # ρ(ω)·e^{jφ}: a crossing where X is real and > 0
        w = np.asarray(w, dtype=float)
        s = 1j * w
        num = ((a[0] * s + a[1]) * s + a[2]) * s + a[3]
        return -s * num / ((p.b * s + p.k) * _hold(p, w, None) * (c + sg * s))

    if tau == 0.0:
        # Im[−jω Num(jω)(k − jbω)(c − jσω)] is a polynomial in ω: its positive real roots
        from numpy.polynomial import polynomial as P  # zero delay only (not haptic's)

        cn = np.array(a[::-1], dtype=complex) * (1j ** np.arange(4))  # Num(jω) in ω
        poly = P.polymul(P.polymul(P.polymul([0, -1j], cn), [p.k, -1j * p.b]), [c, -1j * sg])
        rts = np.roots(np.trim_zeros(poly.imag[::-1], "f"))
        wc = np.sort(rts.real[(np.abs(rts.imag) < 1e-9 * np.abs(rts)) & (rts.real > 0)])
    else:

        def lower(w: float) -> float:  # |ρ(ω)| past ω_a (|H| ≤ 1, |jω − r| ≥ ω − |r|)
            return a[0] * w * max(w - w_a, 0.0) ** 3 / ((p.k + p.b * w) * (c + sg * w))

        # No crossing lies below limits.quiet_below: there arg Num(jω) + ωτ < π/2 (its
        # derivation), so arg X = −π/2 + arg Num + ωτ − atan(bω/k) − atan(σω/c) lies in
        # (−3π/2, 0) (each atan in [0, π/2]) and X is never real positive. A fixed start
        # (10⁻⁴ ω_a) missed the slow delayed mode of a light, strongly coupled lever.
        w_z = float(np.min(np.abs(roots)))  # the slowest zero of Num
        rz = _poles_and_zeros(roots, p, *([-c / sg] if sg > 0 else []))  # X's, on the ray
        wc = _scan_imaginary_axis(
            X, w_a, tau, lower, rho_stop, w_lo=quiet_below(w_z, tau), roots=rz
        )
    xv = X(wc)
    ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
    wc, rc = wc[ok], xv.real[ok]
    s, h = 1j * wc, 1e-6 * wc

    def chi(rho: Any, s: Any) -> Any:  # χ along the ray
        num = ((a[0] * s + a[1]) * s + a[2]) * s + a[3]
        E = np.exp(-s * p.delay)
        if p.sample_period > 0:
            E = E * (1 - np.exp(-s * p.sample_period)) / (s * p.sample_period)
        return s * num + rho * E * (c + sg * s) * (p.b * s + p.k)

    dchi = (chi(rc, s + h) - chi(rc, s - h)) / (2 * h)
    dchi_drho = chi(rc + 1.0, s) - chi(rc, s)
    dirs = np.sign((-dchi_drho / dchi).real)
    order = np.argsort(rc)
    return rc[order], dirs[order]


def is_stable_spring_damper(p: HapticParams, K: float, B: float) -> bool:
    """Whether the free loop with the virtual spring–damper (K, B) has no root with
    Re s > 0 (D-subdivision along the ray from (0, 0); module docstring for what is
    certified). One design (scalar fields). (0, 0) and K = 0 keep the rigid-body root at
    s = 0 (marginal): reported True when no other root is unstable."""
    if p.shape:
        raise ParameterError(f"design shape = {p.shape}: need one design (scalar fields)")
    if not (math.isfinite(K) and math.isfinite(B) and K >= 0 and B >= 0):
        raise ParameterError(f"(K, B) = ({K}, {B}): need finite K, B >= 0")
    rho = math.hypot(K, B)
    if rho == 0.0:
        return True
    rc, dirs = _ray_crossings(p, K / rho, B / rho, rho)
    if np.any(np.isclose(rc, rho, rtol=1e-12)):
        return False
    return bool(np.sum(2 * dirs[rc < rho]) == 0)
