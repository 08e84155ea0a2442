"""The 2-DOF haptic lever model ([lebel] Eq. 1–4): impedances, bandwidth, rendering
area, passivity and stability. Pure functions on :class:`HapticParams`, SI units, angular
frequencies ``w`` in rad/s, results in Hz where the name says ``_hz``.

**Model** (paper Fig. 4b). Actuator mass m1 with grounded damper b1 and force F_a;
transmission spring k and damper b between x1 and the lever x2; lever mass m2; the human
pushes the lever with F_h::

    m1 s² x1 = F_a − b1 s x1 − (b s + k)(x1 − x2)
    m2 s² x2 = F_h + (b s + k)(x1 − x2)

**Passive impedance** (F_a = 0). The first line gives x1 = (bs+k) x2 / D1 with
D1 = m1 s² + (b1+b) s + k; substituting in the second, Z_h = F_h/(s x2) is Eq. 2::

    Z_p = Num(s)/D1(s),  Num = m1 m2 s³ + (m2 b1 + m1 b + m2 b) s² + (b1 b + m1 k + m2 k) s + b1 k

**Closed loop.** The controller renders a virtual spring K from the lever sensor x2:
F_a = −K E(s) x2 with E(s) = e^{−sτ} H(s), the actuator's pure delay τ and, if a sample
period T is given, the zero-order hold's frequency response H(jω) = (1 − e^{−jωT})/(jωT)
(the fundamental of the sampled loop; aliasing is neglected). Then
x1 = (bs + k − K E) x2 / D1 and::

    Z_cl = m2 s + (bs + k)(m1 s² + b1 s + K E) / (s D1) = [s Num + K E (bs + k)] / (s D1)

At K = 0 it is Eq. 2. It is evaluated exactly (no Padé). The free lever's characteristic
quasi-polynomial is χ(s) = s Num(s) + K E(s)(bs + k).

**Effective impedance** (the decomposition of Mehling, Colgate & Peshkin [mehling2005],
the paper's [5]): with F/X = s Z at s = jω, effective stiffness k_eff = Re(jωZ) [N/m],
effective damping b_eff = Re Z [N·s/m], effective mass m_eff = Im(Z)/ω = −k_eff/ω² [kg].

**Rendering bandwidth.** Lumped: ω*_s = √(K/(m1+m2)) (Eq. 1). Full: the first frequency
where k_eff crosses zero from positive (spring-like) to negative (mass-like), i.e. the
anti-resonance of the closed loop. Certified not to skip a narrow negative window: every
frequency interval below the crossing is proven root-free by bounds on k_eff's variation
(``bandwidth``), then the crossing is refined by Illinois regula falsi to a relative 1e-8.

**Rendering area** [dB·decade]: over a stated band (default 1 Hz – 1 kHz), the area
between 20 log10|Z_cl(K)| and 20 log10|Z_p| where the closed loop lies above the passive
floor: A = ∫ max(0, 20 log10|Z_cl/Z_p|) d(log10 f), trapezoid rule on a log grid of
``points_per_decade`` (default 25: within 0.01 dB·decade of the converged value).

**Passivity.** Re Z_cl(jω) = Re Z_p(jω) + K g(ω) with g = Re[E (bs+k)/(s D1)] is affine in
K and Re Z_p ≥ 0, so the passive K form the interval [0, K_p] with
K_p = inf over {g < 0} of Re Z_p/(−g) (dense log grid, then five 20× zooms on its minimum).

**Stability** (exact for a pure delay, D-subdivision). For K > 0 small, the roots of χ are
those of s Num (left half-plane) with the rigid-body root moved from 0 to ≈ −K/b1. Roots
reach the right half-plane only by crossing the imaginary axis (χ is retarded), at jω with
K E(jω) = −jω Num(jω)/(k + jbω) =: K(ω)·E — i.e. where X(ω) = −jω Num/((k+jbω)E) is real
and positive, with K_c = X. Every crossing frequency is found (polynomial roots when there
is no delay; otherwise sign changes of Im X on a grid fine against the delay's phase
period, refined by Illinois regula falsi, up to a frequency beyond which the lower bound
ω|Num(jω)|/|k+jbω| ≤ K(ω), increasing there, exceeds the best K_c), with its crossing
direction sign Re(ds/dK) = Re[−E (bs+k)/χ'(s)]. The number of right-half-plane roots at K
is 2 Σ sign over crossings with K_c < K: stable iff it is 0. The largest stable K is the
first K_c where that count turns positive.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.polynomial import polynomial as P

from geometry.numerics import illinois
from geometry.validation import ParameterError, check_nonnegative
from mrclutch.haptics.actuator import HapticParams

#: Most frequencies one step of the crossing search may take (memory: 8 bytes each).
MAX_GRID = 2_000_000
#: Most live intervals one design's bandwidth search bisects (the paper's design needs
#: under 100): past it the design's bandwidth is left NaN (unresolved) — a guard on memory.
MAX_BRACKETS = 4096

__all__ = [
    "BAND_HZ",
    "EffectiveImpedance",
    "HapticParams",
    "bandwidth",
    "bandwidth_lumped",
    "closed_loop_impedance",
    "effective_impedance",
    "is_passive",
    "is_stable",
    "max_passive_stiffness",
    "max_stable_stiffness",
    "metrics",
    "metrics_batch",
    "metrics_of",
    "passive_impedance",
    "rendering_area",
    "resonance",
]

TWO_PI = 2.0 * math.pi
BAND_HZ = (1.0, 1000.0)  # rendering-area band [Hz]
METRIC_KEYS = (
    "m1_kg",
    "m2_kg",
    "b1_N_s_per_m",
    "k_N_per_m",
    "b_N_s_per_m",
    "K_N_per_m",
    "delay_s",
    "bandwidth_lumped_hz",
    "bandwidth_hz",
    "resonance_hz",
    "passive",
    "max_passive_K_N_per_m",
    "max_stable_K_N_per_m",
    "rendering_area_dB_decade",
)


def _check_K(K: Any) -> Any:
    if np.ndim(K) == 0:
        return check_nonnegative("K", float(K), " N/m")
    a = np.asarray(K, dtype=float)
    bad = ~np.isfinite(a) | (a < 0)
    if bad.any():
        raise ParameterError(f"K = {a[bad].flat[0]:.6g} N/m: must be finite and >= 0")
    return a


def _num_coeffs(p: HapticParams) -> tuple[Any, Any, Any, Any]:
    """Eq. 2 numerator coefficients (s³, s², s¹, s⁰)."""
    return (
        p.m1 * p.m2,
        p.m2 * p.b1 + p.m1 * p.b + p.m2 * p.b,
        p.b1 * p.b + p.m1 * p.k + p.m2 * p.k,
        p.b1 * p.k,
    )


def crossing_frequency(p: HapticParams, K: float) -> float:
    """ω [rad/s] where a root of the delayed loop at K sits on the imaginary axis: the
    magnitude condition K|k + jbω| = ω|Num(jω)| (the delay only sets the phase; Eq. 2)."""
    from scipy.optimize import brentq

    c3, c2, c1, c0 = _num_coeffs(p)

    def f(w: float) -> float:
        s = 1j * w
        num = ((c3 * s + c2) * s + c1) * s + c0
        return math.log(w * abs(num)) - math.log(K * abs(p.k + 1j * p.b * w))

    lo, hi = 1e-6, 1.0
    while f(hi) < 0:
        hi *= 2.0
    return float(brentq(f, lo, hi, xtol=1e-12, rtol=1e-12))


def _hold(p: HapticParams, w: Any, sample_period: Any) -> Any:
    """E(jω) = e^{−jωτ} H(jω): pure delay τ and zero-order hold of period T (0: none)."""
    T = p.sample_period if sample_period is None else sample_period
    E = np.exp(-1j * w * p.delay)
    if np.any(np.asarray(T) > 0):
        x = w * T
        # ZOH: (1 − e^{−jωT})/(jωT) = e^{−jωT/2} sinc(ωT/2)  [franklin-powell-workman]
        E = E * np.exp(-0.5j * x) * np.sinc(x / TWO_PI)
    return E


def passive_impedance(p: HapticParams, w: Any) -> Any:
    """Eq. 2: Z_h(jω) = F_h / ẋ2 of the backdriven device [N·s/m]. ``p`` fields and ``w``
    [rad/s] broadcast (fields of shape (N, 1) and w of shape (M,) give N × M)."""
    s = 1j * np.asarray(w, dtype=float)
    a3, a2, a1, a0 = _num_coeffs(p)
    num = ((a3 * s + a2) * s + a1) * s + a0  # Eq. 2 numerator (Horner)
    den = (p.m1 * s + (p.b1 + p.b)) * s + p.k  # Eq. 2 denominator
    return num / den


def closed_loop_impedance(
    p: HapticParams, K: Any, w: Any, sample_period: float | None = None
) -> Any:
    """Z_cl(jω) with the virtual spring K [N/m] on the sensor x2 (module docstring):
    m2 s + (bs + k)(m1 s² + b1 s + K E)/(s D1), E = delay × optional zero-order hold."""
    K = _check_K(K)
    w = np.asarray(w, dtype=float)
    s = 1j * w
    E = _hold(p, w, sample_period)
    d1 = (p.m1 * s + (p.b1 + p.b)) * s + p.k
    return p.m2 * s + (p.b * s + p.k) * ((p.m1 * s + p.b1) * s + K * E) / (s * d1)


@dataclass(frozen=True)
class EffectiveImpedance:
    """Effective stiffness [N/m], damping [N·s/m] and mass [kg] against frequency."""

    stiffness: Any
    damping: Any
    mass: Any


def effective_impedance(
    p: HapticParams, K: Any, w: Any, sample_period: float | None = None
) -> EffectiveImpedance:
    """[mehling2005] decomposition of F/X = jωZ: k_eff = Re(jωZ), b_eff = Re Z,
    m_eff = Im(Z)/ω = −k_eff/ω²."""
    w = np.asarray(w, dtype=float)
    z = closed_loop_impedance(p, K, w, sample_period)
    k_eff = -w * z.imag
    return EffectiveImpedance(stiffness=k_eff, damping=z.real, mass=z.imag / w)


def _k_eff(m1, b1, k, b, m2, tau, K, w):  # type: ignore[no-untyped-def]
    """k_eff = Re(jω Z_cl) in real arithmetic (fast path, pure delay only):
    F/X = −m2ω² + (k + jbω)(P + jQ)/(R + jS), P + jQ = −m1ω² + jb1ω + K e^{−jωτ},
    R + jS = k − m1ω² + j(b1+b)ω (module docstring)."""
    w2 = w * w
    th = w * tau
    P = K * np.cos(th) - m1 * w2
    Q = b1 * w - K * np.sin(th)
    R = k - m1 * w2
    S = (b1 + b) * w
    bw = b * w
    return ((k * P - bw * Q) * R + (k * Q + bw * P) * S) / (R * R + S * S) - m2 * w2


def bandwidth_lumped(p: HapticParams, K: Any) -> Any:
    """Eq. 1: ω*_s = √(K/(m1+m2)), returned in Hz."""
    return np.sqrt(_check_K(K) / (p.m1 + p.m2)) / TWO_PI


def _flat(p: HapticParams, K: Any) -> tuple[np.ndarray, ...]:
    names = ("m1", "b1", "k", "b", "m2", "delay", "sample_period")
    arrs = np.broadcast_arrays(*(np.asarray(getattr(p, n), float) for n in names), K)
    return tuple(np.ravel(a) for a in arrs)


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
        (_, b, c), (a1, b1, c1) = self._ev(self.P, d, w), self._ev(self.D1, d, w)
        t = self._tau(d)
        cs, sn = np.cos(w * t), np.sin(w * t)
        return a1 + (b1 + c * t) * cs + (c1 - b * t) * sn

    def bound1(self, d: Any, w: np.ndarray) -> np.ndarray:
        """max |N'| over [0, ω]."""
        (_, b0, c0), (a1, b1, c1) = (self._ev(X, d, w) for X in self.abs[:2])
        return a1 + b1 + c1 + self._tau(d) * (b0 + c0)

    def bound2(self, d: Any, w: np.ndarray) -> np.ndarray:
        """max |N''| over [0, ω]."""
        (_, b0, c0), (_, b1, c1), (a2, b2, c2) = (self._ev(X, d, w) for X in self.abs)
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


def resonance(p: HapticParams) -> Any:
    """System resonance [Hz] of the backdriven device: |s| of the complex pair of zeros of
    Eq. 2 (the free lever's poles: the masses oscillating on the transmission spring, not
    in solid-body motion). NaN if the zeros are all real (overdamped)."""
    shape = p.shape
    a3, a2, a1, a0 = (np.ravel(np.broadcast_to(c, shape)) for c in _num_coeffs(p))
    b_, c_, d_ = a2 / a3, a1 / a3, a0 / a3  # monic cubic s³ + b s² + c s + d
    # discriminant of the cubic ([abramowitz-stegun] 3.8.2): < 0 ⇔ one real root + a pair
    disc = 18 * b_ * c_ * d_ - 4 * b_**3 * d_ + b_**2 * c_**2 - 4 * c_**3 - 27 * d_**2
    # Cardano on the depressed cubic t³ + P t + Q (s = t − b/3), then two Newton steps
    P = c_ - b_**2 / 3.0
    Q = 2.0 * b_**3 / 27.0 - b_ * c_ / 3.0 + d_
    sq = np.sqrt(np.maximum(Q * Q / 4.0 + P**3 / 27.0, 0.0))
    r = np.cbrt(-Q / 2.0 + sq) + np.cbrt(-Q / 2.0 - sq) - b_ / 3.0
    for _ in range(2):
        f = ((r + b_) * r + c_) * r + d_
        r = r - f / ((3.0 * r + 2.0 * b_) * r + c_)
    # product of the roots is −d: r |z|² = −d gives the pair's natural frequency |z|
    mag = np.sqrt(np.abs(d_ / r))
    out = np.where(disc < 0, mag / TWO_PI, np.nan)
    return out.reshape(shape) if shape else float(out[0])


def rendering_area(
    p: HapticParams,
    K: Any,
    band: tuple[float, float] = BAND_HZ,
    points_per_decade: int = 25,
) -> Any:
    """Rendering area [dB·decade] over ``band`` [Hz] (module docstring):
    ∫ max(0, 20 log10|Z_cl/Z_p|) d(log10 f), with Z_cl/Z_p = 1 + K E (bs+k)/(s Num)."""
    K = _check_K(K)
    f_lo, f_hi = band
    if not (0 < f_lo < f_hi and math.isfinite(f_hi)):
        raise ParameterError(f"band = {band!r} Hz: need 0 < f_lo < f_hi < inf")
    shape = np.broadcast_shapes(p.shape, np.shape(K))
    m1, b1, k, b, m2, tau, T, Kf = _flat(p, K)
    tau = tau + 0.5 * T  # ZOH phase lag
    dec = math.log10(f_hi / f_lo)
    n = max(math.ceil(dec * points_per_decade), 2) + 1
    u = np.linspace(math.log10(f_lo), math.log10(f_hi), n)
    w = TWO_PI * 10.0**u
    w2 = w * w
    out = np.empty(m1.size)
    # one delay for every design (a sweep's usual case): its phase terms once, exactly
    shared = bool(np.all(tau == tau[0])) if tau.size else False
    if shared:
        cs_all, sn_all = np.cos(w * tau[0]), np.sin(w * tau[0])
    coeffs = [np.broadcast_to(x, m1.shape) for x in _num_coeffs(HapticParams(m1, b1, k, b, m2))]
    for a in range(0, m1.size, 1024):
        sl = slice(a, a + 1024)
        c3, c2, c1, c0 = (x[sl, None] for x in coeffs)
        kk, bb, KK, tt = k[sl, None], b[sl, None], Kf[sl, None], tau[sl, None]
        # s Num(jω) = C + jD;  (bs + k) e^{−jωτ} = A + jB  (real arithmetic, Eq. 2 numerator)
        C = (c3 * w2 - c1) * w2
        D = (c0 - c2 * w2) * w
        if shared:
            cs, sn = cs_all, sn_all
        else:
            th = w * tt
            cs, sn = np.cos(th), np.sin(th)
        bw = bb * w
        A = kk * cs + bw * sn
        B = bw * cs - kk * sn
        if np.any(T[sl] > 0):  # zero-order hold magnitude sinc(ωT/2); its phase is in τ
            h = np.sinc(w * T[sl, None] / TWO_PI)
            A, B = A * h, B * h
        num2 = (C + KK * A) ** 2 + (D + KK * B) ** 2
        db = np.maximum(10.0 * np.log10(num2 / (C * C + D * D)), 0.0)  # 20 log10|Z_cl/Z_p|
        out[sl] = np.trapezoid(db, u, axis=1)
    return out.reshape(shape) if shape else float(out[0])


def max_passive_stiffness(p: HapticParams) -> Any:
    """Largest K [N/m] with Re Z_cl(jω) ≥ 0 at every ω (module docstring): inf over g < 0
    of Re Z_p/(−g), on a log grid 1e-3 Hz – 1 MHz (40 per decade) around each design's
    minimum, zoomed five times by a 41-point grid over the two neighbouring cells (each
    zoom narrows the cell 20×: 0.025 → 8e-9 decade; the minimum's value is quadratic in
    that). inf if g ≥ 0 everywhere. Vectorised over designs."""
    shape = p.shape
    m1, b1, k, b, m2, tau, T = (
        np.ravel(np.broadcast_to(np.asarray(getattr(p, f), float), shape))[:, None]
        for f in ("m1", "b1", "k", "b", "m2", "delay", "sample_period")
    )
    q = HapticParams(m1, b1, k, b, m2, delay=tau, sample_period=T)
    a3, a2, a1, a0 = _num_coeffs(q)

    def ratio(u: np.ndarray) -> np.ndarray:  # Re Z_p/(−g) where g < 0, else inf
        w = TWO_PI * 10.0**u
        s = 1j * w
        d1 = (m1 * s + (b1 + b)) * s + k  # Eq. 2 denominator
        g = (_hold(q, w, None) * (b * s + k) / (s * d1)).real
        re = ((((a3 * s + a2) * s + a1) * s + a0) / d1).real  # Re Z_p, Eq. 2
        neg = g < 0
        return np.where(neg, re / np.where(neg, -g, 1.0), np.inf)

    rows = np.arange(m1.shape[0])
    u = np.broadcast_to(np.linspace(-3.0, 6.0, 361), (rows.size, 361))
    best = np.full(rows.size, np.inf)
    zoom = np.linspace(-1.0, 1.0, 41)
    for _ in range(6):  # the full grid, then five zooms on [j−1, j+1]
        r = ratio(u)
        j = np.argmin(r, axis=1)
        best = np.minimum(best, r[rows, j])
        if not np.isfinite(best).any():
            break
        du = u[:, 1:2] - u[:, 0:1]
        u = u[rows, j][:, None] + du * zoom
    return best.reshape(shape) if shape else float(best[0])


def is_passive(p: HapticParams, K: Any) -> Any:
    """Whether the closed loop at K is passive (Re Z_cl ≥ 0 at every frequency)."""
    return _check_K(K) <= max_passive_stiffness(p) * (1.0 + 1e-9)


# --- stability (D-subdivision) -------------------------------------------------------


def _scalar(p: HapticParams) -> HapticParams:
    if p.shape:
        raise ParameterError(f"design shape = {p.shape}: need one design (scalar fields)")
    return p


def _chi(p: HapticParams, K: Any, s: Any) -> Any:
    """χ(s) = s Num(s) + K E(s)(bs + k), vectorised over K and s."""
    a3, a2, a1, a0 = _num_coeffs(p)
    num = ((a3 * s + a2) * s + a1) * s + a0
    E = np.exp(-s * p.delay)
    if p.sample_period > 0:
        E = E * (1 - np.exp(-s * p.sample_period)) / (s * p.sample_period)
    return s * num + K * E * (p.b * s + p.k)


def _scan_imaginary_axis(
    X: Callable[[Any], Any],
    w_a: float,
    tau: float,
    lower: Callable[[float], float],
    limit: float | None,
    w_lo: float | None = None,
) -> np.ndarray:
    """Frequencies ω > 0 [rad/s] where Im X(ω) changes sign (D-subdivision: a crossing of
    the imaginary axis where X, the gain that puts a root at jω, is real and > 0).

    Log grid below ω_a (the largest mode; from ``w_lo`` if lower), then linear chunks of
    doubling span with a step fine against both the delay's phase period π/(16τ) and the
    modes, each bracket refined by regula falsi. ``lower(ω)``: an increasing lower bound
    on |X| for ω ≥ ω_a; the scan stops once it exceeds ``limit`` (None: the smallest real
    positive X found so far, i.e. up to the first crossing) or at 10⁴ (ω_a + 1/τ)."""
    step = min(w_a / 50.0, math.pi / (16.0 * tau))
    grid = w_a * np.logspace(-4, 0, 401)
    if w_lo is not None and w_lo < grid[0]:  # a slow mode below the grid: start lower
        grid = np.concatenate([np.geomspace(w_lo, grid[0], 101)[:-1], grid])
    found, best = [], math.inf
    while True:
        xi = X(grid).imag
        sc = np.nonzero(np.sign(xi[:-1]) * np.sign(xi[1:]) < 0)[0]
        w = illinois(lambda _, x: X(x).imag, grid[sc], grid[sc + 1], xi[sc], xi[sc + 1], 1e-13)
        found.append(w)
        xv = X(w)
        ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
        best = min(best, float(np.min(xv.real[ok]))) if ok.any() else best
        w_end = float(grid[-1])
        if (w_end >= w_a and lower(w_end) > (best if limit is None else limit)) or (
            w_end > 1e4 * (w_a + 1 / tau)
        ):
            break
        n = math.ceil(w_end / step) + 1
        if n > MAX_GRID:  # an absurd delay or stiffness: refuse rather than fill memory
            raise StabilitySearchError(
                f"stability search: delay {tau:.3g} s needs more than {MAX_GRID:.0e} "
                "frequencies per scan step; not a haptic loop"
            )
        grid = np.linspace(w_end, 2 * w_end, n)
    return np.concatenate(found)


def _crossings(
    p: HapticParams, k_stop: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Imaginary-axis crossings of χ for one design: frequencies ω_c [rad/s], gains K_c
    [N/m] and directions sign Re(ds/dK) (+1: into the right half-plane) — every crossing
    with K_c ≤ ``k_stop`` (None: up to the smallest K_c, the stability limit), possibly
    more. Above ω_a (the largest |root| of Num) the bound K(ω) ≥ ω|Num(jω)|/|k + jbω| is
    increasing, so the scan stops where it exceeds the gains sought."""
    a = _num_coeffs(p)
    roots = np.roots(a)
    w_a = float(np.max(np.abs(roots)))
    tau = p.delay + 0.5 * p.sample_period

    def X(w: Any) -> Any:  # K(ω)·e^{jφ}: crossing where X is real and > 0
        s = 1j * np.asarray(w, dtype=float)
        num = ((a[0] * s + a[1]) * s + a[2]) * s + a[3]
        return -s * num / ((p.b * s + p.k) * _hold(p, np.asarray(w, float), None))

    def real_positive(xv: np.ndarray) -> np.ndarray:
        return (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))

    if tau == 0.0:
        # Im[−jωNum(jω)(k − jbω)] is a polynomial in ω: its positive real roots, exactly.

        c = np.array(a[::-1], dtype=complex) * (1j ** np.arange(4))  # Num(jω) in ω
        poly = P.polymul(P.polymul([0, -1j], c), [p.k, -1j * p.b])
        rts = np.roots(poly.imag[::-1])
        wc = np.sort(rts.real[(np.abs(rts.imag) < 1e-9 * np.abs(rts)) & (rts.real > 0)])
    else:

        def lower(w: float) -> float:  # |X| ≥ ω|Num(jω)|/|k + jbω| (|E| ≤ 1), increasing
            return abs(1j * w * np.polyval(a, 1j * w)) / abs(p.k + p.b * 1j * w)

        wc = _scan_imaginary_axis(X, w_a, tau, lower, k_stop)
    xv = X(wc)
    ok = real_positive(xv)
    wc, Kc = wc[ok], xv.real[ok]
    s, h = 1j * wc, 1e-6 * wc
    dchi = (_chi(p, Kc, s + h) - _chi(p, Kc, s - h)) / (2 * h)
    dchi_dK = _chi(p, Kc + 1.0, s) - _chi(p, Kc, s)  # ∂χ/∂K = E (bs + k)
    dirs = np.sign((-dchi_dK / dchi).real)
    order = np.argsort(Kc)
    return wc[order], Kc[order], dirs[order]


class StabilitySearchError(ParameterError):
    """The stability scan would need more than MAX_GRID frequencies per step."""


def max_stable_stiffness(p: HapticParams) -> Any:
    """Largest K [N/m] such that the free closed loop is stable for every K in (0, K]:
    the first crossing gain at which the count of right-half-plane roots turns positive
    (module docstring; exact for a pure delay). inf if no crossing destabilises; NaN where
    the scan would need more than MAX_GRID frequencies a step (StabilitySearchError: an
    extreme transmission or delay), so the limit is unknown.
    Vectorised fields are handled design by design (slower than the numeric metrics)."""
    if p.shape:
        n = int(np.prod(p.shape))
        flat = HapticParams(
            **{f: np.ravel(np.broadcast_to(getattr(p, f), p.shape)) for f in _FIELDS}
        )
        return np.array([max_stable_stiffness(flat.item(i)) for i in range(n)]).reshape(p.shape)
    try:
        _, Kc, dirs = _crossings(p)
    except StabilitySearchError:  # the scan cannot resolve this loop: the limit is unknown
        return math.nan
    count = np.cumsum(2 * dirs)
    bad = np.nonzero(count > 0)[0]
    return float(Kc[bad[0]]) if bad.size else math.inf


_FIELDS = ("m1", "b1", "k", "b", "m2", "delay", "f_max", "workspace", "sample_period")


def is_stable(p: HapticParams, K: float) -> bool:
    """Whether the free closed loop at K has no root with Re s ≥ 0 (D-subdivision count).
    K = 0 is the backdriven device: marginally stable (rigid-body root at 0), reported True.
    """
    K = _check_K(K)
    _scalar(p)
    if K == 0:
        return True
    _, Kc, dirs = _crossings(p, k_stop=K)
    if np.any(np.isclose(Kc, K, rtol=1e-12)):
        return False
    return bool(np.sum(2 * dirs[Kc < K]) == 0)


# --- metrics -------------------------------------------------------------------------


def metrics_batch(
    p: HapticParams, K: Any = None, *, limits: bool = True, band: tuple[float, float] = BAND_HZ
) -> dict[str, np.ndarray]:
    """All metrics for a vectorised set of designs, as arrays under the JSON keys of
    :func:`metrics`. K defaults to K_max (Eq. 4). ``limits=False`` skips the passivity and
    stability keys (``passive``, ``max_passive_K_N_per_m``, ``max_stable_K_N_per_m``):
    the stability limit is computed design by design and is the slow part."""
    K = p.k_max if K is None else K
    K = _check_K(K)
    shape = np.broadcast_shapes(p.shape, np.shape(K))

    def full(x: Any) -> np.ndarray:
        return np.broadcast_to(np.asarray(x, dtype=float), shape).copy()

    out: dict[str, np.ndarray] = {
        "m1_kg": full(p.m1),
        "m2_kg": full(p.m2),
        "b1_N_s_per_m": full(p.b1),
        "k_N_per_m": full(p.k),
        "b_N_s_per_m": full(p.b),
        "K_N_per_m": full(K),
        "delay_s": full(p.delay),
        "bandwidth_lumped_hz": full(bandwidth_lumped(p, K)),
        "bandwidth_hz": full(bandwidth(p, K)),
        "resonance_hz": full(resonance(p)),
    }
    if limits:
        kp = full(max_passive_stiffness(p))
        out["passive"] = out["K_N_per_m"] <= kp * (1.0 + 1e-9)
        out["max_passive_K_N_per_m"] = kp
        out["max_stable_K_N_per_m"] = full(max_stable_stiffness(p))
    out["rendering_area_dB_decade"] = full(rendering_area(p, K, band))
    return out


def metrics(p: HapticParams, K: float | None = None) -> dict[str, Any]:
    """The metrics of one design at K (default K_max, Eq. 4) under the JSON keys of issue 2
    (SI; NaN/inf mean "none"/"unbounded" and become null in JSON)."""
    _scalar(p)
    return metrics_of([p], [K])[0]


def metrics_of(
    ps: Sequence[HapticParams], Ks: Sequence[float | None] | None = None
) -> list[dict[str, Any]]:
    """:func:`metrics` of several single designs (each at its K; None: its K_max), in one
    vectorised pass: the per-call overhead is paid once (evaluate's MR pair and motor)."""
    for p in ps:
        _scalar(p)
    Ks = [None] * len(ps) if Ks is None else list(Ks)
    if len(Ks) != len(ps):
        raise ParameterError(f"Ks: {len(Ks)} stiffnesses for {len(ps)} designs")
    q = HapticParams.stack(ps)
    K = np.array([p.k_max if K is None else K for p, K in zip(ps, Ks, strict=True)])
    b = metrics_batch(q, K)
    out = []
    for i in range(len(ps)):
        res: dict[str, Any] = {}
        for key in METRIC_KEYS:
            v = b[key][i].item()
            res[key] = bool(v) if key == "passive" else float(v)
        out.append(res)
    return out
