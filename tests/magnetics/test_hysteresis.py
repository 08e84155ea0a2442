"""magnetics.hysteresis: the Takács loop, the coercive current and the clutch's loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.circuit import path_from_section
from magnetics.hysteresis import (
    HYSTERESIS,
    Hysteresis,
    coercive_current,
    coercive_mmf,
    pulse_train,
    steel_elements,
    torque_loop,
)
from mrclutch.design import design_preset

STEEL = Hysteresis("test", coercivity=100.0, remanence=1.0, saturation=2.0)


def test_coercivity_after_a_peak_hand_worked() -> None:
    """Hc = 100 A/m, Br = 1 T, Js = 2 T: a = Hc/artanh(1/2) = 200/ln 3 = 182.048 A/m.
    Peak Hm = 100 A/m: b = (2/2)·[tanh(200/a) − tanh(0)] = tanh(ln 3) = 0.8 T, so
    Hc(100) = 100 − a·artanh(0.4) = 100·(1 − ln(7/3)/ln 3) = 22.876 A/m. A wrong a (Br),
    b (closure) or Hc (coercivity) term moves it."""
    assert STEEL.shape == pytest.approx(200 / math.log(3), rel=1e-12)
    assert float(STEEL.closure(100.0)) == pytest.approx(0.8, rel=1e-12)
    assert float(STEEL.coercivity_after(100.0)) == pytest.approx(22.876, abs=1e-3)


def test_loop_limits_and_closure() -> None:
    """Far past the knee the loop is the major one (Hc, through (0, Br)); from no peak it
    has no width; the branches meet at the tip ±Hm."""
    assert float(STEEL.coercivity_after(1e6)) == pytest.approx(100.0, rel=1e-9)
    assert float(STEEL.coercivity_after(0.0)) == pytest.approx(0.0, abs=1e-9)
    assert float(STEEL.falling(0.0, 1e6)) == pytest.approx(1.0, rel=1e-9)
    for hm in (30.0, 100.0, 400.0):
        assert float(STEEL.falling(hm, hm)) == pytest.approx(float(STEEL.rising(hm, hm)))
    hc = STEEL.coercivity_after(np.geomspace(1, 1e4, 30))
    assert np.all(np.diff(hc) >= 0) and hc[0] < hc[-1]


def test_bad_data_is_refused() -> None:
    with pytest.raises(ParameterError, match="remanence_T"):
        Hysteresis("x", 100.0, 2.5, 2.0)
    with pytest.raises(ParameterError, match="coercivity_A_per_m"):
        Hysteresis("x", -1.0, 1.0, 2.0)
    with pytest.raises(ParameterError, match="ratio"):
        pulse_train(7.0, ratio=0.5)


def test_every_steel_has_a_loop_with_its_source() -> None:
    assert set(HYSTERESIS) == {"steel_1018", "steel_1010", "steel_1117", "pure_iron",
                               "hiperco_50", "stainless_430"}  # fmt: skip
    for h in HYSTERESIS.values():
        assert h.source and 0 < h.remanence < h.saturation


def test_coercive_mmf_sums_each_element() -> None:
    """Saturated elements hold their major Hc: 100 A/m × 10 mm + 200 A/m × 2 mm = 1.4 A
    (dropping an element, or its length, changes it)."""
    loops = {"core": STEEL, "drums": Hysteresis("b", 200.0, 1.0, 2.0)}
    mmf = coercive_mmf({"core": np.array([0.01]), "drums": np.array([0.002])},
                       {"core": np.array([1e6]), "drums": np.array([1e6])}, loops)  # fmt: skip
    assert float(mmf[0]) == pytest.approx(1.4, rel=1e-6)


def test_paper_steel_path() -> None:
    """The paper clutch's loop: core 14.5 mm and back iron 14.5 mm axially, two poles of
    11.5 − 8.7 = 2.8 mm and six drum walls (0.3 + 0.3 + 0.25 mm per zone) radially:
    36.3 mm of steel 1018. After 7 A (saturated core, Hc,m → 240 A/m) I_c ≤ 240·0.0363/140
    = 0.0622 A; the unsaturated drums hold less, so I_c lies a little below."""
    d = design_preset("paper")
    path = path_from_section(build_section(d.clutch, d.materials))
    total = sum(float(length[0]) for length, _ in steel_elements(path).values())
    assert total == pytest.approx(0.0363, abs=1e-6)
    ic = float(coercive_current(path, [7.0])[0])
    assert 0.8 * 0.0622 < ic < 0.0622
    assert float(coercive_current(path, [0.1])[0]) < ic / 5  # a small peak: a thin loop


def test_torque_loop_of_a_known_curve() -> None:
    """T(I) = I² N·m/A², I_c = 0.5 A: residual T(0.5) = 0.25; at 3 A rising T(2.5) =
    6.25, falling T(3.5) = 12.25."""
    loop = torque_loop(lambda i: np.asarray(i) ** 2, 7.0, 0.5, 15)
    assert loop.residual == pytest.approx(0.25)
    k = int(np.argmin(abs(loop.current - 3.0)))
    assert (loop.rising[k], loop.falling[k]) == pytest.approx((6.25, 12.25))
