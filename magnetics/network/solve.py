"""Solving the reluctance network (``magnetics.network.build``'s ladder) for its loop fluxes.

Every steel and fluid element has its material's non-linear B–H (MMF = Σ w·H(k·Φ) at Gauss
points, exact for a linear material; along a zone, where the axial flux builds up linearly,
the exact mean of H over the build-up, ``BHCurve.h_mean_dh``). Unknowns: the loop fluxes x_k
(the ladder's loops), the window's x_w, the outer air's, the end leaks' e_A, e_B, and the
sheaths' q (2m + 1). The equations are the loop MMF balances — the gradient of the network's
(convex) magnetic co-energy — so the Jacobian is symmetric positive definite: each sheath
couples to its own rung only and is condensed out element by element, leaving a tridiagonal
chain with a 3 × 3 tail, bordered by the two end leaks. Damped Newton with a backtracking
line search on the residual, each step one batched Thomas solve and a 2 × 2 Schur
complement, vectorised over designs × currents. A row that does not converge is refused
(``NetworkConvergenceError``, the rows named), never returned.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.validation import ParameterError
from magnetics.materials import MATERIALS, Magnetic, magnetic
from magnetics.network.build import Network

FloatArray = NDArray[np.float64]


class NetworkConvergenceError(ParameterError):
    """The network's Newton did not converge for some designs (they are named)."""


def _terms(mat: Magnetic, a: FloatArray, k: FloatArray, w: FloatArray, mean: bool = False):  # type: ignore[no-untyped-def]  # fmt: skip
    """w·H(k·a) and its a-derivative w·k·H'(k·a) at fluxes a ≥ 0, element by element
    (``mean``: w·H̄(k·a), a build-up kernel, ``Network``)."""
    h, dh = (mat.h_mean_dh if mean else mat.h_dh)(k * a)
    h *= w
    dh *= w
    dh *= k
    return h, dh


def _odd(mat: Magnetic, phi: FloatArray, k: FloatArray, w: FloatArray, mean: bool = False):  # type: ignore[no-untyped-def]  # fmt: skip
    """Σ_j w·H(k·Φ) over the last axis and its Φ-derivative, for Φ of any sign (H odd;
    ``mean``: build-up kernels, ``_terms``)."""
    h, dh = _terms(mat, np.abs(phi)[..., None], k, w, mean)
    return np.copysign(_rowsum(h), phi), _rowsum(dh)


def _rowsum(a: FloatArray) -> FloatArray:
    """Σ over the last axis, short (1–12 points): a sum of slices beats a strided reduce."""
    out = a[..., 0].copy()
    for j in range(1, a.shape[-1]):
        out += a[..., j]
    return out


def _each(mat: Magnetic, phi: FloatArray, k: FloatArray, w: FloatArray):  # type: ignore[no-untyped-def]
    """w·H(k·Φ) and its Φ-derivative element by element (one Gauss point each), Φ of any
    sign (H odd)."""
    h, dh = _terms(mat, np.abs(phi), k, w)
    return np.copysign(h, phi), dh


def _band(fluid: Magnetic, y: FloatArray, perm: FloatArray, area: FloatArray, length: FloatArray,
          start: FloatArray | None = None):  # type: ignore[no-untyped-def]  # fmt: skip
    """MMF F (odd in y) and dF/dy of a band element: a linear permeance ``perm`` (H) in
    parallel with ``area`` (m²) of ``fluid`` over ``length`` (m), carrying flux y.

    The two share F = l·H: |y| = perm·l·H(B) + A·B for the fluid's B, solved by Newton on
    B from above the root (the linear start B0 = |y|/(A + perm·l·H'(0)) has r ≥ 0, since
    H(B) ≥ H'(0)·B on a saturating curve), or from ``start`` (the fluid's B at the last
    Newton iterate: 1–2 steps instead of 4–6); dF/dy = l·H'/(perm·l·H' + A). Without fluid
    (A = 0) F = |y|/perm; with neither (the core's and shell's rungs) F = 0. Returns
    (F, dF/dy, the fluid's B)."""
    a = np.abs(y)
    fl = area > 0
    lp = perm * length
    s0 = fluid.h_dh(np.zeros(1))[1][0]
    b = a / np.where(fl, area + lp * s0, 1.0) if start is None else start.copy()
    safe = np.where(fl, area, 1.0)  # the elements without fluid iterate harmlessly
    for _ in range(_BAND_ITER):
        h, dh = fluid.h_dh(b)
        r = np.where(fl, lp * h + area * b - a, 0.0)
        b = np.maximum(b - r / (lp * dh + safe), 0.0)
        if np.all(np.abs(r) <= 1e-13 * a):
            break
    h, dh = fluid.h_dh(b)
    lin = np.where(perm > 0, 1.0 / np.where(perm > 0, perm, 1.0), 0.0)
    f = np.where(fl, length * h, a * lin)
    d = np.where(fl, length * dh / (lp * dh + safe), lin)
    return np.copysign(f, y), d, b


_BAND_ITER = 30


def _pair(steel: Magnetic, fluid: Magnetic, y, q, ks, ws, kf, wf, mean):  # type: ignore[no-untyped-def]
    """A wall's steel section (kernel ks, ws) in parallel with its fluid sheath (kf, wf)
    carrying y − q and q, both build-up kernels if ``mean``: (the steel's MMF, the residual
    F_fluid(q) − F_steel(y − q), the steel's slope a, a + the sheath's slope b, the pair's
    slope a·b/(a + b)). Without a sheath (wf = 0) the residual is q and the slopes (0, 1, a):
    q stays 0 and the section is the steel alone."""
    fs, a = _odd(steel, y - q, ks, ws, mean)
    ff, b = _odd(fluid, q, kf, wf, mean)
    has = wf.sum(-1) > 0
    ab = np.where(has, a + b, 1.0)
    return (fs, np.where(has, ff - fs, q), np.where(has, a, 0.0), ab,
            np.where(has, a * b / ab, a))  # fmt: skip


def _residual(net: Network, mats, x: FloatArray, ni: FloatArray, warm=None):  # type: ignore[no-untyped-def]
    """Loop MMF residuals (S, C, ``Network.unknowns``) at the loop fluxes x (films, window,
    outer air, the two end leaks, the sheaths') and the Jacobian: the chain's diagonal (…, m − 1)
    and off-diagonal (…, m − 1) for loops 0 … m − 2, the dense block (…, 3, 3) of loops
    m − 1, window, outer air, the end leaks' border (…, m + 2, 2) and block (…, 2, 2), the
    band fluid's state, and the sheaths' slopes (a, a + b) (…, 2m + 1) each.

    End leak z (zone A, B) runs from the pole to the core past the zone's far end, in
    parallel with the zone's stack of films and drum walls: film k carries x_k − e_z in
    zone z (``_end_leak``). Sheath q (wall j in zone A, B, then the core over the band)
    carries q of its rung's flux y, the wall's steel y − q (``_pair``); its loop's
    equation is F_fluid(q) = F_steel(y − q). The chain's rows hold the rungs' slopes with
    the sheaths condensed out, a·b/(a + b) (``_solve`` restores them)."""
    steel, fluid = magnetic(net.steel, mats), magnetic(net.fluid, mats)
    ex = lambda a: a[:, None]  # noqa: E731  (S, 1, …): broadcast over currents
    m = net.m
    xl, xw, xo, xe = x[..., :m], x[..., m], x[..., m + 1], x[..., net.leaks]
    q = x[..., net.sheaths]
    # each zone's films and drum walls, at the zone's film flux (…, m, 2)
    xz = np.stack([xl - xe[..., :1], xl - xe[..., 1:]], axis=-1)
    a, da = _each(fluid, xz, ex(net.fluid_k), ex(net.fluid_w))
    b, db = _each(steel, xz, ex(net.wall_k), ex(net.wall_w))
    gzz, dgzz = a + b, da + db
    gz, dgz = (gzz[..., 0], gzz[..., 1]), (dgzz[..., 0], dgzz[..., 1])
    g, dg = gz[0] + gz[1], dgz[0] + dgz[1]
    # rung fluxes, A → B: y0 = −x0 (core), y_i = x_{i−1} − x_i, y_m = x_{m−1} + x_w (shell)
    y = np.concatenate([-xl[..., :1], xl[..., :-1] - xl[..., 1:], (xl[..., -1] + xw)[..., None]],
                       axis=-1)  # fmt: skip
    f, df = np.zeros_like(y), np.zeros_like(y)
    # every wall's steel in both zones beside its fluid sheaths (rungs 0 … m − 1)
    shape = (*q.shape[:-1], m, 2)
    fs, rq, pa, pk, cond = _pair(steel, fluid, y[..., :m, None], q[..., : 2 * m].reshape(shape),
                                 ex(net.rung_k), ex(net.rung_w),
                                 ex(net.sheath_k), ex(net.sheath_w), True)  # fmt: skip
    f[..., :m] = fs[..., 0] + fs[..., 1]  # zones A and B (slices beat a reduce over 2)
    df[..., :m] = cond[..., 0] + cond[..., 1]
    # the core over the band beside half of film 0
    fc, rc, pac, pkc, dc = _pair(steel, fluid, y[..., 0], q[..., 2 * m],
                                 ex(net.core_k), ex(net.core_w),
                                 ex(net.core_sheath_k), ex(net.core_sheath_w), False)  # fmt: skip
    f[..., 0] += fc
    df[..., 0] += dc
    # the drums' bands (rungs 1 … m − 1; the shell's is its own element below)
    mid = slice(1, m)
    band = ex(net.band_len)
    fb, dfb, b_rung = _band(fluid, y[..., mid], ex(net.rung_perm[:, mid]),
                            ex(net.rung_fluid[:, mid]), band[..., None],
                            None if warm is None else warm[..., : m - 1])  # fmt: skip
    f[..., mid] += fb
    df[..., mid] += dfb
    sh, dsh = _odd(steel, y[..., m], ex(net.shell_k), ex(net.shell_w))  # the poles
    yb = y[..., m] - xo  # the back iron: the shell's flux less the outer air's
    bk, dbk = _odd(steel, yb, ex(net.back_k), ex(net.back_w))
    f[..., m] += sh + bk
    win, dwin, b_win = _band(fluid, xw, ex(net.window_perm), ex(net.window_fluid), band,
                             None if warm is None else warm[..., m - 1])  # fmt: skip
    air = net.outer_air[:, None]
    res = np.empty_like(x)
    res[..., :m] = g + f[..., 1:] - f[..., :-1]
    res[..., m - 1] -= ni
    res[..., m] = f[..., m] + win - ni
    res[..., m + 1] = air * xo - bk
    leak = ex(net.end_leak)
    res[..., net.leaks] = leak * xe - np.stack([_rowsum(gz[0]), _rowsum(gz[1])], axis=-1)
    res[..., net.sheaths] = np.concatenate([rq.reshape(*q.shape[:-1], 2 * m), rc[..., None]], -1)
    dm = df[..., m] + dsh + dbk  # dF_shell/dy_m
    diag = dg[..., : m - 1] + df[..., 1:m] + df[..., : m - 1]
    off = -df[..., 1:m]
    tail = np.empty((*x.shape[:-1], 3, 3))
    tail[..., 0, 0] = dg[..., m - 1] + dm + df[..., m - 1]
    tail[..., 0, 1] = tail[..., 1, 0] = dm
    tail[..., 1, 1] = dm + dwin
    tail[..., 0, 2] = tail[..., 2, 0] = tail[..., 1, 2] = tail[..., 2, 1] = -dbk
    tail[..., 2, 2] = air + dbk
    border = np.zeros((*x.shape[:-1], m + 2, 2))
    border[..., :m, 0], border[..., :m, 1] = -dgz[0], -dgz[1]
    corner = np.zeros((*x.shape[:-1], 2, 2))
    corner[..., 0, 0] = leak[..., 0] + _rowsum(dgz[0])
    corner[..., 1, 1] = leak[..., 1] + _rowsum(dgz[1])
    # the band fluid's B, the next call's start (``_band``), travels with the Jacobian
    state = np.concatenate([b_rung, b_win[..., None]], axis=-1)
    flat = (*q.shape[:-1], 2 * m)
    sa = np.concatenate([pa.reshape(flat), pac[..., None]], axis=-1)
    sk = np.concatenate([pk.reshape(flat), pkc[..., None]], axis=-1)
    return res, (diag, off, tail, border, corner, state, sa, sk)


def _solve(jac, rhs: FloatArray) -> FloatArray:  # type: ignore[no-untyped-def]
    """Solve J·d = rhs, J symmetric: the sheaths condensed out (each couples to its rung's
    flux only: a sheath row reads −a·dy + (a + b)·dq = r_q, so its rung's rows gain
    a·r_q/(a + b), and dq = (r_q + a·dy)/(a + b) after), then the ladder
    (``_solve_ladder``) bordered by the two end leaks, by their 2 × 2 Schur complement
    (J is SPD, so is the complement)."""
    diag, off, tail, border, corner, _, sa, sk = jac
    n = border.shape[-2]
    m = n - 2
    rq = rhs[..., n + 2 :]
    t = sa * rq / sk
    tr = t[..., : 2 * m : 2] + t[..., 1 : 2 * m : 2]  # per rung 0 … m − 1
    tr[..., 0] += t[..., 2 * m]
    rl = rhs[..., : n + 2].copy()
    rl[..., : m - 1] += tr[..., 1:] - tr[..., :-1]  # loop k: rungs k + 1 (+) and k (−)
    rl[..., m - 1] -= tr[..., m - 1]
    # the ladder's solve for the right-hand side and both border columns at once
    uv = _solve_ladder((diag, off, tail), np.concatenate([rl[..., :n, None], border], -1))
    u, v = uv[..., 0], uv[..., 1:]
    bt = np.swapaxes(border, -1, -2)
    schur = corner - bt @ v  # D − Bᵀ·A⁻¹·B, (…, 2, 2)
    re = rl[..., n:] - (bt @ u[..., None])[..., 0]
    det = schur[..., 0, 0] * schur[..., 1, 1] - schur[..., 0, 1] * schur[..., 1, 0]
    e0 = (schur[..., 1, 1] * re[..., 0] - schur[..., 0, 1] * re[..., 1]) / det
    e1 = (schur[..., 0, 0] * re[..., 1] - schur[..., 1, 0] * re[..., 0]) / det
    out = np.empty_like(rhs)
    out[..., n], out[..., n + 1] = e0, e1
    out[..., :n] = u - v[..., 0] * e0[..., None] - v[..., 1] * e1[..., None]
    d = out[..., :m]
    dy = np.concatenate([-d[..., :1], d[..., :-1] - d[..., 1:]], axis=-1)  # rungs 0 … m − 1
    dyq = np.concatenate([np.repeat(dy, 2, axis=-1), dy[..., :1]], axis=-1)
    out[..., n + 2 :] = (rq + sa * dyq) / sk
    return out


def _solve_ladder(jac, rhs: FloatArray) -> FloatArray:  # type: ignore[no-untyped-def]
    """Solve the ladder's J·D = rhs (…, n, K), J symmetric: a tridiagonal chain (loops
    0 … m − 2) ending in a dense 3 × 3 block (loop m − 1, window, outer air); Thomas down
    the chain, batched over designs, currents and the K right-hand sides."""
    diag, off, tail = jac
    n = diag.shape[-1]  # m − 1 chain rows before the block
    c = np.empty_like(off)
    d = np.empty_like(rhs[..., :n, :])
    for i in range(n):
        b = diag[..., i] - (off[..., i - 1] * c[..., i - 1] if i else 0.0)
        c[..., i] = off[..., i] / b
        prev = off[..., i - 1, None] * d[..., i - 1, :] if i else 0.0
        d[..., i, :] = (rhs[..., i, :] - prev) / b[..., None]
    blk = tail.copy()
    r = rhs[..., n:, :].copy()
    if n:
        blk[..., 0, 0] -= off[..., n - 1] * c[..., n - 1]
        r[..., 0, :] -= off[..., n - 1, None] * d[..., n - 1, :]
    out = np.empty_like(rhs)
    out[..., n:, :] = _solve3(blk, r)
    for i in range(n - 1, -1, -1):
        out[..., i, :] = d[..., i, :] - c[..., i, None] * out[..., i + 1, :]
    return out


def _solve3(m: FloatArray, r: FloatArray) -> FloatArray:
    """Solve the symmetric 3 × 3 systems m (…, 3, 3)·X = r (…, 3, K) by the adjugate
    (batched LAPACK calls on 3 × 3 blocks cost more than the arithmetic)."""
    a, b, c = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    d, e, f = m[..., 1, 1], m[..., 1, 2], m[..., 2, 2]
    ca, cb, cc = d * f - e * e, c * e - b * f, b * e - c * d
    cd, ce, cf = a * f - c * c, b * c - a * e, a * d - b * b
    inv = 1.0 / (a * ca + b * cb + c * cc)
    r0, r1, r2 = r[..., 0, :], r[..., 1, :], r[..., 2, :]
    out = np.empty_like(r)
    out[..., 0, :] = (ca[..., None] * r0 + cb[..., None] * r1 + cc[..., None] * r2) * inv[..., None]
    out[..., 1, :] = (cb[..., None] * r0 + cd[..., None] * r1 + ce[..., None] * r2) * inv[..., None]
    out[..., 2, :] = (cc[..., None] * r0 + ce[..., None] * r1 + cf[..., None] * r2) * inv[..., None]
    return out


def solve_network(
    net: Network,
    ampere_turns: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    rtol: float = 1e-10,
    max_iter: int = 60,
    start: FloatArray | None = None,
) -> FloatArray:
    """Loop fluxes (S, C, ``Network.unknowns``) (films, the window, the outer air, the end
    leaks, the sheaths) at ampere-turns (S, C).

    Damped Newton: the full step, halved until the residual's norm falls (Armijo,
    [nocedal-wright] §3.1); the Jacobian is SPD tridiagonal (co-energy Hessian). Started at
    ``start`` or by continuation in the current: the currents one after another, the
    weakest (on the block's median) from the linear network's solution (initial
    permeabilities), each next one from the last one's solution, so each (design, current)
    iterates only as long as it needs (a joint solve of all currents iterates every current
    until the design's slowest settles: 1.6× the Newton work, docs/magnetics.md); a row
    that does not converge from the continuation start is retried from the linear one.
    Solved in blocks of ``_BLOCK`` designs (cache-sized temporaries: 2× faster at 10⁴
    designs); designs that do not converge are refused together."""
    mats = MATERIALS if materials is None else materials
    ni = np.atleast_2d(np.asarray(ampere_turns, dtype=float))
    ni = np.broadcast_to(ni, (net.turns.size, ni.shape[-1])).copy()
    if not np.all(np.isfinite(ni)):
        raise ParameterError("current: must be finite")
    shape = (*ni.shape, net.unknowns)
    x0 = None if start is None else np.broadcast_to(np.asarray(start, dtype=float), shape)
    out = np.zeros(shape)
    failed: set[int] = set()
    for lo in range(0, shape[0], _BLOCK):
        blk = slice(lo, lo + _BLOCK)
        part = net if shape[0] <= _BLOCK else _take(net, blk)
        nb = ni[blk]
        prev = None
        for c in np.argsort(np.median(np.abs(nb), axis=0), kind="stable"):
            col = slice(c, c + 1)
            first = prev if x0 is None else x0[blk, col]
            x, bad = _newton(part, nb[:, col], mats, rtol, max_iter, first)
            if bad.size and x0 is None and prev is not None:  # again from the linear start
                x[bad], bad2 = _newton(_take(part, bad), nb[bad, col], mats, rtol, max_iter,
                                       None)  # fmt: skip
                bad = bad[bad2]
            out[blk, col] = prev = x
            failed.update((lo + bad).tolist())
    if failed:
        rows = sorted(failed)
        raise NetworkConvergenceError(
            f"network: no convergence in {max_iter} Newton steps for {len(rows)} design(s) "
            f"(rows {rows[:5]}…); refusing their torque"
        )
    return out


_BLOCK = 2048  # designs per Newton block (one current at a time)
_FLOOR = 1e-8  # relative residual accepted when the line search finds no decrease


def _take(net: Network, rows: slice | NDArray[np.bool_] | NDArray[np.intp]) -> Network:
    """The designs ``rows`` of ``net`` (a slice, a mask or indices)."""
    return replace(net, **{f.name: getattr(net, f.name)[rows] for f in fields(net)
                           if isinstance(getattr(net, f.name), np.ndarray)})  # fmt: skip


def _newton(net, ni, mats, rtol, max_iter, start):  # type: ignore[no-untyped-def]
    """``solve_network`` on one block: (loop fluxes, indices of the rows not converged)."""
    shape = (*ni.shape, net.unknowns)
    if start is None:
        r0, j0 = _residual(net, mats, np.zeros(shape), ni)
        x = _solve(j0, -r0)
    else:
        x = start.copy()
    out = x.copy()
    rows = np.arange(shape[0])
    scale = np.maximum(np.abs(ni), 1e-300)[..., None]
    if x.size == 0:  # no design (or no current): nothing to solve
        return out, rows[:0]
    res, jac = _residual(net, mats, x, ni)
    stalled = np.zeros(ni.shape, bool)  # the last step moved x by ≤ rtol (rounding floor)
    for _ in range(max_iter):
        err = np.max(np.abs(res) / scale, axis=-1)  # (S', C)
        settled = (err <= rtol) | stalled
        done = settled.all(axis=1)
        if done.any():
            out[rows[done]] = x[done]
            keep = ~done
            rows, x, ni, scale = rows[keep], x[keep], ni[keep], scale[keep]
            net = _take(net, keep)  # the rest iterate on their own designs only
            res, jac, settled = res[keep], tuple(a[keep] for a in jac), settled[keep]
            err = err[keep]
            if rows.size == 0:
                return out, rows
        step = _solve(jac, -res)
        norm0 = np.sum((res / scale) ** 2, axis=-1)
        # a current already settled, of a design still iterating, stays where it is: its
        # residual is noise at the rounding floor that no step would lower
        t = np.where(settled, 0.0, 1.0)
        for _ls in range(30):
            xn = x + t[..., None] * step
            rn, jn = _residual(net, mats, xn, ni, jac[5])
            better = settled | (np.sum((rn / scale) ** 2, axis=-1) <= (1 - 1e-4 * t) * norm0)
            if better.all():
                break
            t = np.where(better, t, 0.5 * t)
        # At the rounding floor the residual is noise: the full Newton correction is then
        # negligible against x, or (ill-conditioned, e.g. near-open leakage paths) no step
        # along a descent direction lowers the residual. Either is the answer to working
        # precision — the latter only once the residual is already below _FLOOR.
        small = np.max(np.abs(step), axis=-1) <= rtol * np.max(np.abs(x), axis=-1)
        stalled = settled | small | (~better & (err <= _FLOOR))
        x, res, jac = xn, rn, jn
    return out, rows


def flux_linkage(
    net: Network, ampere_turns: ArrayLike, materials: Mapping[str, Magnetic] | None = None
) -> tuple[FloatArray, FloatArray]:
    """(λ [Wb], L_inc = dλ/dI [H]) of the coil at ampere-turns (S, C).

    The coil's N·I drives the loops through the shell (loop m − 1 and the window), so the
    co-energy's derivative is λ = ∂W'/∂I = N·(x_{m−1} + x_w) (the network's loop fluxes at
    the solution). Its derivative follows from the solution's tangent: J·dx/dI = N·s with
    s the loops' source pattern, so L_inc = N²·sᵀJ⁻¹s, one more solve with the Jacobian
    at the solution (SPD, so L_inc > 0)."""
    mats = MATERIALS if materials is None else materials
    x = solve_network(net, ampere_turns, mats)
    ni = np.broadcast_to(np.atleast_2d(np.asarray(ampere_turns, dtype=float)), x.shape[:-1])
    m = net.m
    n = net.turns[:, None]
    source = np.zeros(x.shape)
    source[..., m - 1] = source[..., m] = 1.0
    lam, ind = np.zeros(x.shape[:-1]), np.zeros(x.shape[:-1])
    for lo in range(0, x.shape[0], _BLOCK):  # the blocks solve_network used
        blk = slice(lo, lo + _BLOCK)
        part = net if x.shape[0] <= _BLOCK else _take(net, blk)
        _, jac = _residual(part, mats, x[blk], np.ascontiguousarray(ni[blk]))
        v = _solve(jac, source[blk])
        lam[blk] = n[blk] * (x[blk, ..., m - 1] + x[blk, ..., m])
        ind[blk] = n[blk] ** 2 * (v[..., m - 1] + v[..., m])
    return lam, ind
