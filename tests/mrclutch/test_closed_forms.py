"""Derived figures against their closed forms, worked by hand in each docstring (issue 46):
the dynamic range, torque per inertia, the continuous rating, the slip heat behind the
times to the limits, the felt mass, damping and backdrive force, and the motor's gearing.
A figure here is pinned by its definition and the paper preset's numbers, not by another
call of the function that computes it.

The paper preset's figures used (``mrclutch evaluate --preset paper --json``): max torque
0.42723 N·m, off-state torque 4.0765 mN·m, rotor inertia 2.5865e-7 kg·m², input speed
530 rpm; at the hand m1 = 1.4791 g, b1 = 0.26839 N·s/m, k = 4000 N/m, b = 20 N·s/m,
m2 = 14 g, K_max = 367.32 N/m on a 50 mm workspace.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from geometry.section import build_section
from magnetics import thermal
from mrclutch.design import design_preset
from mrclutch.haptics.actuator import ACTUATORS, EM_170, PULLEY_RATIO
from mrclutch.pipeline import dynamic_range_db, evaluate, evaluate_batch, fluid_limit

RPM_530 = 530 * 2 * math.pi / 60  # 55.501 rad/s: the paper's input speed (§II-B)


@pytest.fixture(scope="module")
def paper_eval():
    d = design_preset("paper")
    ev = evaluate(d)
    return d, ev, ev.as_json()


def test_dynamic_range_is_twenty_log10_of_the_torque_ratio():
    """A torque (amplitude) ratio in dB is 20·log10: 1 N·m over 10 mN·m is 100 → 40 dB;
    10 over 1 → 20 dB; equal torques → 0 dB. The paper preset: 0.42723/0.0040765 =
    104.81 → 20·log10(104.81) = 40.408 dB (10·log10 would give 20.20 dB)."""
    assert dynamic_range_db(1.0, 0.01) == pytest.approx(40.0, rel=1e-12)
    assert dynamic_range_db(10.0, 1.0) == pytest.approx(20.0, rel=1e-12)
    assert dynamic_range_db(3.0, 3.0) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(dynamic_range_db(np.array([1.0, 2.0]), np.array([0.1, 0.02])),
                               [20.0, 40.0], rtol=1e-12)  # fmt: skip
    assert dynamic_range_db(0.42723, 0.0040765) == pytest.approx(40.408, abs=2e-3)


def test_evaluation_and_batch_report_twenty_log10_of_their_own_torques(paper_eval):
    """What ``evaluate`` and the sweep rows print is 20·log10(T_max/T_off) of the torques
    they print beside it: 40.41 dB on the paper preset."""
    d, _, js = paper_eval
    c = js["clutch"]
    want = 20 * math.log10(c["max_torque_N_m"] / c["off_state_torque_N_m"])
    assert c["dynamic_range_dB"] == pytest.approx(want, rel=1e-12)
    assert c["dynamic_range_dB"] == pytest.approx(40.41, abs=0.01)
    rows = evaluate_batch({f: np.array([v]) for f, v in vars(d.clutch).items()}, d)
    want = 20 * np.log10(rows["max_torque_N_m"] / rows["off_state_torque_N_m"])
    np.testing.assert_allclose(rows["dynamic_range_dB"], want, rtol=1e-12)


def test_torque_per_inertia_is_peak_torque_over_rotor_inertia(paper_eval):
    """0.42723 N·m / 2.5865e-7 kg·m² = 1.6517e6 N·m/(kg·m²) (the rotor and shaft: the
    carried fluid is not in it)."""
    _, _, js = paper_eval
    c = js["clutch"]
    assert c["torque_per_inertia_N_m_per_kg_m2"] == pytest.approx(
        c["max_torque_N_m"] / c["rotor_inertia_kg_m2"], rel=1e-12
    )
    assert c["torque_per_inertia_N_m_per_kg_m2"] == pytest.approx(1.6517e6, rel=1e-4)


def _network(d):
    section = build_section(d.clutch, d.materials)
    rg = section.table
    limit = fluid_limit(rg.materials)
    return thermal.network(rg, d.operating.ambient_temperature, limit), limit


def test_continuous_rating_holds_one_node_at_its_limit_with_the_slip_heat_in_rad_s(paper_eval):
    """The continuous rating (I_c, T_c): held forever, the coil's Joule heat I_c² R(T) and
    the slip heat T_c·ω (ω = 2π·530/60 = 55.501 rad/s) bring the hotter-limited node of
    the thermal network's steady state exactly to its limit (coil 180 °C or fluid
    130 °C) and the other below it. Paper preset: I_c = 0.4012 A, T_c = 0.04511 N·m, a slip
    heat of 0.04511 × 55.501 = 2.504 W. ``thermal.steady`` is the direct solve G T = q,
    not the closed form the rating bisects on."""
    d, _, js = paper_eval
    c = js["clutch"]
    net, limit = _network(d)
    i_c, t_c = c["continuous_current_A"], c["continuous_torque_N_m"]
    assert d.operating.input_speed == pytest.approx(RPM_530, rel=1e-12)
    assert t_c * RPM_530 == pytest.approx(2.504, rel=1e-3)
    temps = np.ravel(thermal.steady(net, i_c, t_c * RPM_530))
    margin = max(temps[0] - d.operating.wire_temperature_limit, temps[1] - limit)
    assert margin == pytest.approx(0.0, abs=0.02)  # K: the chords' 0.33 % in torque
    # in rpm the slip heat is 9.5× larger: the same current would overheat the fluid
    temps_rpm = np.ravel(thermal.steady(net, i_c, t_c * 530.0))
    assert temps_rpm[1] - limit > 5.0 or temps_rpm[0] - d.operating.wire_temperature_limit > 5.0


def test_time_to_the_limits_takes_the_slip_heat_as_torque_times_rad_s(paper_eval):
    """The peak endurance: the coil at the current limit (7 A) and the clutch slipping at
    the peak torque, a slip heat P = T·ω = 0.42723 N·m × 55.501 rad/s = 23.712 W (in rpm it
    would be 226.4 W, 9.5× too much). The times the pipeline reports are the thermal
    network's at exactly that heat: 31.59 s to the fluid's limit (at 226 W: 8.1 s)."""
    d, _, js = paper_eval
    c = js["clutch"]
    net, limit = _network(d)
    p = c["max_torque_N_m"] * RPM_530
    assert p == pytest.approx(23.712, rel=1e-4)
    tw, tf = thermal.time_to_limits(net, c["max_current_A"], p,
                                    d.operating.wire_temperature_limit, limit)  # fmt: skip
    assert c["time_to_wire_limit_s"] == pytest.approx(tw, rel=1e-9)
    assert c["time_to_fluid_limit_s"] == pytest.approx(tf, rel=1e-9)
    assert tf == pytest.approx(31.59, rel=2e-3)
    _, tf_rpm = thermal.time_to_limits(net, c["max_current_A"], c["max_torque_N_m"] * 530.0,
                                       d.operating.wire_temperature_limit, limit)  # fmt: skip
    assert tf_rpm < 0.5 * tf  # the unit slip this test guards against is not a small change


def _zp(m1, b1, k, b, m2, w):
    """Eq. 2 at K = 0 written out: the lever's m2 plus the cable (k, b) in series with the
    clutch's m1, b1: Z = m2 s + (b s + k)(m1 s + b1)/(m1 s² + (b1 + b) s + k), s = jω."""
    s = 1j * w
    return m2 * s + (b * s + k) * (m1 * s + b1) / (m1 * s * s + (b1 + b) * s + k)


def test_felt_mass_damping_and_backdrive_force_are_eq2_at_2_hz(paper_eval):
    """Free motion at 2 Hz (ω = 4π = 12.566 rad/s), 10 mm: with the paper pair at the hand
    Z = 0.26841 + 0.19429j N·s/m. Felt damping Re Z = 0.26841 N·s/m, felt mass
    Im Z/ω = 0.19429/12.566 = 15.461 g (≈ m1 + m2 = 15.479 g: the cable is stiff at 2 Hz),
    backdrive force |Z| ω X = 0.33134 × 12.566 × 0.01 = 41.64 mN."""
    _, _, js = paper_eval
    h, mr = js["haptic"], js["hand"]["mr"]
    w = 4 * math.pi
    z = _zp(h["m1_kg"], h["b1_N_s_per_m"], h["k_N_per_m"], h["b_N_s_per_m"], h["m2_kg"], w)
    assert (z.real, z.imag) == pytest.approx((0.26841, 0.19429), abs=2e-5)
    assert mr["felt_damping_N_s_per_m"] == pytest.approx(z.real, rel=1e-9)
    assert mr["felt_mass_kg"] == pytest.approx(z.imag / w, rel=1e-9)
    assert mr["felt_mass_kg"] == pytest.approx(15.461e-3, rel=1e-4)
    assert mr["motion"] == {"amplitude_m": 0.01, "frequency_hz": 2.0}
    assert mr["backdrive_force_N"] == pytest.approx(abs(z) * w * 0.01, rel=1e-9)
    assert mr["backdrive_force_N"] == pytest.approx(41.64e-3, rel=1e-3)
    mo = js["hand"]["motor"]
    m = js["motor"]
    z = _zp(m["m1_kg"], m["b1_N_s_per_m"], m["k_N_per_m"], m["b_N_s_per_m"], m["m2_kg"], w)
    assert mo["felt_mass_kg"] == pytest.approx(z.imag / w, rel=1e-9)
    assert mo["backdrive_force_N"] == pytest.approx(abs(z) * w * 0.01, rel=1e-9)


def test_motor_gearing_matches_the_mr_pairs_force(paper_eval):
    """Equal force (paper §IV): the MR pair's F_max = K_max·d = 367.32 N/m × 0.05 m =
    18.366 N; the Maxon 136206 gives T nG/l = 0.348 N·m × 7.3080/0.170 m = 14.960 N at
    G = 1, so G = 18.366/14.960 = 1.2277. Its K at the hand is the MR pair's."""
    _, _, js = paper_eval
    motor = ACTUATORS["maxon-136206"]
    assert motor.max_torque == 0.348
    reduction = PULLEY_RATIO / EM_170.lever
    assert reduction == pytest.approx(42.988, rel=1e-4)
    f_mr = js["haptic"]["K_N_per_m"] * 0.05
    assert f_mr == pytest.approx(18.366, rel=1e-4)
    assert js["motor"]["gearing"] == pytest.approx(f_mr / (motor.max_torque * reduction), rel=1e-9)
    assert js["motor"]["gearing"] == pytest.approx(1.2277, rel=1e-4)
    assert js["motor"]["K_N_per_m"] == pytest.approx(js["haptic"]["K_N_per_m"], rel=1e-12)
