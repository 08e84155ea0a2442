"""The reluctance network's kernels (``magnetics.network.solve``'s Newton), as plain Python:
the residual of the loop MMF balances, its Jacobian, the Newton step (a Thomas solve of the
tridiagonal chain with its 3 × 3 tail, bordered by the two end leaks) and the whole damped
Newton with its line search, one design and current at a time; and the layout they read
(``_pack``: the network's arrays one row per design; ``_tables``: each material's H(B) as a
piecewise-linear table). ``magnetics.network.compiled`` compiles these same functions with
numba (the network's only solver: one implementation, compiled or run as Python).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from magnetics.materials import MU0, LinearMaterial, Magnetic
from magnetics.network.build import Network

FloatArray = NDArray[np.float64]

_FLOOR = 1e-8  # relative residual accepted when the line search finds no decrease
_LINE_STEPS = 30  # step halvings in the line search
_BAND_ITER = 30  # Newton steps of a band element's inner solve

# The network's per-design arrays, packed in this order one row per design (``_pack``); the
# kernels read field F of design s at P[s, off[F] + j], j the field's flattened index.
_PACKED = ("fluid_k", "fluid_w", "wall_k", "wall_w", "rung_k", "rung_w", "sheath_k",
           "sheath_w", "rung_perm", "rung_fluid", "core_k", "core_w", "core_sheath_k",
           "core_sheath_w", "shell_k", "shell_w", "back_k", "back_w", "window_perm",
           "window_fluid", "band_len", "outer_air", "end_leak")  # fmt: skip
(_FK, _FW, _WK, _WW, _RK, _RW, _SK, _SW, _RP, _RF, _CK, _CW, _CSK, _CSW, _HK, _HW, _BK, _BW,
 _WP, _WF, _BL, _AIR, _LEAK) = range(len(_PACKED))  # fmt: skip
# the materials' rows in the tables (``_tables``): the drums' steel, the fluid, the core's
# and the shell's steel (the same curve thrice when one steel is chosen for all)
_STEEL, _FLUID, _CORE, _SHELL = 0, 1, 2, 3


def _pack(net: Network) -> tuple[FloatArray, NDArray[np.int64]]:
    """(P (S, L), off): the ``_PACKED`` fields of ``net``, one row per design."""
    size = net.turns.size
    cols = [np.asarray(getattr(net, name), dtype=float).reshape(size, -1) for name in _PACKED]
    off = np.concatenate([[0], np.cumsum([c.shape[1] for c in cols])[:-1]]).astype(np.int64)
    return np.ascontiguousarray(np.concatenate(cols, axis=1)), off


def _tables(
    steel: Magnetic, fluid: Magnetic, core: Magnetic | None = None, shell: Magnetic | None = None
) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """(T (4, N, 3), 1/step (4,), segments (4,)): the drums' steel's, the fluid's, the core's
    and the shell's H(B) (``core``, ``shell``: the drums' steel if None) as the
    piecewise-linear curve on a uniform grid that ``BHCurve.h_dh`` indexes (per segment i:
    slope, H = icpt + slope·B, ∫0^B H = gcpt + icpt·B + slope·B²/2); a linear material is
    one segment of slope 1/μ through the origin (1/step 0: every B is in it)."""
    rows = []
    for mat in (steel, fluid, steel if core is None else core, steel if shell is None else shell):
        if isinstance(mat, LinearMaterial):
            nu = 1.0 / (MU0 * mat.mu_r)  # H = B/μ, as LinearMaterial.h_dh
            rows.append((0.0, np.array([nu]), np.zeros(1), np.zeros(1)))
        else:
            rows.append((mat._inv_step, mat._slope, mat._icpt, mat._gcpt))
    n = max(r[1].size for r in rows)
    table = np.zeros((4, n, 3))  # a segment's three numbers side by side (one cache line)
    for i, (_, slope, icpt, gcpt) in enumerate(rows):
        table[i, : slope.size, 0], table[i, : slope.size, 1] = slope, icpt
        table[i, : slope.size, 2] = gcpt
    inv = np.array([r[0] for r in rows], dtype=float)
    return table, inv, np.array([r[1].size for r in rows], dtype=np.int64)


# ---- the kernels: plain Python, compiled by ``compiled._kernels``--------------------------
# x of one design and current: x[:m] loops, x[m] window, x[m + 1] outer air, x[m + 2 : m + 4]
# end leaks, x[m + 4 :] sheaths (wall j in zone z at 2j + z, the core over the band at 2m).
# The Jacobian of one row, flat (``_jac_layout``): the chain's diagonal (m − 1) and
# off-diagonal (m − 1), the 3 × 3 tail (row-major), the border (m + 2) × 2, the corner 2 × 2,
# the band fluid's B (m: the drums' bands, the window), the sheaths' slopes a and a + b
# (2m + 1 each).


def _jac_layout(m):  # type: ignore[no-untyped-def]
    """Offsets of (off-diagonal, tail, border, corner, band state, sa, sk) and the length."""
    o_off = m - 1
    o_tail = 2 * m - 2
    o_border = o_tail + 9
    o_corner = o_border + 2 * (m + 2)
    o_state = o_corner + 4
    o_sa = o_state + m
    o_sk = o_sa + 2 * m + 1
    return o_off, o_tail, o_border, o_corner, o_state, o_sa, o_sk, o_sk + 2 * m + 1


def _segment(inv, nseg, mat, b):  # type: ignore[no-untyped-def]
    """The segment of material ``mat``'s B–H table that holds B ≥ 0 (the last one past
    the table's end)."""
    t = b * inv[mat]
    top = nseg[mat] - 1
    if t > top:
        t = top
    return int(t)


def _h_dh(tab, inv, nseg, mat, b):  # type: ignore[no-untyped-def]
    """(H, dH/dB) of material ``mat`` at B ≥ 0 (``BHCurve.h_dh``: the segment's line)."""
    i = _segment(inv, nseg, mat, b)
    s = tab[mat, i, 0]
    return tab[mat, i, 1] + s * b, s


def _h_mean_dh(tab, inv, nseg, mat, b):  # type: ignore[no-untyped-def]
    """(H̄, dH̄/dB), H̄(B) = (1/B)·∫0^B H, at B ≥ 0 (``BHCurve.h_mean_dh``)."""
    i = _segment(inv, nseg, mat, b)
    s = tab[mat, i, 0]
    bb = max(b, 1e-300)
    g = tab[mat, i, 2] / bb
    h = tab[mat, i, 1] + g
    s2 = 0.5 * s
    h = h + s2 * b
    return h, s2 - g / bb


def _odd(tab, inv, nseg, mat, phi, k, w, mean):  # type: ignore[no-untyped-def]
    """w·H(k·|Φ|)·sign(Φ) and its Φ-derivative w·k·H'(k·|Φ|), one Gauss point (``mean``:
    a build-up kernel, w·H̄(k·|Φ|), ``Network``)."""
    a = abs(phi)
    if mean:
        h, dh = _h_mean_dh(tab, inv, nseg, mat, k * a)
    else:
        h, dh = _h_dh(tab, inv, nseg, mat, k * a)
    return math.copysign(h * w, phi), dh * w * k


def _pair(tab, inv, nseg, smat, y, q, ks, ws, kf, wf, mean):  # type: ignore[no-untyped-def]
    """A wall's steel section (material row ``smat``, kernel ks, ws) in parallel with its
    fluid sheath (kf, wf)
    carrying y − q and q: (the steel's MMF, the residual F_fluid(q) − F_steel(y − q), the
    steel's slope a, a + the sheath's slope b, the pair's slope a·b/(a + b)). Without a
    sheath (wf = 0) the residual is q and the slopes (0, 1, a): q stays 0, the steel alone."""
    fs, a = _odd(tab, inv, nseg, smat, y - q, ks, ws, mean)
    ff, b = _odd(tab, inv, nseg, 1, q, kf, wf, mean)
    if wf > 0:
        ab = a + b
        return fs, ff - fs, a, ab, a * b / ab
    return fs, q, 0.0, 1.0, a


def _band(tab, inv, nseg, y, perm, area, length, start, warm):  # type: ignore[no-untyped-def]
    """MMF F (odd in y) and dF/dy of a band element: a linear permeance ``perm`` (H) in
    parallel with ``area`` (m²) of fluid over ``length`` (m), carrying flux y.

    The two share F = l·H: |y| = perm·l·H(B) + A·B for the fluid's B, solved by Newton on
    B from above the root (the linear start B0 = |y|/(A + perm·l·H'(0)) has r ≥ 0, since
    H(B) ≥ H'(0)·B on a saturating curve), or from ``start`` if ``warm`` (the fluid's B at
    the last Newton iterate: 1–2 steps instead of 4–6); dF/dy = l·H'/(perm·l·H' + A).
    Without fluid (A = 0) F = |y|/perm; with neither (the core's and shell's rungs) F = 0.
    Returns (F, dF/dy, the fluid's B)."""
    a = abs(y)
    fl = area > 0
    lp = perm * length
    safe = area if fl else 1.0  # the elements without fluid iterate harmlessly
    if warm:
        b = start
    else:
        b = a / ((area + lp * tab[1, 0, 0]) if fl else 1.0)  # H'(0): the first segment's
    for _ in range(_BAND_ITER):
        h, dh = _h_dh(tab, inv, nseg, 1, b)
        r = (lp * h + area * b - a) if fl else 0.0
        b = max(b - r / (lp * dh + safe), 0.0)
        if abs(r) <= 1e-13 * a:
            break
    h, dh = _h_dh(tab, inv, nseg, 1, b)
    lin = 1.0 / perm if perm > 0 else 0.0
    if fl:
        return math.copysign(length * h, y), length * dh / (lp * dh + safe), b
    return math.copysign(a * lin, y), lin, b


def _residual(p, off, m, npole, tab, inv, nseg, x, ni, jw, warm, res, jac, work):  # type: ignore[no-untyped-def]
    """Loop MMF residuals ``res`` of one design and current at the loop fluxes x, and its
    Jacobian ``jac`` (``_jac_layout``); the bands' Newton starts from ``jw``'s band state if
    ``warm``. ``work`` (≥ 5 rows of m + 1): scratch.

    End leak z (zone A, B) runs from the pole to the core past the zone's far end, in
    parallel with the zone's stack of films and drum walls: film k carries x_k − e_z in
    zone z (``build._end_leak``). Sheath q (wall j in zone A, B, then the core over the
    band) carries q of its rung's flux y, the wall's steel y − q (``_pair``); its loop's
    equation is F_fluid(q) = F_steel(y − q). The chain's rows hold the rungs' slopes with
    the sheaths condensed out, a·b/(a + b) (``_solve`` restores them)."""
    o_off, o_tail, o_border, o_corner, o_state, o_sa, o_sk, _ = _jac_layout(m)
    y, f, df, g, dg = work[0], work[1], work[2], work[3], work[4]
    xw, xo, e0, e1 = x[m], x[m + 1], x[m + 2], x[m + 3]
    # each zone's film and drum wall at the zone's film flux; their sums over the stack
    sg0, sg1, sdg0, sdg1 = 0.0, 0.0, 0.0, 0.0
    for k in range(m):
        wm = 2 if k == 0 else 0  # film 0's inner wall is the core
        z0 = x[k] - e0
        a, da = _odd(tab, inv, nseg, 1, z0, p[off[_FK] + 2 * k], p[off[_FW] + 2 * k], False)
        b, db = _odd(tab, inv, nseg, wm, z0, p[off[_WK] + 2 * k], p[off[_WW] + 2 * k], False)
        z1 = x[k] - e1
        a1, da1 = _odd(tab, inv, nseg, 1, z1, p[off[_FK] + 2 * k + 1], p[off[_FW] + 2 * k + 1],
                       False)  # fmt: skip
        b1, db1 = _odd(tab, inv, nseg, wm, z1, p[off[_WK] + 2 * k + 1], p[off[_WW] + 2 * k + 1],
                       False)  # fmt: skip
        g0, g1, dg0, dg1 = a + b, a1 + b1, da + db, da1 + db1
        g[k], dg[k] = g0 + g1, dg0 + dg1
        jac[o_border + 2 * k], jac[o_border + 2 * k + 1] = -dg0, -dg1
        sg0 += g0
        sg1 += g1
        sdg0 += dg0
        sdg1 += dg1
    for i in range(2 * m, 2 * m + 4):  # the leaks' own rows of the border
        jac[o_border + i] = 0.0
    # rung fluxes, A → B: y0 = −x0 (core), y_i = x_{i−1} − x_i, y_m = x_{m−1} + x_w (shell)
    y[0] = -x[0]
    for i in range(1, m):
        y[i] = x[i - 1] - x[i]
    y[m] = x[m - 1] + xw
    # every wall's steel in both zones beside its fluid sheaths (rungs 0 … m − 1)
    for j in range(m):
        fj, dfj = 0.0, 0.0
        for z in range(2):
            i = 2 * j + z
            fs, rq, pa, pk, cond = _pair(tab, inv, nseg, 2 if j == 0 else 0, y[j],
                                         x[m + 4 + i], p[off[_RK] + i],
                                         p[off[_RW] + i], p[off[_SK] + i], p[off[_SW] + i],
                                         True)  # fmt: skip
            fj += fs
            dfj += cond
            res[m + 4 + i], jac[o_sa + i], jac[o_sk + i] = rq, pa, pk
        f[j], df[j] = fj, dfj
    # the core over the band beside half of film 0
    fc, rc, pac, pkc, dc = _pair(tab, inv, nseg, 2, y[0], x[3 * m + 4], p[off[_CK]], p[off[_CW]],
                                 p[off[_CSK]], p[off[_CSW]], False)  # fmt: skip
    f[0] += fc
    df[0] += dc
    res[3 * m + 4], jac[o_sa + 2 * m], jac[o_sk + 2 * m] = rc, pac, pkc
    # the drums' bands (rungs 1 … m − 1; the shell's is its window below)
    band = p[off[_BL]]
    for j in range(1, m):
        fb, dfb, bs = _band(tab, inv, nseg, y[j], p[off[_RP] + j], p[off[_RF] + j], band,
                            jw[o_state + j - 1], warm)  # fmt: skip
        f[j] += fb
        df[j] += dfb
        jac[o_state + j - 1] = bs
    sh, dsh = 0.0, 0.0  # the poles, radially (Gauss points in ln r)
    for j in range(npole):
        h, dh = _odd(tab, inv, nseg, 3, y[m], p[off[_HK] + j], p[off[_HW] + j], False)
        sh += h
        dsh += dh
    yb = y[m] - xo  # the back iron: the shell's flux less the outer air's
    bk, dbk = _odd(tab, inv, nseg, 3, yb, p[off[_BK]], p[off[_BW]], False)
    f[m] = sh + bk
    win, dwin, bw = _band(tab, inv, nseg, xw, p[off[_WP]], p[off[_WF]], band,
                          jw[o_state + m - 1], warm)  # fmt: skip
    jac[o_state + m - 1] = bw
    air = p[off[_AIR]]
    for k in range(m):
        res[k] = g[k] + f[k + 1] - f[k]
    res[m - 1] -= ni
    res[m] = f[m] + win - ni
    res[m + 1] = air * xo - bk
    leak0, leak1 = p[off[_LEAK]], p[off[_LEAK] + 1]
    res[m + 2] = leak0 * e0 - sg0
    res[m + 3] = leak1 * e1 - sg1
    dm = dsh + dbk  # dF_shell/dy_m
    for i in range(m - 1):
        jac[i] = dg[i] + df[i + 1] + df[i]
        jac[o_off + i] = -df[i + 1]
    jac[o_tail] = dg[m - 1] + dm + df[m - 1]
    jac[o_tail + 1] = jac[o_tail + 3] = dm
    jac[o_tail + 4] = dm + dwin
    jac[o_tail + 2] = jac[o_tail + 6] = jac[o_tail + 5] = jac[o_tail + 7] = -dbk
    jac[o_tail + 8] = air + dbk
    jac[o_corner], jac[o_corner + 1] = leak0 + sdg0, 0.0
    jac[o_corner + 2], jac[o_corner + 3] = 0.0, leak1 + sdg1


def _solve(m, jac, rhs, out, work):  # type: ignore[no-untyped-def]
    """Solve J·d = rhs into ``out``, J symmetric: the sheaths condensed out (each couples to
    its rung's flux only: a sheath row reads −a·dy + (a + b)·dq = r_q, so its rung's rows
    gain a·r_q/(a + b), and dq = (r_q + a·dy)/(a + b) after), then the ladder
    (``_solve_ladder``) bordered by the two end leaks, by their 2 × 2 Schur complement
    (J is SPD, so is the complement). ``work`` (≥ 3 + 3 + 2 rows of m + 2): scratch."""
    o_off, o_tail, o_border, o_corner, _, o_sa, o_sk, _ = _jac_layout(m)
    n = m + 2
    q0 = n + 2  # the sheaths' first row
    u = work[0:3]  # the ladder's right-hand sides: the loops' rows, then the border's columns
    tr = work[6]
    rl = work[7]
    for j in range(m):
        i = 2 * j
        tr[j] = (jac[o_sa + i] * rhs[q0 + i] / jac[o_sk + i]
                 + jac[o_sa + i + 1] * rhs[q0 + i + 1] / jac[o_sk + i + 1])  # fmt: skip
    tr[0] += jac[o_sa + 2 * m] * rhs[q0 + 2 * m] / jac[o_sk + 2 * m]
    for i in range(n + 2):
        rl[i] = rhs[i]
    for i in range(m - 1):  # loop i: rungs i + 1 (+) and i (−)
        rl[i] += tr[i + 1] - tr[i]
    rl[m - 1] -= tr[m - 1]
    for i in range(n):
        u[0, i] = rl[i]
        u[1, i] = jac[o_border + 2 * i]
        u[2, i] = jac[o_border + 2 * i + 1]
    _solve_ladder(m, jac, o_off, o_tail, u, work[3:6])
    s00, s01, s10, s11, r0, r1 = jac[o_corner], jac[o_corner + 1], jac[o_corner + 2], \
        jac[o_corner + 3], rl[n], rl[n + 1]  # fmt: skip
    for i in range(n):  # D − Bᵀ·A⁻¹·B and its right-hand side
        b0, b1 = jac[o_border + 2 * i], jac[o_border + 2 * i + 1]
        s00 -= b0 * u[1, i]
        s01 -= b0 * u[2, i]
        s10 -= b1 * u[1, i]
        s11 -= b1 * u[2, i]
        r0 -= b0 * u[0, i]
        r1 -= b1 * u[0, i]
    det = s00 * s11 - s01 * s10
    e0 = (s11 * r0 - s01 * r1) / det
    e1 = (s00 * r1 - s10 * r0) / det
    out[n], out[n + 1] = e0, e1
    for i in range(n):
        out[i] = u[0, i] - u[1, i] * e0 - u[2, i] * e1
    for j in range(m):  # the sheaths back from their rungs' dy
        dy = -out[0] if j == 0 else out[j - 1] - out[j]
        for z in range(2):
            i = 2 * j + z
            out[q0 + i] = (rhs[q0 + i] + jac[o_sa + i] * dy) / jac[o_sk + i]
    i = 2 * m
    out[q0 + i] = (rhs[q0 + i] + jac[o_sa + i] * -out[0]) / jac[o_sk + i]


def _solve_ladder(m, jac, o_off, o_tail, u, work):  # type: ignore[no-untyped-def]
    """Solve the ladder's J·X = U in place, U (3, m + 2): three right-hand sides, J
    symmetric: a tridiagonal chain (loops 0 … m − 2) ending in a dense 3 × 3 block (loop
    m − 1, window, outer air). Thomas down the chain, the block by its adjugate."""
    n = m - 1  # chain rows before the block
    c = work[0]
    for i in range(n):
        b = jac[i] - (jac[o_off + i - 1] * c[i - 1] if i else 0.0)
        c[i] = jac[o_off + i] / b
        for r in range(3):
            prev = jac[o_off + i - 1] * u[r, i - 1] if i else 0.0
            u[r, i] = (u[r, i] - prev) / b
    a, bb, cc = jac[o_tail], jac[o_tail + 1], jac[o_tail + 2]
    d, e, f = jac[o_tail + 4], jac[o_tail + 5], jac[o_tail + 8]
    if n:
        a -= jac[o_off + n - 1] * c[n - 1]
        for r in range(3):
            u[r, n] -= jac[o_off + n - 1] * u[r, n - 1]
    # the symmetric 3 × 3 block by its adjugate
    ca, cb, c3 = d * f - e * e, cc * e - bb * f, bb * e - cc * d
    cd, ce, cf = a * f - cc * cc, bb * cc - a * e, a * d - bb * bb
    det = 1.0 / (a * ca + bb * cb + cc * c3)
    for r in range(3):
        r0, r1, r2 = u[r, n], u[r, n + 1], u[r, n + 2]
        u[r, n] = (ca * r0 + cb * r1 + c3 * r2) * det
        u[r, n + 1] = (cb * r0 + cd * r1 + ce * r2) * det
        u[r, n + 2] = (c3 * r0 + ce * r1 + cf * r2) * det
    for i in range(n - 1, -1, -1):
        for r in range(3):
            u[r, i] -= c[i] * u[r, i + 1]


def _newton(p, off, m, npole, tab, inv, nseg, ni, start, warm_start, gain, rtol, max_iter,
            x_out, ws):  # type: ignore[no-untyped-def]  # fmt: skip
    """Damped Newton on one design at ampere-turns ``ni``, from ``start`` if
    ``warm_start``, else from the linear network's solution times ``gain`` (1: as is; the
    circuit's saturation Φ/Φ_linear at that current puts a saturated design's start near
    its answer: ~5 Newton steps instead of ~8); the answer in ``x_out``.
    (True if it converged, the workspace's row that holds the Jacobian at the answer).
    ``ws``: the workspace (``_workspace``)."""
    nx = 3 * m + 5
    x, xn, step, res, rn = ws[0], ws[1], ws[2], ws[3], ws[4]
    jac, jn, work = ws[5], ws[6], ws[7:15]
    jrow, jnrow = 5, 6
    if warm_start:
        for i in range(nx):
            x[i] = start[i]
    else:  # the linear start: one Newton step from 0
        for i in range(nx):
            xn[i] = 0.0
        _residual(p, off, m, npole, tab, inv, nseg, xn, ni, jac, False, res, jac, work)
        for i in range(nx):
            rn[i] = -res[i]
        _solve(m, jac, rn, x, work)
        if gain != 1.0:
            for i in range(nx):
                x[i] *= gain
    scale = max(abs(ni), 1e-300)
    _residual(p, off, m, npole, tab, inv, nseg, x, ni, jac, False, res, jac, work)
    stalled = False
    for _ in range(max_iter):
        err, norm0, big_x = 0.0, 0.0, 0.0
        for i in range(nx):
            r = res[i] / scale
            err = max(err, abs(r))
            norm0 += r * r
            big_x = max(big_x, abs(x[i]))
        if err <= rtol or stalled:
            for i in range(nx):
                x_out[i] = x[i]
            return True, jrow
        for i in range(nx):
            rn[i] = -res[i]
        _solve(m, jac, rn, step, work)
        t = 1.0
        better = False
        for _ls in range(_LINE_STEPS):
            for i in range(nx):
                xn[i] = x[i] + t * step[i]
            _residual(p, off, m, npole, tab, inv, nseg, xn, ni, jac, True, rn, jn, work)
            norm = 0.0
            for i in range(nx):
                r = rn[i] / scale
                norm += r * r
            better = norm <= (1 - 1e-4 * t) * norm0
            if better:
                break
            t *= 0.5
        # At the rounding floor the residual is noise: the full Newton correction is then
        # negligible against x, or (ill-conditioned, e.g. near-open leakage paths) no step
        # along a descent direction lowers the residual. Either is the answer to working
        # precision — the latter only once the residual is already below _FLOOR.
        big_step = 0.0
        for i in range(nx):
            big_step = max(big_step, abs(step[i]))
        stalled = big_step <= rtol * big_x or (not better and err <= _FLOOR)
        x, xn = xn, x
        res, rn = rn, res
        jac, jn = jn, jac
        jrow, jnrow = jnrow, jrow
    return False, jrow


def _workspace(m: int) -> FloatArray:
    """Scratch rows for ``_newton`` (x, trial x, step, two residuals, two Jacobians, and
    the residual's and the solve's work rows, the continuation's source and predicted start),
    each long enough for any of them. Allocated by the caller, not in a compiled kernel: the
    kernels then allocate nothing and compile without numba's reference counting (NRT),
    ≈ 20 % less code to compile (``compiled._kernels``)."""
    return np.zeros((7 + 8 + 2, max(_jac_layout(m)[-1], 3 * m + 5)))


def _solve_rows(pk, off, m, npole, tab, inv, nseg, ni, order, start, has_start, gain, rtol,
                max_iter, out, ok, ws):  # type: ignore[no-untyped-def]  # fmt: skip
    """``solve_network``'s kernel: every design s, its currents in ``order[s]``, each Newton
    started from ``start`` (if ``has_start``) or by continuation from the last current's
    solution, the first (and a continuation that fails) from the linear network's times
    ``gain[s, c]`` (``gain`` (S, C), or empty: 1), retried as is if that start fails; the
    loop fluxes in ``out`` (S, C, 3m + 5), ``ok[s]`` False where one did not converge.
    ``ws``: the caller's workspace (``_workspace``)."""
    src, guess = ws[15], ws[16]
    for i in range(src.size):
        src[i] = 0.0
    src[m - 1] = src[m] = 1.0  # the coil's ampere-turns drive loop m − 1 and the window
    for s in range(pk.shape[0]):
        p = pk[s]
        prev, jrow = -1, 5
        for ci in range(ni.shape[1]):
            c = order[s, ci]
            # from ``start``, or the continuation's predicted start, or the linear one × g
            g = 1.0 if has_start or not gain.size else gain[s, c]
            warm = has_start or prev >= 0
            x0 = start[s, c] if has_start else guess
            if warm and not has_start:  # Euler predictor: x + (dx/dNI)·ΔNI, J·dx/dNI = s
                _solve(m, ws[jrow], src, guess, ws[7:15])  # at the last answer
                step = ni[s, c] - ni[s, prev]
                for i in range(3 * m + 5):
                    guess[i] = out[s, prev, i] + guess[i] * step
            # one call of the Newton (compiled inline, ``compiled._INLINE``): a failed
            # continuation or scaled start again from the linear start, as is
            for _ in range(2):
                conv, jrow = _newton(p, off, m, npole, tab, inv, nseg, ni[s, c], x0, warm, g,
                                     rtol, max_iter, out[s, c], ws)  # fmt: skip
                if conv or has_start or not (warm or g != 1.0):
                    break
                warm, g = False, 1.0
            if not conv:
                ok[s] = False
            prev = c


def _tangent_rows(pk, off, m, npole, tab, inv, nseg, x, ni, source, v, ws):  # type: ignore[no-untyped-def]
    """``flux_linkage``'s kernel: v = J⁻¹·source at the loop fluxes x (S, C, 3m + 5), ``ws``
    the caller's workspace (``_workspace``)."""
    res, jac, work = ws[3], ws[5], ws[7:15]
    for s in range(pk.shape[0]):
        for c in range(x.shape[1]):
            _residual(pk[s], off, m, npole, tab, inv, nseg, x[s, c], ni[s, c], jac, False, res,
                      jac, work)  # fmt: skip
            _solve(m, jac, source, v[s, c], work)


_KERNELS = ("_jac_layout", "_segment", "_h_dh", "_h_mean_dh", "_odd", "_pair", "_band",
            "_residual", "_solve", "_solve_ladder", "_newton", "_solve_rows",
            "_tangent_rows")  # fmt: skip
