"""The vectorised kernels the robust verdicts search with (docs/verdicts.md): the largest
stable K of many designs at once (``stable_stiffness_batch``, the D-subdivision of
``haptics.model`` on arrays) and a bounded search over a box of each design's parameters
(``box_search``)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from geometry.numerics import illinois
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.limits import quiet_below
from mrclutch.haptics.model import (
    _num_coeffs,
    max_stable_stiffness,
)

TWO_PI = 2.0 * math.pi
#: Points of the log grid over [1e-4 ω_a, ω_end] in the vectorised crossing search.
_LOG_POINTS = 300
#: Phase step (rad) of the linear grid against the delay, ωτ per point.
_PHASE_STEP = 0.25
#: Most linear points a batch may take before designs go to the exact kernel one by one.
_MAX_LINEAR = 4000
#: Turns of the delay's phase (2π/τ each) beyond ω_a that the first, short scan covers.
_TURNS = 3


def stable_stiffness_batch(p: HapticParams) -> np.ndarray:
    """``haptics.model.max_stable_stiffness`` of each design of a 1-D vectorised set, in one
    vectorised pass: the smallest gain K_c = Re X(ω_c) over the imaginary-axis crossings of
    the free loop, X(ω) = −jω Num(jω) e^{jωτ}/(k + jbω) real and positive (D-subdivision,
    ``haptics.model``'s docstring). For K → 0⁺ every root is in the left half-plane, so the
    first crossing met as K grows is destabilising: the stability limit is min K_c.

    Crossings are the sign changes of Im X on a grid of each design (log-spaced over
    [ω_lo, ω_top], ω_a the largest |zero| of Num, ω_lo = min(1e-4 ω_a,
    ``limits.quiet_below``: no crossing lies below it), merged with a linear grid of step
    0.25/τ), refined by Illinois regula falsi. |X(ω)| = ω|Num(jω)|/|k + jbω| does not
    depend on τ and rises beyond ω_a (each factor |jω − z| does for ω ≥ |z|), so no
    crossing beyond ω_top can give a smaller K_c once |X(ω_top)| exceeds the smallest found.
    The scan first stops at ω_top = ω_a + ``_TURNS`` turns of the delay's phase (2π/τ each;
    a positive-real crossing comes once a turn there), then, for designs where that bound
    does not yet hold, runs to ω_end = max(4 ω_a, 4/τ). Where the bound still does not hold,
    where no crossing is found, where the linear grid would exceed ``_MAX_LINEAR`` points or
    where a sample-and-hold is modelled, the design is handed to the exact kernel. Returns
    inf where no crossing destabilises."""
    shape = p.shape
    f = {n: np.ravel(np.broadcast_to(np.asarray(getattr(p, n), float), shape))
         for n in ("m1", "b1", "k", "b", "m2", "delay", "sample_period")}  # fmt: skip
    n = f["m1"].size
    out = np.full(n, np.nan)
    if n == 0:
        return out.reshape(shape)
    coeffs = tuple(np.ravel(np.broadcast_to(c, shape)) for c in _num_coeffs(p))
    zeros = zero_moduli(coeffs)
    w_a = np.max(zeros, axis=1)
    tau = f["delay"]
    w_lo = np.minimum(1e-4 * w_a, quiet_below(np.min(zeros, axis=1), tau))  # grid start
    exact = (f["sample_period"] > 0) | (tau <= 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        w_end = np.maximum(4.0 * w_a, np.where(tau > 0, 4.0 / tau, 0.0))
        w_first = np.minimum(w_end, w_a + np.where(tau > 0, _TURNS * TWO_PI / tau, 0.0))
    todo = np.nonzero(~exact)[0]
    for w_top in (w_first, w_end):  # a short scan first, the full one where it cannot tell
        n_lin = np.ceil(w_top[todo] * tau[todo] / _PHASE_STEP) + 2
        over = n_lin > _MAX_LINEAR
        exact[todo[over]] = True
        rows = todo[~over]
        best = _crossing_scan(coeffs, f["k"], f["b"], tau, w_lo, w_top, n_lin[~over], rows)
        done = np.isfinite(best) & (_abs_x(coeffs, f["k"], f["b"], w_top, rows) > best)
        out[rows[done]] = best[done]
        todo = rows[~done]
    exact[todo] = True
    hard = np.nonzero(exact)[0]
    if hard.size:  # the exact kernel's scans side by side (each row its scalar call's bits)
        out[hard] = max_stable_stiffness(
            HapticParams._of_checked(**{x: f[x][hard] for x in _EXACT_FIELDS})
        )
    return out.reshape(shape)


#: The fields ``stable_stiffness_batch`` hands the exact kernel (the others at their
#: defaults: the stability limit does not depend on the force capacity or workspace).
_EXACT_FIELDS = ("m1", "b1", "k", "b", "m2", "delay", "sample_period")


def zero_moduli(coeffs: tuple[np.ndarray, ...]) -> np.ndarray:
    """|zeros| (N, 3) of the cubics a3 s³ + a2 s² + a1 s + a0 (``coeffs`` = (a3, a2, a1, a0),
    arrays (N,), a3 ≠ 0): the eigenvalues of the companion matrices of the monic cubics,
    batched (first row −(a2, a1, a0)/a3, ones below the diagonal)."""
    a3, a2, a1, a0 = coeffs
    comp = np.zeros((a3.size, 3, 3))
    comp[:, 0, :] = -np.stack([a2 / a3, a1 / a3, a0 / a3], axis=1)
    comp[:, 1, 0] = comp[:, 2, 1] = 1.0
    return np.abs(np.linalg.eigvals(comp))


def _abs_x(coeffs: tuple[np.ndarray, ...], k: np.ndarray, b: np.ndarray, w: np.ndarray,
           rows: np.ndarray) -> np.ndarray:  # fmt: skip
    """|X(ω)| = ω|Num(jω)|/|k + jbω| of ``rows`` at their ω (independent of the delay)."""
    s = 1j * w[rows]
    c3, c2, c1, c0 = (x[rows] for x in coeffs)
    return np.abs(s * (((c3 * s + c2) * s + c1) * s + c0)) / np.abs(k[rows] + b[rows] * s)


def _crossing_scan(coeffs: tuple[np.ndarray, ...], k: np.ndarray, b: np.ndarray,
                   tau: np.ndarray, w_lo: np.ndarray, w_top: np.ndarray, n_lin: np.ndarray,
                   rows: np.ndarray) -> np.ndarray:  # fmt: skip
    """The smallest K_c = Re X(ω_c) > 0 over the crossings of Im X = 0 in (0, ω_top] of
    each of ``rows`` (inf where none): the grid and the refinement of
    ``stable_stiffness_batch``; ``n_lin``: each row's linear points."""
    best = np.full(rows.size, np.inf)
    if rows.size == 0:
        return best
    order = np.argsort(n_lin, kind="stable")  # chunks of like grid sizes
    c = [x[rows] for x in (*coeffs, k, b, tau)]

    def X(sel: np.ndarray, ww: np.ndarray) -> np.ndarray:
        c3, c2, c1, c0, kk, bb, tt = (x[sel] for x in c)
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

    t = np.linspace(0.0, 1.0, _LOG_POINTS)
    for a in range(0, rows.size, 256):
        sl = order[a : a + 256]
        r = rows[sl]
        lo, hi = np.log(w_lo[r]), np.log(w_top[r])
        w_log = np.exp(lo[:, None] + (hi - lo)[:, None] * t)
        w_lin = _linear(w_top[r], n_lin[sl])  # step ≤ 0.25/τ; ends repeated: no sign change
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
    return best


def _linear(w_top: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Each row's linear grid ``w_top · np.linspace(0, 1, n)[1:]`` (its values bit for bit:
    i·(1/(n − 1)), the end exactly 1), rows of fewer points padded to the most with copies of
    their end: a row's grid is its own whatever rows share the chunk (issue 40)."""
    i = np.arange(1.0, float(np.max(n)))
    step = 1.0 / (n - 1.0)
    t = np.where(i >= (n - 1.0)[:, None], 1.0, i * step[:, None])
    return w_top[:, None] * t


# ---- a bounded search over a box, vectorised over designs ------------------------------


def box_search(
    fn: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    sense: int | np.ndarray = -1,
    points: int = 5,
    zooms: int = 3,
) -> tuple[np.ndarray, np.ndarray]:
    """The smallest (``sense`` −1) or largest (+1) of ``fn`` over the box [lo, hi] of each
    design (lo, hi: (N, d)): a grid of ``points``^d (corners included), then ``zooms``
    grids of the same size centred on the best point so far, each half as wide (5 points:
    the two cells beside it; 3 points: half a cell each side), within the box. ``fn(x)``
    takes points x of shape (N, M, d) and returns (N, M); NaN counts as no value.
    ``sense``: one for every design, or (N,) of ±1, each design's own (the worst and the
    best over one box as two designs of one search: one ``fn`` call a zoom, not two).
    Returns (value (N,), argument (N, d))."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    n, d = lo.shape
    if np.ndim(sense):  # a design's values × its own ±1 (× ±1 is exact, as a scalar's)
        sense = np.asarray(sense, dtype=float).reshape(n, 1)
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
    out = -sense[:, 0] * best if np.ndim(sense) else -sense * best
    return np.where(seen, out, np.nan), arg


# ---- the worst largest stable K over a box, by the frequency of the crossing ----------


def _in_cone(z: np.ndarray, rot: tuple[np.ndarray, ...]) -> np.ndarray:
    """Whether z e^{jωτ} is real and positive for some τ ∈ [τ⁻, τ⁺] (``rot``: ``_rot``):
    as τ rises it turns counterclockwise from y⁻ = z e^{jωτ⁻} through ω(τ⁺ − τ⁻) to y⁺.
    A turn of at most π passes the positive real axis when Im y⁻ ≤ 0 ≤ Im y⁺; a turn
    of less than 2π misses it only when the rest of the circle, from y⁺ on to y⁻ (under
    π), holds it: Im y⁺ < 0 < Im y⁻; a whole turn holds every direction."""
    ea, eb, span = rot
    ya, yb = (z * ea).imag, (z * eb).imag
    return np.where(span <= np.pi, (ya <= 0) & (yb >= 0), (span >= TWO_PI) | ~((yb < 0) & (ya > 0)))


def _rot(w: np.ndarray, ta: np.ndarray, tb: np.ndarray) -> tuple[np.ndarray, ...]:
    """(e^{jωτ⁻}, e^{jωτ⁺}, ω(τ⁺ − τ⁻)): the cone of ``_in_cone`` and the rays of τ⁻, τ⁺."""
    return np.exp(1j * w * ta), np.exp(1j * w * tb), w * (tb - ta)


def _affine(w: np.ndarray, k: np.ndarray, b: np.ndarray, m2: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """(c, u, v) with G(ω) = −jω Num(jω)/(k + jbω) = c + m1 u + b1 v: Num = (m1 s + b1)T(s)
    + m2 s(bs + k), T = m2 s² + bs + k (``_num_coeffs`` regrouped), so with H = T/(k + bs)
    at s = jω: c = m2 ω², u = ω² H, v = −jω H."""
    s = 1j * w
    h = ((m2 * s + b) * s + k) / (k + b * s)
    return m2 * w * w, w * w * h, -s * h


def _family(f: int, w: np.ndarray, cuv: tuple[np.ndarray, ...], q: tuple[np.ndarray, ...]
            ) -> np.ndarray:  # fmt: skip
    """Family ``f`` of the candidate gains K_c = |G| at ω (``stable_worst_box``): 0–3 the
    corners of (m1, b1) inside the cone; 4–7 an edge's point nearest 0 inside the cone
    (τ strictly inside its range); 8–15 an edge met by the ray of τ⁻ or τ⁺. ``cuv``:
    ``_affine`` and ``_rot`` at ω; ``q``: (m1⁻, m1⁺, b1⁻, b1⁺, τ⁻, τ⁺, k, b, m2)
    broadcasting against ω; inf where no crossing."""
    c, u, v, *rot = cuv
    if f < 4:
        z = c + q[f // 2] * u + q[2 + f % 2] * v
        return np.where(_in_cone(z, rot), np.abs(z), np.inf)
    e = (f - 4) % 4 if f < 8 else (f - 8) // 2
    fixed, d = (q[e], v) if e < 2 else (q[e], u)  # m1 fixed (b1 free) or b1 fixed
    z0 = c + fixed * (u if e < 2 else v)
    pa, pb = (q[2], q[3]) if e < 2 else (q[0], q[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        if f < 8:
            p = -(z0 * np.conj(d)).real / (d * np.conj(d)).real
            z = z0 + p * d
            return np.where((p > pa) & (p < pb) & _in_cone(z, rot), np.abs(z), np.inf)
        x = rot[f % 2]
        p = -(z0 * x).imag / (d * x).imag
        r = (z0 * x).real + p * (d * x).real
        return np.where((p >= pa) & (p <= pb) & (r > 0), r, np.inf)


def _nearest(w: np.ndarray, q: tuple[np.ndarray, ...], cuv: tuple[np.ndarray, ...] = ()
             ) -> np.ndarray:  # fmt: skip
    """The least |G| over the box's (m1, b1) at ω, crossing or not: a corner or an edge's
    point nearest 0 (0 is outside: ``stable_worst_box``). ``cuv``: ``_affine`` at ω if
    already computed."""
    c, u, v = cuv[:3] if cuv else _affine(w, *q[6:])
    out = [np.abs(c + q[i] * u + q[2 + j] * v) for i in (0, 1) for j in (0, 1)]
    with np.errstate(divide="ignore", invalid="ignore"):
        for z0, d, pa, pb in (
            (c + q[0] * u, v, q[2], q[3]),
            (c + q[1] * u, v, q[2], q[3]),
            (c + q[2] * v, u, q[0], q[1]),
            (c + q[3] * v, u, q[0], q[1]),
        ):
            p = -(z0 * np.conj(d)).real / (d * np.conj(d)).real
            out.append(np.where((p > pa) & (p < pb), np.abs(z0 + p * d), np.inf))
    return np.minimum.reduce(out)


#: Families of candidate crossings (``_family``), grid minima of each refined, and zooms of
#: each refinement (9 points, each zoom a quarter as wide: ω to 2e-6 of a grid cell; a
#: window's ends are the corners' crossings, refined by Illinois).
_FAMILIES, _REFINED, _ZOOMS = 16, 3, 10
#: Where the families are scanned and refined: the least |G| there below _MARGIN × the
#: least crossing gain found so far (values between grid points may dip below both).
_MARGIN = 1.1


def stable_worst_box(lo: np.ndarray, hi: np.ndarray, k: np.ndarray, b: np.ndarray,
                     m2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The least largest stable K [N/m] over the box (m1, b1, τ) ∈ [lo, hi] (N, 3) of
    each design, from the crossings themselves rather than a search of the box.

    A design q's limit is min over its crossings ω of |G_q(ω)|, G = −jω Num(jω)/(k + jbω),
    a crossing where G e^{jωτ} is real positive (``stable_stiffness_batch``). At one ω, G
    is affine in (m1, b1) (``_affine``): the box's G is a parallelogram P(ω), the
    crossings its points inside the cone C(ω) = {r e^{−jωτ}: τ ∈ [τ⁻, τ⁺]}, and the worst
    is the least |z| over P ∩ C and over ω. |z| has no minimum inside P (0 ∉ P: Num's
    coefficients are positive and a2 a1 > a3 a0, so its zeros are in the left half-plane),
    so the least lies on P's edges: at a corner, at an edge's point nearest 0, or where a
    ray of τ⁻ or τ⁺ meets an edge (``_family``). Each is smooth in ω where it exists, and
    the ends of that are another family's points or a corner's crossing at τ⁻ or τ⁺. So
    the worst is the least of the 8 corners' ``stable_stiffness_batch`` (exact) and the
    16 families' minima over ω: each family on the grid of ``stable_stiffness_batch``
    (300 log points from 1e-4 × ω_a of the corner (m1⁻, b1⁻), a linear step 0.25/τ⁺),
    its ``_REFINED`` least grid minima refined by ``_ZOOMS`` zooms of 9 points. Every
    value found is some q's crossing gain, so never below the true worst; a minimum
    narrower than the grid can be missed (tests bound the answer against the box search
    and dense sampling).

    The scan ends at ω_top = ω_A, Cauchy's bound on Num's zeros over the box (the positive
    root of a3⁻ω³ − a2⁺ω² − a1⁺ω − a0⁺); beyond ω_A every |G_q| rises
    (``stable_stiffness_batch``), so once the least |G| over P(ω_top) exceeds the worst
    found nothing later is smaller; where it does not yet, a second scan runs to
    4 ω_A + 3 turns of τ⁺. Returns (worst (N,), done (N,)): ``done`` False
    where that bound does not hold, τ⁺ ≤ 0 or the grid would pass ``_MAX_LINEAR`` points;
    the caller searches those otherwise."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    n = lo.shape[0]
    k, b, m2 = (np.broadcast_to(np.asarray(x, float), (n,)) for x in (k, b, m2))
    q = (lo[:, 0], hi[:, 0], lo[:, 1], hi[:, 1], lo[:, 2], hi[:, 2], k, b, m2)
    m1a, m1b, b1a, b1b, tb = (*q[:4], q[5])
    best = np.full(n, np.inf)
    # Cauchy's bound ([marden1966] §27) on |zeros| of Num over the box
    w_A = _largest_zero(np.stack([m1a * m2, -(m2 * b1b + m1b * b + m2 * b),
                                  -(b1b * b + (m1b + m2) * k), -b1b * k], 1))  # fmt: skip
    # the grid's start: as stable_stiffness_batch's, below every q's quiet_below (it rises
    # with the slowest zero, at least 1/R, R Cauchy's bound on the zeros of the reversed
    # cubic over the box, and falls with τ)
    r_z = 1.0 / _largest_zero(np.stack([b1a * k, -(b1b * b + (m1b + m2) * k),
                                        -(m2 * b1b + m1b * b + m2 * b), -m1b * m2], 1))  # fmt: skip
    w_a = _largest_zero(np.stack([m1a * m2, m2 * b1a + m1a * b + m2 * b,
                                  b1a * b + (m1a + m2) * k, b1a * k], 1))  # fmt: skip
    w_lo = np.minimum(1e-4 * w_a, quiet_below(r_z, tb))
    # a scan to ω_A first; where the bound does not hold there, a longer one
    todo = np.nonzero(tb > 0)[0]
    done = np.zeros(n, dtype=bool)
    for w_top in (w_A * (1.0 + 1e-9), 4.0 * w_A + _TURNS * TWO_PI / np.where(tb > 0, tb, 1.0)):
        n_lin = np.ceil(w_top[todo] * tb[todo] / _PHASE_STEP) + 2
        todo = todo[n_lin <= _MAX_LINEAR]
        best[todo] = np.minimum(best[todo], _scan(todo, w_lo, w_top, q))
        # the bound at ω_top: the least |G| over P(ω_top) above the worst found
        ok = _nearest(w_top[todo], tuple(x[todo] for x in q)) > best[todo]
        done[todo[ok]] = True
        todo = todo[~ok]
    return best, done


def _scan(rows: np.ndarray, w_lo: np.ndarray, w_top: np.ndarray, q: tuple[np.ndarray, ...]
          ) -> np.ndarray:  # fmt: skip
    """The least of the 16 families over [ω_lo, ω_top] of each of ``rows``
    (``stable_worst_box``: grid, then zooms on each family's least grid minima)."""
    n_lin = np.ceil(w_top * q[5] / _PHASE_STEP) + 2
    t = np.linspace(0.0, 1.0, _LOG_POINTS)
    order = np.argsort(n_lin[rows], kind="stable")  # chunks of like grid sizes
    best = np.full(rows.size, np.inf)
    brackets = np.zeros((3, _FAMILIES, rows.size, _REFINED))  # (ω⁻, ω⁺, grid value)
    for a in range(0, order.size, 32):  # 32 rows a chunk: little padding to the longest
        i = order[a : a + 32]
        r = rows[i]
        g_lo, g_hi = np.log(w_lo[r]), np.log(w_top[r])
        w_log = np.exp(g_lo[:, None] + (g_hi - g_lo)[:, None] * t)
        w_lin = _linear(w_top[r], n_lin[r])  # a row's own, its end repeated to the longest
        w = np.sort(np.concatenate([w_log, w_lin], axis=1), axis=1)
        qr = tuple(x[r, None] for x in q)
        # the 8 corners' crossings: limit candidates, and with the midpoints between them
        # grid points inside every window where a corner or a ray family lives (a row
        # without a crossing: its last point once more, as alone)
        best[i], seeds = _corner_crossings(w, qr)
        own = ~np.isnan(seeds)
        own[~own.any(axis=1), 0] = True
        seeds = np.where(np.isnan(seeds), w[:, -1:], seeds)
        # each row's grid as alone (its own linear points and seeds, sorted), then +inf
        # past its end, there replaced by its last point and ``inside`` False
        lin = np.arange(w_lin.shape[1]) < (n_lin[r] - 1.0)[:, None]
        w = np.concatenate([w_log, w_lin, seeds], axis=1)
        inside = np.concatenate([np.ones(w_log.shape, bool), lin, own], axis=1)
        w = np.sort(np.where(inside, w, np.inf), axis=1)
        inside = np.arange(w.shape[1]) < np.sum(inside, axis=1)[:, None]
        L = np.sum(inside, axis=1)
        w = np.where(inside, w, w[np.arange(r.size), L - 1][:, None])
        cuv = (*_affine(w, *qr[6:]), *_rot(w, qr[4], qr[5]))
        # the families only where the least |G| over the box, crossing or not, could beat
        # the corners' crossings (with a margin of _MARGIN for the refinement between points)
        rr, ll = np.nonzero((_nearest(w, qr, cuv) < _MARGIN * best[i][:, None]) & inside)
        fam = np.full((_FAMILIES, *w.shape), np.inf)
        qa = tuple(x[rr, 0] for x in qr)
        cuv_a = tuple(x[rr, ll] for x in cuv)
        for f in range(_FAMILIES):
            fam[f, rr, ll] = _family(f, w[rr, ll], cuv_a, qa)
        # each family's _REFINED least grid minima, each bracketed by its two neighbours
        pad = np.pad(fam, ((0, 0), (0, 0), (1, 1)), constant_values=np.inf)
        low = np.where((fam <= pad[..., :-2]) & (fam <= pad[..., 2:]), fam, np.inf)
        j = _least(low)  # (F, R, 3)
        best[i] = np.minimum(best[i], np.min(low, axis=(0, 2)))
        ii = np.arange(r.size)[None, :, None]
        brackets[0][:, i] = w[ii, np.maximum(j - 1, 0)]
        brackets[1][:, i] = w[ii, np.minimum(j + 1, L[None, :, None] - 1)]
        brackets[2][:, i] = np.take_along_axis(low, j, 2)
    # the refinement of the brackets whose grid value could beat the least found, all rows
    # at once: zooms of 9 points on each
    fi, ri, mi = np.nonzero(brackets[2] < _MARGIN * best[None, :, None])
    lo_w, hi_w = brackets[0][fi, ri, mi], brackets[1][fi, ri, mi]
    qb = tuple(x[rows[ri], None] for x in q)
    groups = [np.nonzero(fi == f)[0] for f in range(_FAMILIES)]
    z9 = np.linspace(0.0, 1.0, 9)
    for _ in range(_ZOOMS):
        ww = lo_w[:, None] + (hi_w - lo_w)[:, None] * z9  # (brackets, 9)
        cuv = (*_affine(ww, *qb[6:]), *_rot(ww, qb[4], qb[5]))
        vals = np.full(ww.shape, np.inf)
        for f, g in enumerate(groups):
            if g.size:
                vals[g] = _family(f, ww[g], tuple(x[g] for x in cuv), tuple(x[g] for x in qb))
        jj = np.argmin(vals, axis=1)
        np.minimum.at(best, ri, vals[np.arange(ri.size), jj])
        wj = ww[np.arange(ri.size), jj]
        h = (hi_w - lo_w) / 8.0
        lo_w, hi_w = np.maximum(wj - h, lo_w), np.minimum(wj + h, hi_w)
    return best


def _least(low: np.ndarray) -> np.ndarray:
    """The indices (F, R, ``_REFINED``) of the ``_REFINED`` least values along the last axis,
    a tie to the lower index (``np.argmin``'s first): the same picks whatever +inf pads a
    row's end (``np.argpartition`` may pick either of two equal values)."""
    v = low.copy()
    out = np.empty((*low.shape[:2], _REFINED), dtype=np.intp)
    for n in range(_REFINED):
        out[..., n] = j = np.argmin(v, axis=2)
        np.put_along_axis(v, j[..., None], np.inf, axis=2)
    return out


def _corner_crossings(w: np.ndarray, q: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The crossings of the 4 corners (m1, b1) at τ⁻ and τ⁺ on the grid ω (R, L) of
    ``_scan`` (``q``: (R, 1) each): the sign changes of Im G e^{jωτ}, refined by Illinois
    to 1e-12 as in ``stable_stiffness_batch``. Returns (the least crossing gain Re G e^{jωτ}
    > 0 of each row (inf: none), the roots and the midpoints between them, (R, M) padded
    with NaN)."""
    c, u, v = _affine(w, *q[6:])
    rot = [np.exp(1j * w * t) for t in q[4:6]]
    parts = []
    for i, m1 in enumerate(q[:2]):
        for j, b1 in enumerate(q[2:4]):
            z = c + m1 * u + b1 * v
            for t, e in enumerate(rot):
                g = (z * e).imag
                d, col = np.nonzero(g[:, :-1] * g[:, 1:] < 0)
                parts.append((d, col, g[d, col], g[d, col + 1], np.full(d.size, 4 * i + 2 * j + t)))
    d, col, g0, g1, which = (np.concatenate(x) for x in zip(*parts, strict=True))
    m1 = np.where(which >= 4, q[1][d, 0], q[0][d, 0])
    b1 = np.where(which % 4 >= 2, q[3][d, 0], q[2][d, 0])
    tau = np.where(which % 2 == 1, q[5][d, 0], q[4][d, 0])
    kk, bb, mm = (x[d, 0] for x in q[6:])

    def at(act: np.ndarray, x: np.ndarray) -> np.ndarray:
        cc, uu, vv = _affine(x, kk[act], bb[act], mm[act])
        return (cc + m1[act] * uu + b1[act] * vv) * np.exp(1j * x * tau[act])

    root = illinois(lambda act, x: at(act, x).imag, w[d, col], w[d, col + 1], g0, g1, 1e-12)
    x = at(np.arange(d.size), root)
    ok = (x.real > 0) & (np.abs(x.imag) <= 1e-6 * np.abs(x))
    kc = np.full(w.shape[0], np.inf)
    np.minimum.at(kc, d[ok], x.real[ok])
    # the roots of each row in order, NaN-padded, and the midpoints between them
    order = np.lexsort((root, d))
    d, root = d[order], root[order]
    cnt = np.bincount(d, minlength=w.shape[0])
    pos = np.arange(d.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    roots = np.full((w.shape[0], max(int(cnt.max(initial=0)), 1)), np.nan)
    roots[d, pos] = root
    return kc, np.concatenate([roots, 0.5 * (roots[:, 1:] + roots[:, :-1])], axis=1)


def _largest_zero(c: np.ndarray) -> np.ndarray:
    """The largest |zero| of each cubic (rows of coefficients, highest first)."""
    n = c.shape[0]
    comp = np.zeros((n, 3, 3))
    comp[:, 0, :] = -c[:, 1:] / c[:, :1]
    comp[:, 1, 0] = comp[:, 2, 1] = 1.0
    return np.max(np.abs(np.linalg.eigvals(comp)), axis=1)
