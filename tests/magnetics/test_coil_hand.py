"""The coil's mass, inertia, resistance and current density pinned to hand-worked values.

The mesh-versus-analytic mass test reads one smeared density on both sides, so a wrong coil
window or fill cancels there; these tests work the paper preset's coil by hand from its
typed dimensions (window 9.0–11.5 mm radius × 8.5 mm band, 140 turns of 0.321 mm bare
copper wire) and [materials] constants.
"""

from __future__ import annotations

import math

import pytest

from geometry.mass import analytic_mass
from geometry.params import preset
from geometry.section import build_section
from magnetics.torque import coil_properties

MM = 1e-3
RHO_CU, RHO_EPOXY = 8960.0, 1200.0  # kg/m³ [materials]; epoxy typical 1.1–1.3 g/cm³


def test_coil_mass_and_inertia_from_fill_and_window():
    """Window volume π(11.5² − 9.0²)·8.5 = 1368.56 mm³; copper area 140·π·0.321²/4 =
    11.330 mm² of a 2.5 × 8.5 = 21.25 mm² window: fill f = 0.53317. Smeared density
    f·8960 + (1 − f)·1200 = 5337.4 kg/m³ → mass 7.3046 g; its axial inertia
    m·(r0² + r1²)/2 = m·(81 + 132.25)/2 mm²."""
    vol = math.pi * (11.5**2 - 9.0**2) * 8.5 * MM**3
    f = 140 * math.pi * 0.321**2 / 4 / (2.5 * 8.5)
    mass = vol * (f * RHO_CU + (1 - f) * RHO_EPOXY)
    assert vol == pytest.approx(1368.56e-9, rel=1e-5)
    assert f == pytest.approx(0.53317, rel=1e-4)
    assert mass == pytest.approx(7.3046e-3, rel=1e-4)
    coil = analytic_mass(build_section(preset("paper"))).parts["coil"]
    assert coil.mass == pytest.approx(mass, rel=1e-9)
    assert coil.inertia == pytest.approx(mass * (9.0**2 + 11.5**2) / 2 * MM**2, rel=1e-9)


def test_coil_resistance_power_and_current_density_by_hand():
    """Mean turn π(9.0 + 11.5) mm = 64.40 mm, × 140 turns = 9.0164 m of wire; area
    π·0.321²/4 = 0.080928 mm²; R20 = 1.72e-8·9.0164/0.080928e-6 = 1.9163 Ω; at 80 °C
    ×(1 + 0.00393·60) = 2.3682 Ω. At 7 A: 93.898 W at 20 °C, J = 7/0.080928 = 86.50 A/mm²,
    980 ampere-turns."""
    c = preset("paper")
    cold = coil_properties(c, 7.0, temperature=20.0)
    hot = coil_properties(c, 7.0, temperature=80.0)
    assert cold.wire_length == pytest.approx(9.0164, rel=1e-4)
    assert cold.resistance == pytest.approx(1.9163, rel=1e-4)
    assert hot.resistance == pytest.approx(1.9163 * (1 + 0.00393 * 60), rel=1e-4)
    assert cold.power == pytest.approx(49 * cold.resistance, rel=1e-12)
    assert cold.power == pytest.approx(93.898, rel=1e-4)
    assert cold.current_density == pytest.approx(86.50e6, rel=1e-3)
    assert cold.ampere_turns == pytest.approx(980.0, rel=1e-12)
