"""Actuator catalogue, transmission and reflection to the end effector (Eq. 3–4)."""

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry.validation import ParameterError
from mrclutch.haptics.actuator import (
    ACTUATORS,
    EM_170,
    MR_170,
    PULLEY_RATIO,
    TABLE2_MR,
    Actuator,
    HapticParams,
    Transmission,
    actuator,
    geared,
    pulley_ratio_from_table2,
    reflect,
)


def test_pulley_ratio_fits_each_table2_value():
    # each theoretical m1 of Table 2 gives its own n² = m1 l²/I; the fit sits among them
    single = [38.5e-3 * 0.17**2 / 209e-7, 3.7e-3 * 0.17**2 / 20e-7, 1.0e-3 * 0.17**2 / 5.4e-7]
    n2 = PULLEY_RATIO**2
    assert min(single) <= n2 <= max(single)
    assert n2 == pytest.approx(53.2, abs=0.5)
    # the paper's 14 mm winding drums: r_actuator = 7 mm → r_pulley ≈ 51 mm
    assert 7.0 * PULLEY_RATIO == pytest.approx(51.2, abs=0.5)
    assert pulley_ratio_from_table2() == PULLEY_RATIO


def test_motor_max_torque_is_twice_rated_and_mr_pair_doubles_rotors():
    assert actuator("maxon-136206").max_torque == pytest.approx(2 * 0.174)
    assert actuator("maxon-118890").max_torque == pytest.approx(2 * 0.046)
    one = Actuator.mr_pair(2.7e-7, 1e-5, 0.4, 0.085)
    assert one.rotor_inertia == pytest.approx(5.4e-7)
    assert one.damping == pytest.approx(2e-5)
    assert one.max_torque == 0.4  # one clutch pulls in each direction
    assert one.mass == pytest.approx(0.17)
    assert one.delay == 1e-3 and one.kind == "mr"
    assert all(a.delay == 0 for a in ACTUATORS.values() if a.kind == "em")


def test_reflection_eq3_eq4_by_hand():
    act = actuator("maxon-136209")
    p = reflect(act, EM_170)
    r = PULLEY_RATIO / 0.17
    assert p.m1 == pytest.approx(209e-7 * r**2, rel=1e-12)
    assert p.f_max == pytest.approx(0.70 * r, rel=1e-12)
    assert p.k_max == pytest.approx(0.70 * r / EM_170.workspace, rel=1e-12)
    assert (p.k, p.b, p.m2) == (6000.0, 10.0, 14e-3)


@settings(max_examples=40, deadline=None)
@given(
    G=st.floats(0.1, 20.0),
    lever=st.floats(0.02, 0.5),
    name=st.sampled_from(sorted(ACTUATORS)),
)
def test_gearing_and_lever_scaling(G, lever, name):
    act = actuator(name)
    tr = replace(MR_170, lever=lever)
    p1 = reflect(act, tr)
    pG = reflect(act, replace(tr, gearing=G))
    assert pG.m1 == pytest.approx(p1.m1 * G**2, rel=1e-12)
    assert pG.b1 == pytest.approx(p1.b1 * G**2, rel=1e-12)
    assert pG.f_max == pytest.approx(p1.f_max * G, rel=1e-12)
    g = geared(p1, G)
    assert (g.m1, g.b1, g.f_max) == pytest.approx((pG.m1, pG.b1, pG.f_max), rel=1e-12)
    # Eq. 3: m1 ∝ 1/l²
    p2 = reflect(act, replace(tr, lever=2 * lever))
    assert p2.m1 == pytest.approx(p1.m1 / 4, rel=1e-12)


def test_with_lever_scales_rotary_stiffness_and_keeps_m2():
    t = EM_170.with_lever(0.085)
    assert t.k == pytest.approx(4 * EM_170.k) and t.b == pytest.approx(4 * EM_170.b)
    assert t.m2 == EM_170.m2


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"m1": -1e-3}, "m1"),
        ({"m1": 0.0}, "m1"),
        ({"m2": math.nan}, "m2"),
        ({"k": 0.0}, "k"),
        ({"b1": 0.0}, "b1"),
        ({"b": -1.0}, "b"),
        ({"delay": -1e-3}, "delay"),
        ({"f_max": 0.0}, "f_max"),
        ({"f_max": np.array([1.0, math.nan])}, "f_max"),
        ({"m1": np.array([1e-3, 0.0])}, "m1"),
        ({"k": np.array([1e3, math.inf])}, "k"),
    ],
)
def test_bad_haptic_params_name_the_parameter(kwargs, name):
    with pytest.raises(ParameterError, match=rf"^{name} = .*must be"):
        replace(TABLE2_MR, **kwargs)


def test_bad_catalogue_and_transmission():
    with pytest.raises(ParameterError, match="actuator = 'foo': must be one of mr-paper"):
        actuator("foo")
    with pytest.raises(ParameterError, match="lever = 0 m: must be finite and > 0"):
        Transmission(ratio=7.0, lever=0)
    with pytest.raises(ParameterError, match="kind"):
        Actuator("x", "hydraulic", 1e-6, 0.0, 1.0)


def test_vector_fields_broadcast_and_item():
    p = HapticParams(m1=np.array([1e-3, 2e-3, 3e-3]), b1=1.0, k=4000.0, b=20.0, m2=14e-3)
    assert p.shape == (3,)
    assert p.item(1).m1 == 2e-3 and p.item(1).shape == ()
    assert p.item(2).f_max == math.inf  # no force limit by default
    with pytest.raises(ValueError, match="broadcast"):
        HapticParams(m1=np.ones(3), b1=np.ones(2), k=1.0, b=0.0, m2=1.0)
