"""The section is the single source of truth: check it against closed forms and invariants."""

import math
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry import ParameterError, build_section, preset
from geometry.mass import analytic_mass
from geometry.params import DrumClutch


def _overlap(a, b) -> float:
    dr = min(a.r1, b.r1) - max(a.r0, b.r0)
    dz = min(a.z1, b.z1) - max(a.z0, b.z0)
    return dr * dz if dr > 1e-12 and dz > 1e-12 else 0.0


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_regions_do_not_overlap_and_fill_the_cavity(n):
    c = replace(preset("paper"), n_drums=n)
    s = build_section(c)
    regs = s.regions
    for i, a in enumerate(regs):
        assert a.r1 > a.r0 and a.z1 > a.z0, a
        for b in regs[i + 1 :]:
            assert _overlap(a, b) == 0.0, (a.name, b.name)
    # The cavity r < pole radius between the caps is exactly covered (solids + fluid).
    t = c.end_cap_thickness
    z1 = s.region("cap_back").z0
    cavity = c.pole_radius * (z1 - t)
    inside = sum(_overlap(r, type(r)("c", "", "", 0.0, c.pole_radius, t, z1)) for r in regs)
    assert inside == pytest.approx(cavity, rel=1e-12)


@pytest.mark.parametrize("n", [1, 2, 4])
def test_gap_count_and_widths(n):
    c = replace(preset("paper"), n_drums=n)
    s = build_section(c)
    assert len(s.gaps) == 2 * n
    assert len(c.drum_radii_in) == n - 1
    for g in s.gaps:
        assert g.width == pytest.approx(c.gap, rel=1e-12)
        assert g.z1 > g.z0
        # every gap spans both active zones
        for z in s.zones:
            assert g.z0 <= z.z0 and z.z1 <= g.z1
    # walls alternate: output side | input side
    names = [g.inner_wall for g in s.gaps]
    assert names[0] == "core" and s.gaps[-1].outer_wall == "shell"


def test_analytic_inertia_of_a_single_drum_closed_form():
    """Inertia of one output drum region equals m (r0² + r1²)/2 of a thick tube."""
    s = build_section(preset("paper"))
    reg = s.region("out1_A")
    rho = s.densities[reg.material]
    m = rho * math.pi * (reg.r1**2 - reg.r0**2) * (reg.z1 - reg.z0)
    single = type(s)(s.clutch, (reg,), (), (), (), s.densities)
    rep = analytic_mass(single)
    assert rep.parts["rotor"].inertia == pytest.approx(m * (reg.r0**2 + reg.r1**2) / 2, rel=1e-14)


def test_paper_preset_matches_table_1():
    """Lebel et al. [lebel] Table 1: 2.7 g·cm² (±10 %), 85 g (±15 %), within 30×30×40 mm."""
    s = build_section(preset("paper"))
    m = analytic_mass(s)
    assert m.rotor_inertia == pytest.approx(2.7e-7, rel=0.10)
    assert m.clutch_mass == pytest.approx(85e-3, rel=0.15)
    d, length = s.envelope
    assert d <= 30e-3 and length <= 40e-3
    assert s.clutch.coil_turns == 140 and s.clutch.wire_diameter == pytest.approx(0.321e-3)


@settings(max_examples=40, deadline=None)
@given(k=st.floats(0.5, 3.0))
def test_inertia_scales_as_length_to_the_fifth(k):
    """Scaling every length by k scales mass by k³ and inertia by k⁵."""
    from dataclasses import fields

    c = preset("paper")
    big = DrumClutch(
        **{
            f.name: (
                getattr(c, f.name) * k
                if isinstance(getattr(c, f.name), float)
                else getattr(c, f.name)
            )
            for f in fields(c)
        }
    )
    # the wire scales too, so the coil still fits
    a, b = analytic_mass(build_section(c)), analytic_mass(build_section(big))
    assert b.rotor_inertia == pytest.approx(a.rotor_inertia * k**5, rel=1e-9)
    assert b.clutch_mass == pytest.approx(a.clutch_mass * k**3, rel=1e-9)


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        ({"gap": 0.05e-3}, "gap = 5e-05 m: must be in [0.0001"),
        ({"gap": float("nan")}, "gap = nan: must be finite"),
        ({"drum_thickness": -1e-3}, "drum_thickness = -0.001 m: must be in"),
        ({"n_drums": 0}, "n_drums = 0: must be an integer in [1, 20]"),
        ({"coil_turns": 1000}, "coil_turns = 1000: does not fit the coil window"),
        ({"drum_inner_diameter": 0.5e-3}, "drum_inner_diameter = 0.0005 m: must exceed"),
        ({"hub_holes": 6, "hub_hole_diameter": 5e-3}, "hub_hole_pitch_radius"),
        ({"hub_holes": 40, "hub_hole_diameter": 1.0e-3}, "hub_holes = 40: holes of 1 mm"),
    ],
)
def test_validation_names_parameter_value_and_range(change, fragment):
    with pytest.raises(ParameterError, match=None) as exc:
        replace(preset("paper"), **change)
    assert fragment in str(exc.value)


def test_design_mapping_round_trip_and_strict_keys():
    c = preset("paper")
    assert DrumClutch.from_mm(c.to_mm()) == c
    with pytest.raises(ParameterError, match="gap: lengths need their unit"):
        DrumClutch.from_mm({"gap": 0.3}, base=c)
    with pytest.raises(ParameterError, match="gapp_mm: unknown key"):
        DrumClutch.from_mm({"gapp_mm": 0.3}, base=c)
    with pytest.raises(ParameterError, match=r"n_drums = 2\.0: must be an integer"):
        DrumClutch.from_mm({"n_drums": 2.0}, base=c)
    with pytest.raises(ParameterError, match="missing"):
        DrumClutch.from_mm({"gap_mm": 0.3})
