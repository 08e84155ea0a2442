"""Lebel et al., Fig. 2b and Table 2, against the `paper` preset (circuit model)."""

import numpy as np
import pytest

from geometry.params import preset
from magnetics.torque import rpm_to_rad_s, torque_curve

PAPER = preset("paper")


@pytest.mark.xfail(
    strict=True,
    reason="known shortfall: with the band field the circuit gives T(7 A) = 0.447 N·m "
    "(FEM 0.46); the preset has not been re-tuned yet (docs/magnetics.md)",
)
def test_fig_2b_torque_at_7_amperes():
    tc = torque_curve(PAPER, [7.0], speed_rpm=530)
    assert tc.torque[0] == pytest.approx(0.40, rel=0.10)


def test_fig_2b_torque_current_curve():
    i = np.arange(0.0, 7.01, 0.5)
    tc = torque_curve(PAPER, i, speed_rpm=530)
    t7, t4 = tc.torque[-1], tc.torque[i == 4.0][0]
    m = (i >= 1) & (i <= 4)
    p = np.polyfit(i[m], tc.torque[m], 1)
    resid = tc.torque[m] - np.polyval(p, i[m])
    r2 = 1 - resid @ resid / np.sum((tc.torque[m] - tc.torque[m].mean()) ** 2)
    assert r2 >= 0.98
    assert t7 - t4 < 0.25 * t4
    assert tc.yield_torque[0] == 0.0 and tc.torque[0] == pytest.approx(tc.viscous_torque)


def test_viscous_damping_against_table_2_b1():
    """b1 = 1.0 N·s/m for the pair at the 170 mm lever, pulley ratio n ≈ 7.3:
    per clutch c = b1·l²/n²/2. The model (Newtonian films only) is lower; report ratio."""
    c_paper = 1.0 * 0.170**2 / 7.3**2 / 2
    tc = torque_curve(PAPER, [0.0], speed_rpm=530)
    ratio = tc.damping / c_paper
    assert tc.viscous_torque == pytest.approx(tc.damping * rpm_to_rad_s(530))
    assert 0.05 < ratio < 1.0  # seals, bearings and shear thinning are not modelled
