"""The coupled stability's scan over many hands at once (``mrclutch.haptics.hand``): the
D-subdivision of χ_h(s) = P_h(s) + K E(s)(bs + k) for every hand row (m_h, b_h, k_h) of one
design in one pass. The same procedure as ``limits._crossings`` and
``limits._scan_imaginary_axis`` (hand.py's module docstring says why it holds), row by row
on the same grid: delay-free, the positive real roots of Im[−P_h(jω)(k − jbω)] (companion
matrices, as ``np.roots``); delayed or sampled, sign changes of Im X on limits' grids (the
log grid and the linear chunks of doubling span, ``limits._start_grid``/``_chunk_grid``),
each refined until no cell turns arg X by more than π/16 (``limits._phase_refine``, with
the row's zeros of P_h and the pole −k/b), refined by Illinois regula falsi
[dowell-jarratt1971]. Rows are padded by repeating an end point, which makes no sign
change. SI units."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from geometry.numerics import illinois
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.impedance import _hold, _num_coeffs
from mrclutch.haptics.limits import _chunk_grid, _phase_refine_rows, _start_grid, quiet_below


def _p_hands(p: HapticParams, rows: np.ndarray) -> np.ndarray:
    """P_h = s Num + (m_h s² + b_h s + k_h) D1 of each hand row, (H, 5), descending."""
    a3, a2, a1, a0 = _num_coeffs(p)
    d2, d1, d0 = p.m1, p.b1 + p.b, p.k  # Eq. 2 denominator D1 [lebel]
    m, b, k = rows[:, 0], rows[:, 1], rows[:, 2]
    # s · Eq. 2 numerator [lebel] + s Z_h D1 (the product of the two quadratics)
    return np.stack(
        [
            a3 + m * d2,
            a2 + m * d1 + b * d2,
            a1 + m * d0 + b * d1 + k * d2,
            a0 + b * d0 + k * d1,
            k * d0,
        ],
        axis=1,
    )


def _chi_c(p: HapticParams, c: np.ndarray, K: Any, s: Any) -> Any:
    """χ_h(s) = P_h(s) + K E(s)(bs + k) with P_h's coefficients ``c`` (last axis, 5)."""
    poly = (((c[..., 0] * s + c[..., 1]) * s + c[..., 2]) * s + c[..., 3]) * s + c[..., 4]
    E = np.exp(-s * p.delay)
    if p.sample_period > 0:
        E = E * (1 - np.exp(-s * p.sample_period)) / (s * p.sample_period)
    return poly + K * E * (p.b * s + p.k)


def _scan_hands(
    p: HapticParams,
    c: np.ndarray,
    w_a: np.ndarray,
    w_lo: np.ndarray,
    X: Any,
    k_stop: float | None,
    roots: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``limits._scan_imaginary_axis`` for every hand at once (rows of ``c``): each
    row's grid is the one that scan builds (``limits._start_grid``, ``_chunk_grid``,
    refined by ``_phase_refine`` until no cell turns arg X by more than π/16, counting
    the delay and the row's ``roots``, X's zeros and poles), rows padded by repeating an
    end point, which makes no sign change: (hand index, ω) of every sign change of Im X,
    refined by Illinois regula falsi."""
    tau = p.delay + 0.5 * p.sample_period
    step = np.minimum(w_a / 50.0, math.pi / (16.0 * tau))
    rows = np.arange(c.shape[0])
    grids = _refined([_start_grid(float(w_a[i]), float(w_lo[i])) for i in rows], tau, roots)
    best = np.full(c.shape[0], math.inf)
    limit = None if k_stop is None else float(k_stop)
    hids, ws = [], []
    while True:
        ncol = max(g.size for g in grids)
        r, lo, hi, f_lo, f_hi = _sign_changes(X, rows, _padded(grids, ncol), ncol)
        hid = rows[r]
        w = illinois(lambda act, x, hid=hid: X(hid[act], x).imag, lo, hi, f_lo, f_hi, 1e-13)
        hids.append(hid)
        ws.append(w)
        xv = X(hid, w)
        ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
        np.minimum.at(best, hid[ok], xv.real[ok])
        w_end, wa = np.array([g[-1] for g in grids]), w_a[rows]
        # |jω − r| ≥ ω − |r|, |E| ≤ 1: a lower bound on |X|, increasing past ω_a
        lower = c[rows, 0] * np.maximum(w_end - wa, 0.0) ** 4 / (p.k + p.b * w_end)
        target = best[rows] if limit is None else limit
        done = ((w_end >= wa) & (lower > target)) | (w_end > 1e4 * (wa + 1 / tau))
        rows, w_end = rows[~done], w_end[~done]
        if rows.size == 0:
            break
        chunks = [
            _chunk_grid(float(w), float(step[i]), tau) for i, w in zip(rows, w_end, strict=True)
        ]
        grids = _refined(chunks, tau, roots[rows])
    return np.concatenate(hids), np.concatenate(ws)


#: Most grid values one evaluation of X holds (rows × frequencies): the hands are scanned
#: in chunks of rows under it (one row at least), so the scan's memory is that of one
#: hand's scan, not of all 28 at once (a 0.01 gearing once took 1.7 GB batched, 0.11 GB
#: hand by hand). The grids' refinement batches rows under it too (``_refined``).
MAX_CELLS = 1 << 18


def _refined(grids: list[np.ndarray], tau: float, roots: np.ndarray) -> list[np.ndarray]:
    """Each row's grid refined as ``limits._phase_refine`` does (row ``i`` with
    ``roots[i]``), rows batched in passes of at most MAX_CELLS points."""
    out: list[np.ndarray] = []
    a = 0
    while a < len(grids):
        b, size = a + 1, grids[a].size
        while b < len(grids) and size + grids[b].size <= MAX_CELLS:
            size += grids[b].size
            b += 1
        row = np.repeat(np.arange(b - a), [g.size for g in grids[a:b]])
        flat, row = _phase_refine_rows(np.concatenate(grids[a:b]), row, tau, roots[a:b])
        out.extend(np.split(flat, np.flatnonzero(np.diff(row)) + 1))
        a = b
    return out


def _padded(grids: list[np.ndarray], ncol: int) -> Any:
    """Rows a:b of the rows' grids as one (b − a, ncol) array, each padded with its end
    point (built per chunk, never whole)."""

    def grid_of(a: int, b: int) -> np.ndarray:
        out = np.empty((len(grids[a:b]), ncol))
        for j, g in enumerate(grids[a:b]):
            out[j, : g.size], out[j, g.size :] = g, g[-1]
        return out

    return grid_of


def _sign_changes(X: Any, rows: np.ndarray, grid_of: Any, ncol: int) -> tuple[np.ndarray, ...]:
    """Every sign change of Im X on each row's grid, scanned in chunks of at most
    MAX_CELLS values: (row position in ``rows``, bracket ends, Im X at both), in row-major
    order (the order of one whole-array scan)."""
    per = max(1, MAX_CELLS // max(ncol, 1))
    found = []
    for a in range(0, rows.size, per):
        g = grid_of(a, a + per)
        xi = X(rows[a : a + per, None], g).imag
        r, j = np.nonzero(np.sign(xi[:, :-1]) * np.sign(xi[:, 1:]) < 0)
        found.append((r + a, g[r, j], g[r, j + 1], xi[r, j], xi[r, j + 1]))
    return tuple(np.concatenate(col) for col in zip(*found, strict=True))


def _positive_real_roots(poly: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row, root) of the positive real roots of each row's polynomial (descending), as
    ``np.roots`` finds them (eigenvalues of the companion matrix), every row of the same
    degree in one call; rows ascending, each row's roots ascending."""
    hid_l, wc_l = [], []
    lead = np.argmax(poly != 0, axis=1)  # leading zeros trimmed, as np.trim_zeros(.., "f")
    # the distinct degrees ascending, as np.unique gives them (without the numpy.ma it
    # imports: ≈ 20 ms of a single design's answer, issue 40)
    for deg in sorted(set((poly.shape[1] - 1 - lead).tolist())):
        rows = np.nonzero(poly.shape[1] - 1 - lead == deg)[0]
        if deg < 1:
            continue
        q = poly[rows][:, poly.shape[1] - 1 - deg :]
        comp = np.zeros((rows.size, deg, deg))
        comp[:, 0, :] = -q[:, 1:] / q[:, :1]
        comp[:, np.arange(1, deg), np.arange(deg - 1)] = 1.0
        rts = np.linalg.eigvals(comp)
        keep = (np.abs(rts.imag) < 1e-9 * np.abs(rts)) & (rts.real > 0)
        r, _ = np.nonzero(keep)
        hid_l.append(rows[r])
        wc_l.append(rts.real[keep])
    if not hid_l:
        return np.zeros(0, int), np.zeros(0)
    hid, wc = np.concatenate(hid_l), np.concatenate(wc_l)
    order = np.lexsort((wc, hid))
    return hid[order], wc[order]


def _crossings_hands(
    p: HapticParams, hands: Any, k_stop: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Imaginary-axis crossings of χ_h for every hand at once: (hand index, ω_c [rad/s],
    K_c [N/m], direction), sorted by hand, then K_c ascending. Every crossing with
    K_c ≤ ``k_stop`` (None: up to each hand's first, its stability limit) is found."""
    rows = np.asarray(hands, dtype=float).reshape(-1, 3)
    c = _p_hands(p, rows)
    comp = np.zeros((c.shape[0], 4, 4))  # companion matrices, as np.roots builds them
    comp[:, 0, :] = -c[:, 1:] / c[:, :1]
    comp[:, [1, 2, 3], [0, 1, 2]] = 1.0
    zeros = np.linalg.eigvals(comp)  # P_h's zeros (closed left half-plane)
    mags = np.abs(zeros)
    w_a = mags.max(axis=1)
    tau = p.delay + 0.5 * p.sample_period

    def X(hid: Any, w: Any) -> Any:  # K(ω)·e^{jφ}: crossing where X is real and > 0
        w = np.asarray(w, dtype=float)
        s = 1j * w
        return -_chi_c(p, c[hid], 0.0, s) / ((p.b * s + p.k) * _hold(p, w, None))

    if tau == 0.0:
        # Im[−P_h(jω)(k − jbω)] is a polynomial in ω: its positive real roots, exactly
        cw = c[:, ::-1].astype(complex) * (1j ** np.arange(5))  # P_h(jω) in ω, ascending
        im = -(cw[:, :, None] * np.array([p.k, -1j * p.b])[None, None, :]).imag
        poly = np.zeros((c.shape[0], 6))  # ascending in ω: the product of the two
        poly[:, :5] += im[:, :, 0]
        poly[:, 1:] += im[:, :, 1]
        hid, wc = _positive_real_roots(poly[:, ::-1])
    else:
        nz = np.where(mags > 1e-12 * w_a[:, None], mags, np.inf).min(axis=1)
        hands_on = np.any(rows != 0.0, axis=1)
        # Below limits.quiet_below no crossing lies. With a hand, X = −P_h/((k + jbω)E):
        # k_h > 0 gives arg X = π + arg P_h + ωτ − atan(bω/k), real positive only once
        # arg P_h + ωτ ≥ π; k_h = 0 gives P_h = s P̃ and arg X = −π/2 + arg P̃ + ωτ −
        # atan(bω/k), once arg P̃ + ωτ ≥ π/2. P_h's nonzero zeros (≤ 4, none nearer 0
        # than nz) lie in the closed left half-plane (Z_p + Z_h positive real), so
        # quiet_below(nz, τ, 4) bounds both. 1e-2 nz alone (a slow hand mode) missed the
        # slow delayed mode when nz τ > ~150 (a 1 mg mass-only hand: 9895 N/m against
        # the equal lever's 471); the lower of the two keeps the presets' grids.
        w_lo = np.where(
            hands_on, np.minimum(1e-2 * nz, quiet_below(nz, tau, 4)), quiet_below(nz, tau)
        )
        # X's zeros and poles for the grid's phase bound: P_h's zeros (one at 0 turns
        # nothing) and the pole −k/b
        pole = np.full((c.shape[0], 1 if p.b > 0 else 0), -p.k / p.b if p.b > 0 else 0.0)
        roots = np.concatenate([zeros, pole], axis=1)
        hid, wc = _scan_hands(p, c, w_a, w_lo, X, k_stop, roots)
    xv = X(hid, wc)
    ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
    hid, wc, Kc = hid[ok], wc[ok], xv.real[ok]
    s, dh, ch = 1j * wc, 1e-6 * wc, c[hid]
    dchi = (_chi_c(p, ch, Kc, s + dh) - _chi_c(p, ch, Kc, s - dh)) / (2 * dh)
    dchi_dK = _chi_c(p, ch, Kc + 1.0, s) - _chi_c(p, ch, Kc, s)  # ∂χ/∂K = E (bs + k)
    dirs = np.sign((-dchi_dK / dchi).real)
    order = np.lexsort((Kc, hid))
    return hid[order], wc[order], Kc[order], dirs[order]


def _limits_hands(p: HapticParams, hands: Any) -> np.ndarray:
    """The stability limit K_lim [N/m] of each hand (first K_c where the count of
    right-half-plane roots, 2 Σ direction, turns positive; inf if none), in one scan."""
    rows = np.asarray(hands, dtype=float).reshape(-1, 3)
    hid, _, Kc, dirs = _crossings_hands(p, rows)
    out = np.full(rows.shape[0], math.inf)
    if hid.size:
        cum = np.cumsum(2 * dirs)
        start = np.searchsorted(hid, hid)  # each crossing's hand's first crossing
        count = cum - np.concatenate([[0.0], cum])[start]  # 2 Σ sign within the hand
        bad = np.nonzero(count > 0)[0]
        first = bad[np.unique(hid[bad], return_index=True)[1]]
        out[hid[first]] = Kc[first]
    return out
