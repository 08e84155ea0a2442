"""Sampled-data passivity of a haptic device rendered behind a zero-order hold: the
condition of [colgate-schenkel1997] with the encoder limit of [abbott-okamura2005]
(the sampled counterpart of the Z-width, ``mrclutch.haptics.zwidth``). SI units.

**Sampled-data passivity** ([colgate-schenkel1997], one rigid mass m with physical damping
b, virtual environment H(z) = K + B(1 − z⁻¹)/T behind a zero-order hold, d whole samples
of delay): passive iff b > (T/2)/(1 − cos θ) · Re{(1 − e^{−jθ}) e^{−jdθ} H(e^{jθ})} for
0 ≤ θ = ωT ≤ π. With q = 1 − e^{−jθ}, |q|² = 2(1 − cos θ) and sum-to-product identities
the right side is K T D_d(θ) − B cos((d+1)θ), D_d(θ) = sin((2d+1)θ/2)/(2 sin(θ/2)) (derived
here; d = 0 gives the paper's b > KT/2 + |B|, and at B = 0, since |D_d| ≤ D_d(0) = d + ½,
K < 2b/((2d+1)T)). The encoder limit of [abbott-okamura2005] adds K ≤ 2 f_c/Δ (Coulomb
friction f_c, encoder resolution Δ; Δ = 0: ideal encoder, no limit).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from geometry.validation import ParameterError

__all__ = ["encoder_stiffness_limit", "sampled_max_passive_stiffness", "sampled_passivity_margin"]


def _theta(n: int = 2049) -> np.ndarray:
    return np.linspace(0.0, math.pi, n)


def _cs_terms(theta: np.ndarray, d: Any) -> tuple[np.ndarray, np.ndarray]:
    """(D_d(θ), −cos((d+1)θ)): the K T and B coefficients of the right side of
    [colgate-schenkel1997]'s condition (module docstring); D_d(0) = d + ½ (the limit)."""
    half = 0.5 * theta
    sh = np.sin(half)
    safe = np.where(sh == 0.0, 1.0, sh)
    dk = np.where(sh == 0.0, d + 0.5, np.sin((2 * d + 1) * half) / (2.0 * safe))
    return dk, -np.cos((d + 1) * theta)


def sampled_passivity_margin(b: Any, T: Any, K: Any, B: Any = 0.0, d: Any = 0) -> Any:
    """b − max over 0 ≤ θ ≤ π of the right side of [colgate-schenkel1997]'s condition
    [N·s/m]: passive iff > 0. Arguments broadcast; evaluated on 2049 θ (with θ = 0 and π,
    where the d = 0 maximum lies) and zoomed five times on the maximum."""
    b, T, K, B, d = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (b, T, K, B, d)))
    shape = b.shape
    b, T, K, B, d = (np.ravel(x)[:, None] for x in (b, T, K, B, d))

    def rhs(th: np.ndarray) -> np.ndarray:
        dk, cb = _cs_terms(th, d)
        return K * T * dk + B * cb

    th0 = np.broadcast_to(_theta(), (b.shape[0], _theta().size))
    best, _ = _refine_max(th0, rhs)
    out = (b[:, 0] - best).reshape(shape)
    return out if shape else float(out)


def _refine_max(th0: np.ndarray, f: Any) -> tuple[np.ndarray, np.ndarray]:
    """Max over θ ∈ [0, π] per row: grid, then five 41-point zooms (clipped to [0, π])."""
    v = f(th0)
    rows = np.arange(v.shape[0])
    j = np.argmax(v, axis=1)
    best, tb = v[rows, j], th0[rows, j]
    step = th0[0, 1] - th0[0, 0]
    zoom = np.linspace(-1.0, 1.0, 41)
    for _ in range(5):
        th = np.clip(tb[:, None] + step * zoom, 0.0, math.pi)
        v = f(th)
        j = np.argmax(v, axis=1)
        vb = v[rows, j]
        better = vb > best
        best = np.where(better, vb, best)
        tb = np.where(better, th[rows, j], tb)
        step /= 20.0
    return best, tb


def encoder_stiffness_limit(coulomb_friction: Any, encoder_resolution: Any) -> Any:
    """[abbott-okamura2005]: K ≤ 2 f_c/Δ [N/m] (Coulomb friction f_c [N], encoder
    resolution Δ [m]); inf where Δ = 0 (ideal encoder)."""
    fc = np.asarray(coulomb_friction, dtype=float)
    dl = np.asarray(encoder_resolution, dtype=float)
    if np.any(fc < 0) or np.any(dl < 0):
        raise ParameterError("coulomb_friction and encoder_resolution must be >= 0")
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(dl > 0, 2.0 * fc / np.where(dl > 0, dl, 1.0), np.inf)
    return out if out.ndim else float(out)


def sampled_max_passive_stiffness(
    b: Any,
    T: Any,
    B: Any = 0.0,
    d: Any = 0,
    *,
    coulomb_friction: Any = 0.0,
    encoder_resolution: Any = 0.0,
) -> Any:
    """Largest passive virtual stiffness [N/m] of [colgate-schenkel1997]'s sampled system
    (module docstring): sup{K : b > K T D_d(θ) − B cos((d+1)θ) ∀θ ∈ [0, π]} =
    inf over {D_d > 0} of (b + B cos((d+1)θ))/(T D_d(θ)), capped by
    :func:`encoder_stiffness_limit`. NaN where no K ≥ 0 is passive. d = 0: 2(b − |B|)/T.
    b [N·s/m] > 0, T [s] > 0, B [N·s/m] any real, d ≥ 0 integer samples; all broadcast."""
    b, T, B, d = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (b, T, B, d)))
    if np.any(b <= 0) or np.any(T <= 0) or np.any(d < 0) or np.any(d != np.round(d)):
        raise ParameterError("need b > 0, T > 0 and an integer delay d >= 0 (samples)")
    shape = b.shape
    b, T, B, d = (np.ravel(x)[:, None] for x in (b, T, B, d))

    def neg_ratio(th: np.ndarray) -> np.ndarray:  # −(b + B cos)/(T D) where D > 0
        dk, cb = _cs_terms(th, d)
        ok = dk > 0
        r = (b - B * cb) / (T * np.where(ok, dk, 1.0))
        return np.where(ok, -r, -np.inf)

    th0 = np.broadcast_to(_theta(), (b.shape[0], _theta().size))
    kmax = -_refine_max(th0, neg_ratio)[0]
    # where D_d ≤ 0 the condition is a lower bound K > (b + B cos)/(T D_d) (grid only)
    dk, cb = _cs_terms(th0, d)
    rhs0 = b - B * cb
    neg = dk < 0
    k_lo = np.max(np.where(neg, rhs0 / (T * np.where(neg, dk, -1.0)), 0.0), axis=1)
    none = np.any((dk == 0) & (rhs0 <= 0), axis=1) | (kmax < np.maximum(k_lo, 0.0))
    kmax = np.where(none, np.nan, kmax)
    kmax = np.minimum(kmax, np.ravel(encoder_stiffness_limit(coulomb_friction, encoder_resolution)))
    kmax = kmax.reshape(shape)
    return kmax if shape else float(kmax)
