"""Cheaper stand-ins for the exact delay: Padé approximants and time stepping.

The exact reference is :func:`mrclutch.haptics.limits.max_stable_stiffness` (D-subdivision on the
quasi-polynomial with the pure delay e^{−sτ}). The two approximations here give the same
quantity — the largest virtual stiffness K [N/m] for which the free lever is stable — so
their error can be measured against it (``mrclutch fidelity``):

* **Padé of order n**: e^{−sτ} ≈ P_n(sτ)/P_n(−sτ), the diagonal Padé approximant; the
  closed loop becomes the polynomial χ_n(s) = s Num(s) P_n(−sτ) + K P_n(sτ)(bs + k), whose
  roots are found by ``numpy.roots``.
* **Time stepping at h = τ/N**: the 2-DOF equations discretised exactly over one step
  with the delayed force linearly interpolated (first-order hold, [franklin-powell-workman]
  §6.3.2) — the scheme of tests/mrclutch/test_haptic.py. The
  simulation's asymptotic growth per step is the spectral radius of its one-step map on
  the state [x1, ẋ1, x2, ẋ2, x2(t−h), …, x2(t−Nh)]; stable iff it is < 1. (Running the
  simulation and fitting its envelope measures the same number, more slowly and with a
  finite-time bias: :func:`simulate_growth`.)

A zero-order hold of period T is folded into the delay as its phase lag T/2, as
:func:`mrclutch.haptics.bandwidth.bandwidth` does.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from geometry.validation import ParameterError, check_positive
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.impedance import _num_coeffs


def pade_coefficients(order: int) -> tuple[np.ndarray, np.ndarray]:
    """Diagonal Padé approximant of e^{−x}: numerator and denominator coefficients in
    ascending powers of x. c_k = (2n−k)! n! / ((2n)! k! (n−k)!) (Baker & Graves-Morris,
    *Padé Approximants*, §1.2); numerator (−1)^k c_k, denominator c_k."""
    if int(order) != order or order < 1:
        raise ParameterError(f"order = {order!r}: need an integer >= 1")
    n = int(order)
    c = np.array(
        [
            math.factorial(2 * n - k)
            * math.factorial(n)
            / (math.factorial(2 * n) * math.factorial(k) * math.factorial(n - k))
            for k in range(n + 1)
        ]
    )
    return c * (-1.0) ** np.arange(n + 1), c


def pade_phase_error(tau: float, order: int, w: np.ndarray | float) -> np.ndarray:
    """|phase of the Padé approximant − (−ωτ)| [rad] at ω: the approximant is all-pass
    (|P(jy)/P(−jy)| = 1), so its only error is this phase. Phase −2 arg Q(jωτ), with
    arg Q summed over the roots of Q (all in the left half-plane, so continuous)."""
    _, den = pade_coefficients(order)
    roots = np.roots(den[::-1])
    y = np.asarray(w, dtype=float)[..., None] * tau
    arg_q = np.sum(np.angle(1j * y - roots) - np.angle(-roots), axis=-1).real
    return np.abs(-2.0 * arg_q + np.asarray(w, dtype=float) * tau)


def _tau(p: HapticParams) -> float:
    return float(p.delay) + 0.5 * float(p.sample_period)  # ZOH as its phase lag T/2


def _largest_stable(stable: Callable[[float], bool], k0: float, rtol: float = 1e-9) -> float:
    """First unstable K on a doubling grid from k0, then bisection to ``rtol``.
    (Assumes the stable set starts as an interval [0, K*], as for the free lever.)"""
    lo = k0
    while not stable(lo):
        lo /= 2.0
        if lo < 1e-12 * k0:
            return 0.0
    hi = 2.0 * lo
    for _ in range(200):
        if not stable(hi):
            break
        lo, hi = hi, 2.0 * hi
    else:
        return math.inf
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return 0.5 * (lo + hi)


def _k_scale(p: HapticParams) -> float:
    return float(p.k) * 1e-3 + 1.0


def pade_stable_stiffness(p: HapticParams, order: int) -> float:
    """Largest stable K [N/m] with the delay replaced by its order-n Padé approximant."""
    num_p, den_p = pade_coefficients(order)
    tau = _tau(p)
    check_positive("delay", tau, " s")
    w0 = 1.0 / tau  # s = w0 σ: coefficients of comparable size for numpy.roots
    sig = w0 ** np.arange(8)

    def poly(coeffs_asc_x: np.ndarray) -> np.ndarray:  # P(sτ) as a polynomial in σ
        return (coeffs_asc_x * (tau * w0) ** np.arange(coeffs_asc_x.size))[::-1]

    num = np.array(_num_coeffs(p), dtype=float)  # Eq. 2 Num(s), descending powers
    snum = np.polymul(num * sig[3::-1], [1.0, 0.0]) * 1.0  # s Num(s), s = w0σ
    snum = snum * w0  # the extra factor s = w0 σ
    bk = np.array([p.b * w0, p.k])
    lhs = np.polymul(snum, poly(den_p))
    rhs = np.polymul(poly(num_p), bk)

    def stable(K: float) -> bool:
        c = np.polyadd(lhs, K * rhs)
        return bool(np.max(np.roots(c / np.max(np.abs(c))).real) < 0)

    return _largest_stable(stable, _k_scale(p))


def step_map(p: HapticParams, K: float, steps_per_delay: int) -> np.ndarray:
    """One-step map of the first-order-hold time stepping of the delayed free loop
    (module docstring), on the state [x1, ẋ1, x2, ẋ2, x2(t−h) … x2(t−Nh)]."""
    from scipy.linalg import expm

    N = int(steps_per_delay)
    if N < 1:
        raise ParameterError(f"steps_per_delay = {steps_per_delay!r}: need >= 1")
    tau = _tau(p)
    check_positive("delay", tau, " s")
    A = np.array(
        [
            [0, 1, 0, 0],
            [-p.k / p.m1, -(p.b1 + p.b) / p.m1, p.k / p.m1, p.b / p.m1],
            [0, 0, 0, 1],
            [p.k / p.m2, p.b / p.m2, -p.k / p.m2, -p.b / p.m2],
        ],
        dtype=float,
    )  # Eq. 1-2 equations of motion (mrclutch.haptics.impedance module docstring)
    B = np.array([0, 1 / p.m1, 0, 0])
    h = tau / N
    M = np.zeros((6, 6))  # FOH discretisation by one matrix exponential [franklin-powell-workman]
    M[:4, :4], M[:4, 4], M[4, 5] = A * h, B * h, 1.0
    E = expm(M)
    Phi, G1, G2 = E[:4, :4], E[:4, 4], E[:4, 5]
    n = 4 + N
    T = np.zeros((n, n))
    # x_{i+1} = Φ x_i + (G1 − G2) u0 + G2 u1, u0 = −K x2(t_i − τ), u1 = −K x2(t_{i+1} − τ)
    T[:4, :4] = Phi
    T[:4, n - 1] += -K * (G1 - G2)  # x2(t_i − Nh): the last history slot
    if N == 1:
        T[:4, 2] += -K * G2  # x2(t_{i+1} − h) = x2(t_i)
    else:
        T[:4, n - 2] += -K * G2  # x2(t_i − (N−1)h)
    T[4, 2] = 1.0  # history shifts: slot 1 ← x2(t_i)
    for j in range(5, n):
        T[j, j - 1] = 1.0
    return T


def step_stable_stiffness(p: HapticParams, steps_per_delay: int) -> float:
    """Largest K [N/m] for which the time stepping at h = τ/N does not grow (spectral
    radius of :func:`step_map` ≤ 1; the rigid-body mode sits at 1 when K = 0)."""

    def stable(K: float) -> bool:
        return bool(np.max(np.abs(np.linalg.eigvals(step_map(p, K, steps_per_delay)))) < 1.0)

    return _largest_stable(stable, _k_scale(p))


def simulate_growth(p: HapticParams, K: float, t_end: float, steps_per_delay: int) -> float:
    """Growth rate [1/s] of the simulated free loop (x2(0) = 1 mm) by running the step
    map for ``t_end`` and fitting log of the window maxima over the second half."""
    T = step_map(p, K, steps_per_delay)
    h = _tau(p) / steps_per_delay
    n = int(t_end / h)
    x = np.zeros(T.shape[0])
    x[2] = 1e-3
    x[4:] = 1e-3  # held before the start
    x2 = np.empty(n + 1)
    x2[0] = x[2]
    for i in range(n):
        x = T @ x
        x2[i + 1] = x[2]
    win = max(n // 20, 1)
    tail = np.abs(x2[n // 2 :])
    starts = range(0, tail.size - win, win)
    peaks = [tail[k : k + win].max() for k in starts]
    tp = [(n // 2 + k) * h for k in starts]
    return float(np.polyfit(tp, np.log(peaks), 1)[0])


def lag_stable_stiffness(p: HapticParams, lags: np.ndarray | list[float], order: int = 8) -> float:
    """Largest stable K [N/m] with first-order lags Π 1/(1 + sT_i) in the loop besides the
    pure delay τ (``p.delay`` + ZOH/2, replaced by its order-n Padé approximant; none when
    τ = 0, and then the result is exact): the roots of
    χ(s) = s Num(s) Π(1 + sT_i) P_n(−sτ) + K P_n(sτ)(bs + k) (the actuator's torque
    response of ``magnetics.dynamics``; scaled s = w0 σ for ``numpy.roots``)."""
    t = np.asarray(lags, dtype=float).ravel()
    if np.any(~np.isfinite(t)) or np.any(t < 0):
        raise ParameterError(f"lags = {t.tolist()}: need finite time constants >= 0 s")
    tau = _tau(p)
    w0 = 1.0 / max(tau + float(t.sum()), 1e-9)
    a = np.array(_num_coeffs(p), dtype=float) * w0 ** np.arange(3, -1, -1)
    lhs = np.polymul(a, [w0, 0.0])  # s Num(s) in σ
    rhs = np.array([p.b * w0, p.k], dtype=float)  # bs + k
    for ti in t:
        lhs = np.polymul(lhs, [ti * w0, 1.0])
    if tau > 0:
        num_p, den_p = pade_coefficients(order)
        scale = (tau * w0) ** np.arange(num_p.size)
        lhs = np.polymul(lhs, (den_p * scale)[::-1])
        rhs = np.polymul(rhs, (num_p * scale)[::-1])

    def stable(K: float) -> bool:
        c = np.polyadd(lhs, K * rhs)
        return bool(np.max(np.roots(c / np.max(np.abs(c))).real) < 0)

    return _largest_stable(stable, _k_scale(p))
