from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry.params import DrumClutch, preset
from geometry.section import build_section
from magnetics.circuit import path_from_section, solve
from magnetics.materials import MU0, linear_materials
from magnetics.torque import max_torque_batch, torque_curve, torque_grid_batch

PAPER = preset("paper")


def _closed_form(c: DrumClutch, current: float, mu_r_fluid: float):
    # Linear, infinitely permeable steel: Φ = 2π μ N I / Σ_k ln(ro/ri)/L_k over the 2n gaps
    # of both zones; the steel walls face each other over the zone, and over the zone plus
    # the end clearance for the outermost gap in zone A (drum and pole both reach the hub).
    s = build_section(c)
    lengths = [c.zone_length] * (2 * len(s.gaps))
    lengths[len(s.gaps) - 1] += c.end_clearance
    gaps = list(s.gaps) * 2
    rsum = sum(np.log(g.r_outer / g.r_inner) / L for g, L in zip(gaps, lengths, strict=True))
    phi = 2 * np.pi * MU0 * mu_r_fluid * c.coil_turns * current / rsum
    return np.array([phi / (2 * np.pi * g.r_mean * L) for g, L in zip(gaps, lengths, strict=True)])


@settings(max_examples=25, deadline=None)
@given(i=st.floats(0.01, 50), mu_f=st.floats(1, 10), gap_mm=st.floats(0.2, 1.5))
def test_linear_limit_axisymmetric_closed_form(i, mu_f, gap_mm):
    """Very permeable linear steel: gap B equals Φ/(2π r L), Φ = 2π μ N I / Σ ln(ro/ri)/L."""
    c = replace(PAPER, gap=gap_mm * 1e-3)
    mats = linear_materials(1e12, mu_f)
    res = solve(c, [i], materials=mats)
    expected = _closed_form(c, i, mu_f)
    # leakage across the band needs no MMF from infinitely permeable steel: exact
    np.testing.assert_allclose(res.gap_b[0, 0], expected, rtol=1e-6)


def test_linear_limit_planar_formula_for_a_thin_large_radius_stack():
    """μ0 μr N I / (L Σ g/L) within the geometric bound Δr/r of a stack at large radius."""
    # the largest stack the haptic envelope admits (geometry.params.MAX_OUTER_DIAMETER)
    c = DrumClutch(n_drums=1, gap=0.1e-3, drum_thickness=0.02e-3, drum_inner_diameter=0.28,
                   coil_turns=140)  # fmt: skip
    mats = linear_materials(1e12, 5.0)
    res = solve(c, [2.0], materials=mats)
    # planar series of the four gap entries: B_k = μ N I / (L_k Σ_j g/L_j)
    lengths = np.array([1, 1, 1, 1]) * c.zone_length + np.array([0, 1, 0, 0]) * c.end_clearance
    planar = MU0 * 5.0 * 140 * 2.0 / (lengths * np.sum(c.gap / lengths))
    spread = (c.drum_radii_out[0][1] + c.gap - c.core_radius) / c.core_radius
    np.testing.assert_allclose(res.gap_b[0, 0], planar, rtol=spread)
    assert spread < 2e-3  # the bound is tight: the planar limit is really tested


def test_path_read_from_the_table_matches_closed_forms():
    """The loop the circuit reads from the region table: gaps carry flux over the zone (the
    outermost gap in zone A over the zone plus the end clearance, where drum and pole both
    reach the hub), drum walls over the zone, core and back iron between the zone centres,
    the band's series reluctance over fluid gaps and stainless walls."""
    c = replace(PAPER, n_drums=3)
    path = path_from_section(build_section(c))
    n, zone, cl = c.n_drums, c.zone_length, c.end_clearance
    expected = np.full(4 * n, zone)
    expected[2 * n - 1] += cl
    np.testing.assert_allclose(path.gap_len[0], expected, rtol=1e-12)
    np.testing.assert_allclose(path.drum_len[0], zone, rtol=1e-12)
    assert path.drum_len.shape[1] == 2 * (2 * n - 1)
    np.testing.assert_allclose(path.core_area, np.pi * c.core_radius**2, rtol=1e-12)
    np.testing.assert_allclose(path.core_len, zone + c.band_length, rtol=1e-12)
    np.testing.assert_allclose(
        path.back_area, np.pi * (c.outer_radius**2 - c.coil_outer_radius**2), rtol=1e-12
    )
    ln_gaps = sum(np.log(g.r_outer / g.r_inner) for g in build_section(c).gaps)
    ln_all = np.log(c.pole_radius / c.core_radius)
    mu_f = MU0 * 5.0
    mats = linear_materials(1e4, 5.0)
    sb = path_from_section(build_section(c), mats).band_reluctance
    np.testing.assert_allclose(sb, ln_gaps / mu_f + (ln_all - ln_gaps) / MU0, rtol=1e-12)


def test_batch_solvers_match_the_design_solve():
    """Arrays of designs: the per-design Newton (rtol 1e-7) and the tabulate-and-invert grid
    (1e-3 by construction) against the one-design solve."""
    t = torque_curve(PAPER, [0.5, 3.0, 7.0], method="circuit").yield_torque
    np.testing.assert_allclose(max_torque_batch({}, [0.5, 3.0, 7.0][2]), t[2], rtol=1e-8)
    np.testing.assert_allclose(torque_grid_batch({}, [0.5, 3.0, 7.0])[0], t, rtol=1e-3)


def test_robust_extreme_currents_finite_monotone():
    tc = torque_curve(PAPER, [0.0, 1e-6, 1.0, 7.0, 100.0, 1000.0], method="circuit")
    assert np.all(np.isfinite(tc.torque))
    assert np.all(np.diff(tc.torque) >= 0)
    assert tc.yield_torque[0] == 0.0
    assert tc.torque[0] == pytest.approx(tc.off_state_torque)


def test_saturation_is_reported_in_the_back_iron():
    res = solve(PAPER, [0.5, 7.0])
    assert not res.saturated["back_iron"][0, 0]
    assert res.saturated["back_iron"][0, 1]


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0, 200), min_size=2, max_size=8))
def test_torque_monotone_in_current(currents):
    i = np.sort(np.array(currents))
    t = torque_curve(PAPER, i, method="circuit").yield_torque
    assert np.all(np.diff(t) >= -1e-12 * t.max(initial=1.0))


@settings(max_examples=20, deadline=None)
@given(g1=st.floats(0.2, 1.4), dg=st.floats(0.01, 0.5))
def test_torque_falls_with_gap_at_fixed_ampere_turns_below_saturation(g1, dg):
    """Below saturation (1 A) a wider gap means less field and less torque (same NI)."""
    t = max_torque_batch({"gap": np.array([g1, g1 + dg]) * 1e-3}, 1.0)
    assert t[1] < t[0]


def test_steel_flux_density_of_the_drums_by_hand():
    """The drums carry the gap flux radially through their walls over the 6 mm zone; the
    largest |B| is at the smallest wall radius, the first output drum's 5.75 mm:
    B = Φ/(2π·5.75 mm·6 mm), one value per current (a mutant that took the maximum over
    the currents instead of the drums survived the suite). The core carries Φ over
    π·5.05²."""
    res = solve(preset("paper"), [2.0, 7.0])
    phi = np.abs(res.flux[0])
    drums = np.asarray(res.steel_b["drums"])
    assert drums.shape == (1, 2)
    np.testing.assert_allclose(drums[0], phi / (2 * np.pi * 5.75e-3 * 6e-3), rtol=1e-12)
    np.testing.assert_allclose(res.steel_b["core"][0], phi / (np.pi * 5.05e-3**2), rtol=1e-12)
