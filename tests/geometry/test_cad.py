"""CAD solids against the section's closed-form volumes (the section is the source of truth)."""

import math
from dataclasses import replace

import pytest

from geometry import build_section, preset
from geometry.section import PARTS

pytest.importorskip("build123d")
from geometry.cad import brep_volume_mm3, material_solids, part_solids


@pytest.fixture(scope="module")
def paper():
    c = preset("paper")
    return c, build_section(c), part_solids(c)


def _section_volume_mm3(regions) -> float:
    # revolved rectangle: V = π (r1² − r0²) Δz
    return sum(math.pi * (r.r1**2 - r.r0**2) * (r.z1 - r.z0) for r in regions) * 1e9


def test_every_part_volume_matches_the_section(paper):
    _, s, parts = paper
    assert set(parts) == set(PARTS)
    for name, shape in parts.items():
        assert shape.is_valid
        assert brep_volume_mm3(shape) == pytest.approx(_section_volume_mm3(s.part(name)), rel=1e-9)


def test_material_solids_partition_each_part(paper):
    c, s, parts = paper
    mats = material_solids(c, s)
    for name, shape in parts.items():
        pieces = sum(brep_volume_mm3(v) for (p, _), v in mats.items() if p == name)
        assert pieces == pytest.approx(brep_volume_mm3(shape), rel=1e-9)


def test_hub_holes_remove_exactly_n_cylinders():
    c = preset("paper-holes")
    s = build_section(c)
    rotor = part_solids(c, s)["rotor"]
    hub = s.region("hub")
    # n through-holes of radius a in a hub of thickness h: ΔV = n π a² h
    a_mm, h_mm = c.hub_hole_diameter / 2 * 1e3, (hub.z1 - hub.z0) * 1e3
    removed = c.hub_holes * math.pi * a_mm**2 * h_mm
    expect = _section_volume_mm3(s.part("rotor")) - removed
    assert brep_volume_mm3(rotor) == pytest.approx(expect, rel=1e-9)


def test_bounding_box_is_the_section_envelope(paper):
    _, s, parts = paper
    from build123d import Compound

    bb = Compound(list(parts.values())).bounding_box()
    d, length = s.envelope
    assert bb.size.X == pytest.approx(d * 1e3, rel=1e-6)
    assert bb.size.Z == pytest.approx(length * 1e3, rel=1e-6)
    assert bb.min.Z == pytest.approx(s.z_min * 1e3, abs=1e-6)


@pytest.mark.parametrize("n", [1, 3])
def test_other_drum_counts_still_match(n):
    c = replace(preset("paper"), n_drums=n)
    s = build_section(c)
    rotor = part_solids(c, s)["rotor"]
    assert brep_volume_mm3(rotor) == pytest.approx(_section_volume_mm3(s.part("rotor")), rel=1e-9)
