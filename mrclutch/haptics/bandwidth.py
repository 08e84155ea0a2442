"""The full-model rendering bandwidth of the 2-DOF lever (``mrclutch.haptics.impedance``):
the first frequency where the closed loop's effective stiffness turns from spring to mass.

**Rendering bandwidth.** Lumped: ω*_s = √(K/(m1+m2)) (Eq. 1). Full: the first frequency
where k_eff crosses zero from positive (spring-like) to negative (mass-like), i.e. the
anti-resonance of the closed loop. Certified not to skip a narrow negative window: every
frequency interval below the crossing is proven root-free by bounds on k_eff's variation
(``bandwidth``), then the crossing is refined by Illinois regula falsi to a relative 1e-8.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from geometry.numerics import illinois
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.impedance import TWO_PI, _check_K, _flat, _k_eff

#: Most live intervals one design's bandwidth search bisects (the paper's design needs
#: under 100): past it the design's bandwidth is left NaN (unresolved) — a guard on memory.
MAX_BRACKETS = 4096


def _pmul(x: list[Any], y: list[Any]) -> list[Any]:
    """Product of two polynomials in ω, coefficients ascending, each an array of designs."""
    out: list[Any] = [0.0] * (len(x) + len(y) - 1)
    for i, xi in enumerate(x):
        for j, yj in enumerate(y):
            out[i + j] = out[i + j] + xi * yj
    return out


def _padd(*ps: list[Any]) -> list[Any]:
    n = max(len(q) for q in ps)
    return [sum(q[i] for q in ps if i < len(q)) for i in range(n)]


def _k_eff_parts(m1, b1, k, b, m2, K):  # type: ignore[no-untyped-def]
    """k_eff(ω)·(R² + S²) = A(ω) + B(ω) cos ωτ + C(ω) sin ωτ (``_k_eff`` expanded, R, S
    as there): the three polynomials in ω, coefficients ascending, arrays of designs."""
    R, S = [k, 0.0, -m1], [0.0, b1 + b]
    A = _padd(
        _pmul(R, [0.0, 0.0, -(k * m1 + b * b1)]),
        _pmul(S, [0.0, k * b1, 0.0, -b * m1]),
        _pmul([0.0, 0.0, -m2], _padd(_pmul(R, R), _pmul(S, S))),
    )
    B = [K * c for c in _padd([k * c for c in R], _pmul([0.0, b], S))]
    C = [K * c for c in _padd(_pmul([0.0, b], R), [-k * c for c in S])]
    return A, B, C


def _horner(c: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Σ c[j] ω^j with coefficient rows c[j] (each gathered to the shape of ω)."""
    out = np.array(c[-1], dtype=float)
    for cj in c[-2::-1]:
        out = out * w + cj
    return out


def _deriv(c: np.ndarray) -> np.ndarray:
    """Coefficient rows of the derivative (ascending powers)."""
    j = np.arange(1, c.shape[0]).reshape(-1, *([1] * (c.ndim - 1)))
    return c[1:] * j if c.shape[0] > 1 else np.zeros_like(c)


class _KeffSign:
    """N(ω) = A + B cos ωτ + C sin ωτ (the sign of k_eff), its derivatives and the bounds
    on them over [0, ω] (majorants: absolute coefficients, increasing for ω ≥ 0)."""

    def __init__(self, A: list[Any], B: list[Any], C: list[Any], tau: np.ndarray) -> None:
        self.tau = tau
        self.P = [np.array(X, dtype=float) for X in (A, B, C)]
        self.D1 = [_deriv(X) for X in self.P]
        self.D2 = [_deriv(X) for X in self.D1]
        self.abs = [[np.abs(X) for X in Ds] for Ds in (self.P, self.D1, self.D2)]

    def _ev(self, rows: list[np.ndarray], d: Any, w: np.ndarray) -> list[np.ndarray]:
        """Rows at ω: flat (``d`` the design of each ω) or 2-D (``d`` None: ω[design, m])."""
        if d is None:
            return [_horner(X[:, :, None], w) for X in rows]
        return [_horner(X[:, d], w) for X in rows]

    def _tau(self, d: Any) -> np.ndarray:
        return self.tau[:, None] if d is None else self.tau[d]

    def value(self, d: np.ndarray, w: np.ndarray) -> np.ndarray:
        a, b, c = self._ev(self.P, d, w)
        th = w * self._tau(d)
        return a + b * np.cos(th) + c * np.sin(th)

    def slope(self, d: np.ndarray, w: np.ndarray) -> np.ndarray:
        (b, c), (a1, b1, c1) = self._ev(self.P[1:], d, w), self._ev(self.D1, d, w)
        t = self._tau(d)
        cs, sn = np.cos(w * t), np.sin(w * t)
        return a1 + (b1 + c * t) * cs + (c1 - b * t) * sn

    def bound1(self, d: Any, w: np.ndarray) -> np.ndarray:
        """max |N'| over [0, ω] (|A| itself not needed: A's derivative's, B's, C's)."""
        (b0, c0), (a1, b1, c1) = self._ev(self.abs[0][1:], d, w), self._ev(self.abs[1], d, w)
        return a1 + b1 + c1 + self._tau(d) * (b0 + c0)

    def bound2(self, d: Any, w: np.ndarray) -> np.ndarray:
        """max |N''| over [0, ω] (nor |A|, |A'|)."""
        (b0, c0), (b1, c1) = (self._ev(X[1:], d, w) for X in self.abs[:2])
        a2, b2, c2 = self._ev(self.abs[2], d, w)
        t = self._tau(d)
        return a2 + b2 + c2 + 2 * t * (b1 + c1) + t * t * (b0 + c0)


def bandwidth(p: HapticParams, K: Any, *, rtol: float = 1e-8) -> Any:
    """Full-model rendering bandwidth [Hz]: the first + → − zero crossing of k_eff(ω).

    Certified not to skip a crossing: k_eff has the sign of N(ω) = A + B cos ωτ + C sin ωτ
    (``_k_eff_parts``; A, B, C polynomials). With M1 ≥ |N'| and M2 ≥ |N''| on [a, b]
    (absolute-coefficient majorants at b), an interval is *resolved* when N has no root in
    it — N(a), N(b) of one sign and |N(a)| + |N(b)| > M1 (b − a) — or when N is monotone
    in it — N'(a), N'(b) of one sign and |N'(a)| + |N'(b)| > M2 (b − a), so it holds a
    root exactly when N changes sign. From N(0) = K k² > 0 up to Fujiwara's root bound of
    the majorant (beyond it −m2 m1² ω⁶ dominates, N < 0), on a half-octave grid around
    Eq. 1's ω*_s, intervals are bisected until all before the first sign change are
    resolved; Illinois regula falsi then refines that crossing to ``rtol``. An interval
    narrower than ``rtol`` that stays unresolved counts
    as a crossing (k_eff touches 0 there). NaN where K = 0. A zero-order hold is included
    as its phase lag T/2. Vectorised over designs.
    """
    K = _check_K(K)
    shape = np.broadcast_shapes(p.shape, np.shape(K))
    m1, b1, k, b, m2, tau, T, Kf = _flat(p, K)
    tau = tau + 0.5 * T  # ZOH phase lag (magnitude sinc ≈ 1 below the bandwidth)
    out = np.full(m1.shape, np.nan)
    idx = np.nonzero(Kf > 0)[0]
    if idx.size == 0:
        return out.reshape(shape)
    m1, b1, k, b, m2, tau, Kf = (x[idx] for x in (m1, b1, k, b, m2, tau, Kf))
    A, B, C = _k_eff_parts(m1, b1, k, b, m2, Kf)
    lead = -m2 * m1 * m1  # ω⁶ coefficient of A; B and C have degree ≤ 3
    rest = [np.abs(c) for c in _padd(A[:-1], B, C)]
    # Fujiwara's bound [fujiwara1916] on the positive root of |lead| ω⁶ − Σ|c_j| ω^j
    w_up = 2.0 * np.max([(r / np.abs(lead)) ** (1.0 / (6 - j)) for j, r in enumerate(rest)],
                        axis=0)  # fmt: skip
    f = _KeffSign(A, B, C, tau)

    # initial intervals: 0, ω*_s·2^(−4…4) (Eq. 1's bandwidth, half octaves), w_up; only
    # those up to the first sign change on this grid can hold the first crossing
    ws = np.sqrt(Kf / (m1 + m2))
    grid = np.minimum(ws[:, None] * 2.0 ** np.linspace(-4.0, 4.0, 17)[None, :], w_up[:, None])
    grid = np.concatenate([np.zeros((idx.size, 1)), grid, w_up[:, None]], axis=1)
    N = f.value(None, grid)
    col = np.argmax((N[:, :-1] > 0) & (N[:, 1:] <= 0), axis=1)  # N(w_up) < 0: one exists
    found = np.zeros(idx.size, dtype=bool)
    br = np.zeros((idx.size, 4))
    # the common case, in 2-D: every interval before ``col`` root-free by the first-order
    # test, and N monotone in interval ``col`` (tested at its two ends only)
    rr = np.arange(idx.size)
    h = np.diff(grid, axis=1)
    free = (N[:, :-1] > 0) & (N[:, 1:] > 0)
    free &= np.abs(N[:, :-1]) + np.abs(N[:, 1:]) > f.bound1(None, grid[:, 1:]) * h
    lo_c, hi_c = grid[rr, col], grid[rr, col + 1]
    s0, s1 = f.slope(rr, lo_c), f.slope(rr, hi_c)
    mono = (s0 * s1 > 0) & (np.abs(s0) + np.abs(s1) > f.bound2(rr, hi_c) * (hi_c - lo_c))
    before = np.arange(h.shape[1])[None, :] < col[:, None]
    easy = np.all(free | ~before, axis=1) & mono
    br[easy] = np.stack([lo_c, hi_c, N[rr, col], N[rr, col + 1]], 1)[easy]
    found |= easy
    # the rest: their intervals up to ``col`` not proven root-free, bisected below
    take = ~easy[:, None] & (np.arange(h.shape[1])[None, :] <= col[:, None]) & ~free
    d = np.broadcast_to(rr[:, None], h.shape)[take]
    a, bb = grid[:, :-1][take], grid[:, 1:][take]
    na, nb = N[:, :-1][take], N[:, 1:][take]
    sa, sb = f.slope(d, a), f.slope(d, bb)
    big = np.iinfo(np.int64).max
    for _ in range(200):
        if d.size == 0:
            break
        pos = np.arange(d.size)
        h = bb - a
        m1b, m2b = f.bound1(d, bb), f.bound2(d, bb)
        change = (na > 0) & (nb <= 0)
        same = (na > 0) & (nb > 0)
        monotone = (sa * sb > 0) & (np.abs(sa) + np.abs(sb) > m2b * h)
        free = same & ((np.abs(na) + np.abs(nb) > m1b * h) | monotone)
        ok = free | (change & monotone)  # resolved
        tiny = ~ok & (h <= rtol * bb)
        first = np.full(idx.size, big)
        np.minimum.at(first, d[~free], pos[~free])  # first interval that may hold a root
        hit = (first < big) & ~found
        fi = first[hit]
        hit[hit] = (change[fi] & ok[fi]) | tiny[fi]
        for c, arr in enumerate((a, bb, na, nb)):
            br[hit, c] = arr[first[hit]]
        found |= hit
        fc = np.full(idx.size, big)
        np.minimum.at(fc, d[change], pos[change])
        keep = ~free & ~found[d] & (pos <= fc[d])  # nothing past the first sign change
        split = keep & ~ok & ~tiny
        if not split.any():
            break
        # the guard on memory: a design whose live intervals pass MAX_BRACKETS (parameters
        # far outside any device: a 1e-300 kg m1) is left unresolved (NaN), not bisected on
        live = np.bincount(d[keep], minlength=idx.size)
        over = live > MAX_BRACKETS
        if over.any():
            keep &= ~over[d]
            split &= ~over[d]
        stay = keep & ~split
        ds = d[split]
        mid = 0.5 * (a[split] + bb[split])
        nm, sm = f.value(ds, mid), f.slope(ds, mid)
        a = np.concatenate([a[stay], a[split], mid])
        bb = np.concatenate([bb[stay], mid, bb[split]])
        na = np.concatenate([na[stay], na[split], nm])
        nb = np.concatenate([nb[stay], nm, nb[split]])
        sa = np.concatenate([sa[stay], sa[split], sm])
        sb = np.concatenate([sb[stay], sm, sb[split]])
        d = np.concatenate([d[stay], ds, ds])
        order = np.lexsort((a, d))
        a, bb, na, nb, sa, sb, d = (x[order] for x in (a, bb, na, nb, sa, sb, d))
    # brackets with N(b) > 0 are unresolved touches: their midpoint (within rtol)
    touch = found & (br[:, 3] > 0)
    out[idx[touch]] = 0.5 * (br[touch, 0] + br[touch, 1]) / TWO_PI
    rows = np.nonzero(found & ~touch)[0]
    if rows.size:
        pr = tuple(x[rows] for x in (m1, b1, k, b, m2, tau, Kf))
        lo, hi = br[rows, 0], br[rows, 1]  # k_eff itself at the ends (N is scaled)
        root = illinois(lambda act, x: _k_eff(*(c[act] for c in pr), x),
                         lo, hi, _k_eff(*pr, lo), _k_eff(*pr, hi), rtol)  # fmt: skip
        out[idx[rows]] = root / TWO_PI
    return out.reshape(shape)
