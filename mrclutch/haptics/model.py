"""The 2-DOF haptic lever model ([lebel] Eq. 1–4) and its metrics at a rendered spring K:
the public face of the lever's four concepts, one module each — its transfer functions
(``mrclutch.haptics.impedance``: the model's equations, the impedances), its bandwidth
(``mrclutch.haptics.bandwidth``), the limits of K (``mrclutch.haptics.limits``: passivity,
stability) — plus the resonance, the rendering area and the metrics on them, here. Pure
functions on :class:`HapticParams`, SI units.

**Rendering area** [dB·decade]: over a stated band (default 1 Hz – 1 kHz), the area
between 20 log10|Z_cl(K)| and 20 log10|Z_p| where the closed loop lies above the passive
floor: A = ∫ max(0, 20 log10|Z_cl/Z_p|) d(log10 f), trapezoid rule on a log grid of
``points_per_decade`` (default 25: within 0.01 dB·decade of the converged value).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from geometry.validation import ParameterError
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.bandwidth import bandwidth
from mrclutch.haptics.impedance import (
    BAND_HZ,
    TWO_PI,
    EffectiveImpedance,
    _check_K,
    _flat,
    _num_coeffs,
    bandwidth_lumped,
    closed_loop_impedance,
    crossing_frequency,
    effective_impedance,
    passive_impedance,
)
from mrclutch.haptics.limits import (
    StabilitySearchError,
    _scalar,
    is_passive,
    is_stable,
    max_passive_stiffness,
    max_stable_stiffness,
)

__all__ = [
    "BAND_HZ",
    "EffectiveImpedance",
    "HapticParams",
    "StabilitySearchError",
    "bandwidth",
    "bandwidth_lumped",
    "closed_loop_impedance",
    "crossing_frequency",
    "effective_impedance",
    "is_passive",
    "is_stable",
    "max_passive_stiffness",
    "max_stable_stiffness",
    "metrics",
    "metrics_batch",
    "metrics_of",
    "passive_impedance",
    "passivity_batch",
    "rendering_area",
    "resonance",
]

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
        out.update(passivity_batch(p, K))
        out["max_stable_K_N_per_m"] = full(max_stable_stiffness(p))
    out["rendering_area_dB_decade"] = full(rendering_area(p, K, band))
    return out


def passivity_batch(p: HapticParams, K: Any) -> dict[str, np.ndarray]:
    """``metrics_batch``'s ``passive`` and ``max_passive_K_N_per_m`` alone (the same arrays,
    bit for bit): what the duty's hot holds read of a pair at K, without the bandwidths
    and the stability scan the other metrics need (issue 40)."""
    K = _check_K(K)
    shape = np.broadcast_shapes(p.shape, np.shape(K))
    kp = np.broadcast_to(np.asarray(max_passive_stiffness(p), dtype=float), shape).copy()
    k = np.broadcast_to(np.asarray(K, dtype=float), shape).copy()
    return {"passive": k <= kp * (1.0 + 1e-9), "max_passive_K_N_per_m": kp}


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
