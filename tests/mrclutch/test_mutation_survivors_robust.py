"""Tests written for the round2 mutation run's survivors in the robust kernels
(mrclutch/robust_search.py, mrclutch/robust.py; benchmarks/mutation_run.py --run round2,
docs/testing.md): each drives a branch the run's tests left unexercised and checks its
answer against a closed form or an independent computation."""

import math

import numpy as np
import pytest

from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import max_stable_stiffness
from mrclutch.robust_search import stable_stiffness_batch, zero_moduli


def _one(p: HapticParams) -> HapticParams:
    """``p`` as a vectorised set of one design (the batch kernel's input)."""
    return HapticParams(np.array([p.m1]), p.b1, p.k, p.b, p.m2, delay=p.delay)


def test_a_light_lever_with_little_grounded_damping_is_limited_by_its_slow_delayed_mode():
    """The rigid lever (m1 + m2 = M, grounded damping b1, rendered K, delay τ):
    M s² + b1 s + K e^{−sτ} = 0 has a root at jω_c (its real and imaginary parts:
    K cos ω_cτ = Mω_c², K sin ω_cτ = b1ω_c) for K_c = Mω_c²/cos(ω_cτ) when
    b1 = Mω_c tan(ω_cτ). With ω_c = 5 rad/s, τ = 10 ms, M = 0.2001 kg: b1 = 0.050067 N·s/m,
    K_c = 5.008760 N/m. A stiff, strongly damped coupling (k = 10⁶ N/m, b = 50 N·s/m) on a
    light actuator (m1 = 0.1 g) puts Num's largest zero at b/m1 ≈ 4.8e5 rad/s, so 5 rad/s
    lies below 10⁻⁴ ω_a, where both kernels began their scans: they missed this crossing
    and gave 79002 N/m, a spring the loop cannot hold (a Padé(8) model of the delay has
    roots with Re s > 0 there). The coupling's compliance moves the 2-DOF limit from the
    rigid one by O(K/k) = 5e-6: rtol 1e-5."""
    m1, m2, tau, wc = 1e-4, 0.2, 0.01, 5.0
    M = m1 + m2
    b1 = M * wc * math.tan(wc * tau)
    k_c = M * wc**2 / math.cos(wc * tau)
    assert abs(k_c - 5.008760) < 1e-6
    p = HapticParams(m1, b1, 1e6, 50.0, m2, delay=tau)
    assert max_stable_stiffness(p) == pytest.approx(k_c, rel=1e-5)
    assert stable_stiffness_batch(_one(p))[0] == pytest.approx(k_c, rel=1e-5)


def test_zero_moduli_are_those_of_cubics_with_known_zeros():
    """``zero_moduli`` (the batch kernel's ω_a and the slowest zero behind its scan's
    start, ``limits.quiet_below``) on cubics built from their zeros, leading coefficient
    ≠ 1 so that a coefficient not divided by it shows: 2(s + 1)(s + 2)(s + 3) =
    2s³ + 12s² + 22s + 12 → 1, 2, 3; 4(s + 0.5)(s² + 2s + 100) = 4s³ + 10s² + 404s + 200 →
    0.5, 10, 10 (|−1 ± j√99| = 10). Dropping the companion row's sign gives the zeros of
    s³ − 6s² − 11s − 6 instead (7.56, 0.89, 0.89)."""
    coeffs = tuple(np.array(c, float) for c in ([2, 4], [12, 10], [22, 404], [12, 200]))
    got = np.sort(zero_moduli(coeffs), axis=1)
    np.testing.assert_allclose(got, [[1.0, 2.0, 3.0], [0.5, 10.0, 10.0]], rtol=1e-12)
