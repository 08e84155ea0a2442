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
    for i in np.nonzero(exact)[0]:
        out[i] = max_stable_stiffness(
            HapticParams(
                *(f[x][i] for x in ("m1", "b1", "k", "b", "m2")),
                delay=f["delay"][i],
                sample_period=f["sample_period"][i],
            )
        )
    return out.reshape(shape)


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
        m = int(np.max(n_lin[sl]))
        lo, hi = np.log(w_lo[r]), np.log(w_top[r])
        w_log = np.exp(lo[:, None] + (hi - lo)[:, None] * t)
        w_lin = w_top[r, None] * np.linspace(0.0, 1.0, m)[1:]  # step ≤ 0.25/τ
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
