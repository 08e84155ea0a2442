"""The 2-DOF haptic lever's transfer functions ([lebel] Eq. 1–4): the passive and
closed-loop impedances, the effective impedance and the lumped bandwidth. Pure functions on
:class:`HapticParams`, SI units, angular frequencies ``w`` in rad/s, results in Hz where the
name says ``_hz``.

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry.validation import ParameterError, check_nonnegative
from mrclutch.haptics.actuator import HapticParams

TWO_PI = 2.0 * math.pi
BAND_HZ = (1.0, 1000.0)  # rendering-area band [Hz]


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
