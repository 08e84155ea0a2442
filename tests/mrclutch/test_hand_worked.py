"""Time constants and the rendering area pinned to hand-worked or independent values.

* A pure first-order current loop (supply so high the voltage never limits, a linear coil)
  must come back with τ_el = 1/(2π f_c): the fast and the reference rise share the
  definition τ = (t90 − t10)/ln 9, so an error in it would cancel between them.
* Two lags in series: 10–90 % rise of equal lags T is 3.3579·T (the roots of
  1 − (1 + x)e^{−x} = 0.1 and 0.9, x = t/T), the −3 dB frequency √(√2 − 1)/T.
* The rendering area with a zero-order hold (T > 0) against a direct integral of
  20·log10|Z_cl/Z_p| built from ``closed_loop_impedance`` with the exact hold
  (1 − e^{−sT})/(sT) and ``passive_impedance``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from geometry.params import preset
from geometry.section import build_section
from magnetics.amplifier import Amplifier
from magnetics.circuit import path_from_section
from magnetics.dynamics import current_rise, lag_bandwidth, lag_step
from magnetics.materials import linear_materials
from mrclutch.haptics.actuator import TABLE2_EM_136206, TABLE2_MR
from mrclutch.haptics.model import closed_loop_impedance, passive_impedance, rendering_area


def test_amplifier_time_constant_by_hand():
    """f_c = 2 kHz → τ_a = 1/(2π·2000) = 79.577 µs; 500 Hz → 318.31 µs."""
    assert Amplifier().time_constant == pytest.approx(79.577e-6, rel=1e-5)
    assert Amplifier(current_bandwidth_hz=500).time_constant == pytest.approx(318.31e-6, rel=1e-5)


@pytest.mark.parametrize("f_c", [200.0, 500.0, 2000.0])
def test_pure_first_order_loop_gives_back_its_time_constant(f_c):
    """Linear coil, 10 kV supply: the current follows (I − i)/τ_a alone, so the
    equivalent first-order time constant is τ_a = 1/(2π f_c) and the 10 % time τ_a·ln(10/9)."""
    mats = linear_materials(1e6, 1.0)
    p = path_from_section(build_section(preset("paper")), mats)
    rise = current_rise(p, 2.0, 1.0, Amplifier(supply_voltage=1e4, current_bandwidth_hz=f_c), mats)
    tau = 1 / (2 * math.pi * f_c)
    assert rise.time_constant[0] == pytest.approx(tau, rel=1e-9)
    assert rise.t10[0] == pytest.approx(tau * math.log(10 / 9), rel=1e-9)
    assert rise.t90[0] == pytest.approx(tau * math.log(10), rel=1e-9)


def test_two_equal_lags_rise_and_bandwidth_by_hand():
    """Step of 1/(1 + sT)²: y = 1 − (1 + x)e^{−x}, x = t/T. y = 0.1 at x = 0.53181,
    y = 0.9 at x = 3.88972: 10–90 % in 3.35791·T. −3 dB at ω = √(√2 − 1)/T = 0.643594/T."""
    T = 2e-3
    x10 = brentq(lambda x: 1 - (1 + x) * math.exp(-x) - 0.1, 0.01, 5)
    x90 = brentq(lambda x: 1 - (1 + x) * math.exp(-x) - 0.9, 0.01, 10)
    assert (x10, x90) == pytest.approx((0.53181, 3.88972), rel=1e-4)
    y = lag_step([[T, T]], [x10 * T, x90 * T])[0]
    np.testing.assert_allclose(y, [0.1, 0.9], atol=1e-7)
    assert lag_bandwidth([[T, T]])[0] == pytest.approx(0.643594 / T, rel=1e-5)
    # a second-order pair of unequal lags: |G|² = 1/((1 + ω²a²)(1 + ω²b²)) = 1/2 in closed
    # form: ω² = [−(a² + b²) + √((a² + b²)² + 4a²b²)]/(2a²b²)
    a, b = 1e-3, 2.5e-4
    sq = a * a + b * b
    w2 = (-sq + math.sqrt(sq**2 + 4 * a * a * b * b)) / (2 * a * a * b * b)
    assert lag_bandwidth([[a, b]])[0] == pytest.approx(math.sqrt(w2), rel=1e-9)


@pytest.mark.parametrize("params", [TABLE2_MR, TABLE2_EM_136206])
@pytest.mark.parametrize("T", [1e-3, 4e-3])
def test_rendering_area_with_a_hold_against_a_direct_integral(params, T):
    """∫ max(0, 20·log10|Z_cl/Z_p|) d(log10 f) over the module's band (BAND_HZ),
    with Z_cl from ``closed_loop_impedance`` (delay and the exact ZOH (1 − e^{−jωT})/(jωT))
    and Z_p from ``passive_impedance``: trapezoids on 20 000 points a decade. The hold must
    matter here (the area differs from T = 0 by more than the tolerance)."""
    from mrclutch.haptics.model import BAND_HZ

    p = replace(params, sample_period=T)
    K = 300.0
    u = np.linspace(math.log10(BAND_HZ[0]), math.log10(BAND_HZ[1]),
                    int(20000 * math.log10(BAND_HZ[1] / BAND_HZ[0])) + 1)  # fmt: skip
    w = 2 * math.pi * 10.0**u
    s = 1j * w
    hold = (1 - np.exp(-s * T)) / (s * T)  # the exact zero-order hold, written out here
    zcl = closed_loop_impedance(p, K, w)
    # Z_cl by hand from the module docstring's form with the hold written out here
    d1 = (p.m1 * s + (p.b1 + p.b)) * s + p.k
    by_hand = p.m2 * s + (p.b * s + p.k) * ((p.m1 * s + p.b1) * s + K * np.exp(-s * p.delay)
                                             * hold) / (s * d1)  # fmt: skip
    np.testing.assert_allclose(zcl, by_hand, rtol=1e-10)
    db = np.maximum(20 * np.log10(np.abs(by_hand / passive_impedance(p, w))), 0.0)
    direct = np.trapezoid(db, u)
    got = rendering_area(p, K, points_per_decade=20000)
    assert got == pytest.approx(direct, rel=1e-6)
    assert abs(rendering_area(replace(params, sample_period=0.0), K, points_per_decade=20000)
               - direct) > 1e-4 * direct  # fmt: skip


def test_simulated_growth_rate_is_the_step_maps_spectral_radius():
    """The free loop's step map x ↦ T x grows as ρ(T)^i, so the fitted growth rate is
    ln ρ(T)/h with h the step (an independent eigenvalue computation; a mutant that fitted
    a parabola to the log of the peaks survived the suite). Above the stable K the rate is
    > 0, below it < 0."""
    from mrclutch.haptics.delay import simulate_growth, step_map
    from mrclutch.haptics.model import max_stable_stiffness

    p = TABLE2_MR
    k = float(max_stable_stiffness(p))
    h = (p.delay + 0.5 * p.sample_period) / 5
    for K in (1.2 * k, 0.8 * k):
        rate = math.log(max(abs(np.linalg.eigvals(step_map(p, K, 5))))) / h
        got = simulate_growth(p, K, 1.0, 5)
        assert got == pytest.approx(rate, rel=0.05)
        assert (got > 0) == (K > k)
