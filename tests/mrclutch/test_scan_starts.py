"""Where the delayed loops' crossing scans start (``limits.quiet_below``): no crossing lies
below the start, checked against closed forms of a rigid lever whose slow delayed mode lies
far below a fixed fraction of the fast modes (the scans' old starts missed it)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.hand import Hand, max_stable_stiffness_coupled
from mrclutch.haptics.impedance import _num_coeffs
from mrclutch.haptics.limits import PHASE_STEP, _phase_bound, _phase_refine
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
    crossing, and a 1 mg hand read 23.46 N/m. The stiff coupling (k = 10⁵ N/m,
    b = 1 N·s/m) moves the limit by ~2.5e-7: rtol 1e-6; the same as the hand-free lever
    with m2 + m_h (``limits``' scan, its own start) to 1e-9. (k = 10⁶ puts a mode at
    3·10⁵ rad/s behind the 0.1 s delay: past ``limits.MAX_REFINED``, refused.)"""
    m1, m2, mh, tau, wc = 1e-5, 1e-4, 1e-6, 0.1, 15.65
    M = m1 + m2 + mh
    b1 = M * wc * math.tan(wc * tau)
    k_c = M * wc**2 / math.cos(wc * tau)
    assert (b1, k_c) == pytest.approx((0.29970, 4.690307), abs=1e-5)
    p = HapticParams(m1, b1, 1e5, 1.0, m2, delay=tau)
    got = max_stable_stiffness_coupled(p, Hand(m=mh))
    assert got == pytest.approx(k_c, rel=1e-6)
    assert got == pytest.approx(max_stable_stiffness(replace(p, m2=m2 + mh)), rel=1e-9)


def _newton_root(p: HapticParams, K: float, B: float, s: complex) -> tuple[complex, float]:
    """A root of the exact χ(s) = s Num(s) + (K + Bs) e^{−sτ} (bs + k) by Newton from ``s``
    (analytic derivative), with its residual relative to |s Num(s)|."""
    a = _num_coeffs(p)
    da, tau = np.polyder(a), p.delay
    for _ in range(60):
        E, num = np.exp(-s * tau), np.polyval(a, s)
        chi = s * num + (K + B * s) * E * (p.b * s + p.k)
        d = num + s * np.polyval(da, s)
        d += E * (B * (p.b * s + p.k) + (K + B * s) * (p.b - tau * (p.b * s + p.k)))
        s = s - chi / d
    E = np.exp(-s * tau)
    res = abs(s * np.polyval(a, s) + (K + B * s) * E * (p.b * s + p.k))
    return complex(s), float(res / abs(s * np.polyval(a, s)))


def test_the_scan_resolves_the_delay_phase_below_the_largest_mode():
    """A lightly damped mode (Num's zeros −20.86 ± 9117j) behind a long delay
    (ω_aτ = 403): the old scan sampled [10⁻⁴ ω_a, ω_a] on a log grid of 2.3 % cells, which
    turn the delay's phase by ~9 rad near ω_a and step over the mode (width ~21 rad/s), and
    called (K, B) = (21.2585, 1.27692) stable. Newton on the exact characteristic equation,
    started at the missed crossing (9106.9 rad/s), finds a root at 3.08 + 9106.2j
    (independent of the scan); along the ray the first crossing is ρ_c = 16.41969 (not
    21.318, the old first one), with the root 0.1 % either side of ρ_c on either side of
    the axis. The refined grid turns arg X by at most π/16 a cell (``_phase_refine``)."""
    m1, b1, k = 0.01682534063979713, 0.9625700289298509, 291105.6071298039
    b, m2, tau = 0.10442872762128229, 0.004422746527719626, 0.044206561244483515
    p = HapticParams(m1, b1, k, b, m2, delay=tau)
    K, B = 21.2585, 1.27692
    s, res = _newton_root(p, K, B, 9106.9j)
    assert s.real == pytest.approx(3.08, abs=0.01) and res < 1e-10
    assert not is_stable_spring_damper(p, K, B)
    rho = math.hypot(K, B)
    c, sg = K / rho, B / rho
    rho_c = _first_destabilising(*_ray_crossings(p, c, sg, rho))
    assert rho_c == pytest.approx(16.41969, rel=1e-6)
    for f, side in ((0.999, -1.0), (1.001, 1.0)):
        s, res = _newton_root(p, f * rho_c * c, f * rho_c * sg, 9106.9j)
        assert side * s.real > 0 and abs(s.imag - 9106.9) < 1.0 and res < 1e-10
        assert is_stable_spring_damper(p, f * rho_c * c, f * rho_c * sg) == (side < 0)


def test_phase_refine_bounds_the_turn_of_every_cell():
    """Every cell of a refined grid turns Φ (delay + each root's atan2) by at most π/16,
    even across a mode 10⁴ times narrower than the log cells, and keeps the old points."""
    roots = np.array([-0.05 + 5000j, -0.05 - 5000j, -30.0, -2e5])
    grid = 5000.0 * np.logspace(-4, 0.5, 401)
    fine = _phase_refine(grid, 0.01, roots)
    assert np.all(np.diff(_phase_bound(fine, 0.01, roots)) <= PHASE_STEP * (1 + 1e-12))
    assert np.all(np.isin(grid, fine)) and np.all(np.diff(fine) > 0)
    assert np.any(np.abs(fine - 5000.0) < 0.05)  # a point inside the mode's width


def _newton_root_hand(p: HapticParams, h: Hand, K: float, s: complex) -> tuple[complex, float]:
    """A root of the exact coupled χ_h(s) = s Num(s) + (m_h s² + b_h s + k_h) D1(s)
    + K e^{−sτ}(bs + k), D1 = m1 s² + (b1 + b) s + k, by Newton from ``s`` (analytic
    derivative), with its residual relative to |P_h(s)|."""
    d1 = [p.m1, p.b1 + p.b, p.k]
    ph = np.polyadd(np.polymul(_num_coeffs(p), [1.0, 0.0]), np.polymul([h.m, h.b, h.k], d1))
    dph, tau = np.polyder(ph), p.delay
    for _ in range(80):
        E = np.exp(-s * tau)
        chi = np.polyval(ph, s) + K * E * (p.b * s + p.k)
        s = s - chi / (np.polyval(dph, s) + K * E * (p.b - tau * (p.b * s + p.k)))
    res = abs(np.polyval(ph, s) + K * np.exp(-s * tau) * (p.b * s + p.k))
    return complex(s), float(res / abs(np.polyval(ph, s)))


def test_the_hand_scan_resolves_a_sharp_hand_mode_behind_a_long_delay():
    """A stiff, undamped hand (1 g, 10⁵ N/m) on a light lever behind 64 ms: P_h has a
    sharp pair of zeros at −1.355 ± 8318.4j (width ~3 rad/s) and ω_aτ = 2140, so the
    old 2.3 % log cells (~190 rad/s there) stepped over the mode and hand_scan read
    14238.6 N/m. Its grids are now ``limits``' own, refined until no cell turns arg X by
    more than π/16 (the hand's zeros among the roots). Newton on the exact coupled
    characteristic equation (independent of the scan) puts a root on either side of the
    axis at 0.999 and 1.001 × the limit 43.2417 N/m."""
    p = HapticParams(1.36637e-5, 1.05461e-3, 14992.7, 0.712563, 4.30745e-4, delay=0.0642861)
    h = Hand(m=1e-3, b=0.0, k=1e5)
    got = max_stable_stiffness_coupled(p, h)
    assert got == pytest.approx(43.24174, rel=1e-6)
    for f, side in ((0.999, -1.0), (1.001, 1.0)):
        s, res = _newton_root_hand(p, h, f * got, 8319.7j)
        assert side * s.real > 0 and abs(s.imag - 8319.7) < 1.0 and res < 1e-10
