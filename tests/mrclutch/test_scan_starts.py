"""Where the delayed loops' crossing scans start (``limits.quiet_below``): no crossing lies
below the start, checked against closed forms of a rigid lever whose slow delayed mode lies
far below a fixed fraction of the fast modes (the scans' old starts missed it)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.hand import Hand, max_stable_stiffness_coupled
from mrclutch.haptics.model import max_stable_stiffness
from mrclutch.haptics.zwidth import _ray_crossings, is_stable_spring_damper


def _first_destabilising(rc: np.ndarray, dirs: np.ndarray) -> float:
    """The first gain where the count of right-half-plane roots 2 Σ direction turns > 0."""
    bad = np.nonzero(np.cumsum(2 * dirs) > 0)[0]
    return float(rc[bad[0]]) if bad.size else math.inf


def test_zwidth_ray_finds_the_slow_delayed_mode_of_a_light_strongly_coupled_lever():
    """The rigid lever (m1 + m2 = M, grounded damping b1) with the virtual spring–damper
    (K, B) = ρ (c, σ) behind a delay τ: M s² + b1 s + ρ (c + σs) e^{−sτ} = 0 at s = jω_c
    (real part: ρ (c cos ω_cτ + σω_c sin ω_cτ) = Mω_c²; imaginary part:
    b1 ω_c = ρ (c sin ω_cτ − σω_c cos ω_cτ)) gives ρ_c for the b1 it fixes. ω_c = 5 rad/s,
    τ = 10 ms, B = 0.004 s × K, M = 0.2001 kg: ρ_c = 5.003792 (K = 5.003752 N/m,
    B = 0.020015 N·s/m), b1 = 0.030027 N·s/m. On a light actuator (m1 = 0.1 g) behind a stiff,
    strongly damped coupling (k = 10⁶ N/m, b = 50 N·s/m), Num's largest zero is
    b/m1 ≈ 4.8e5 rad/s, so 5 rad/s lies below the old start 10⁻⁴ ω_a: the ray's scan missed
    the crossing and called (2K, 2B) and (100K, 100B) stable (first crossing 7.9e4 there).
    The coupling's compliance moves the 2-DOF limit from the rigid one by O(ρ/k): rtol 1e-5,
    and the points 0.1 % either side are stable and unstable."""
    m1, m2, tau, wc, ratio = 1e-4, 0.2, 0.01, 5.0, 0.004
    M = m1 + m2
    c, sg = 1.0 / math.hypot(1.0, ratio), ratio / math.hypot(1.0, ratio)
    rho_c = M * wc**2 / (c * math.cos(wc * tau) + sg * wc * math.sin(wc * tau))
    b1 = rho_c * (c * math.sin(wc * tau) - sg * wc * math.cos(wc * tau)) / wc
    assert rho_c == pytest.approx(5.003792, abs=1e-6)
    assert b1 == pytest.approx(0.030027, abs=1e-6)
    p = HapticParams(m1, b1, 1e6, 50.0, m2, delay=tau)
    assert _first_destabilising(*_ray_crossings(p, c, sg, 10 * rho_c)) == pytest.approx(
        rho_c, rel=1e-5
    )
    K, B = rho_c * c, rho_c * sg
    assert is_stable_spring_damper(p, 0.999 * K, 0.999 * B)
    for f in (1.001, 2.0, 100.0):
        assert not is_stable_spring_damper(p, f * K, f * B)


def test_a_light_hand_does_not_hide_the_slow_delayed_mode_of_the_lever():
    """A mass-only hand is the lever with m2 → m2 + m_h (hand.py's module docstring), so
    the rigid lever's closed form holds with M = m1 + m2 + m_h: K_c = Mω_c²/cos(ω_cτ) when
    b1 = Mω_c tan(ω_cτ). ω_c = 15.65 rad/s, τ = 0.1 s (ω_cτ = 1.565, near π/2),
    M = 0.111 g: b1 = 0.29970 N·s/m, K_c = 4.690307 N/m. Num's slowest zero ≈ b1/M ≈ 2700
    rad/s, so the hand rows' old start 10⁻² × the slowest zero (27 rad/s) lay above the
    crossing, and a 1 mg hand read 23.46 N/m. The stiff coupling (k = 10⁶ N/m,
    b = 1 N·s/m) moves the limit by ~2.5e-8: rtol 1e-6; the same as the hand-free lever
    with m2 + m_h (``limits``' scan, its own start) to 1e-9."""
    m1, m2, mh, tau, wc = 1e-5, 1e-4, 1e-6, 0.1, 15.65
    M = m1 + m2 + mh
    b1 = M * wc * math.tan(wc * tau)
    k_c = M * wc**2 / math.cos(wc * tau)
    assert (b1, k_c) == pytest.approx((0.29970, 4.690307), abs=1e-5)
    p = HapticParams(m1, b1, 1e6, 1.0, m2, delay=tau)
    got = max_stable_stiffness_coupled(p, Hand(m=mh))
    assert got == pytest.approx(k_c, rel=1e-6)
    assert got == pytest.approx(max_stable_stiffness(replace(p, m2=m2 + mh)), rel=1e-9)
