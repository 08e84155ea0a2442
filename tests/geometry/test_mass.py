"""Three mass methods compared field by field, and the mesh guard shown at work."""

from dataclasses import replace

import numpy as np
import pytest

from geometry import ParameterError, build_section, preset
from geometry.mass import analytic_mass, brep_mass, check_mesh, mesh_mass

pytest.importorskip("build123d")
trimesh = pytest.importorskip("trimesh")
from geometry.cad import material_solids  # noqa: E402


@pytest.fixture(scope="module")
def paper():
    c = preset("paper")
    return c, material_solids(c)


@pytest.fixture(scope="module")
def holes():
    c = preset("paper-holes")
    return c, material_solids(c)


def test_brep_equals_analytic_for_the_axisymmetric_preset(paper):
    c, solids = paper
    a, b = analytic_mass(build_section(c)), brep_mass(c, solids)
    for part, pa in a.parts.items():
        assert b.parts[part].mass == pytest.approx(pa.mass, rel=1e-6), part
        assert b.parts[part].inertia == pytest.approx(pa.inertia, rel=1e-6), part
    assert b.rotor_inertia == pytest.approx(a.rotor_inertia, rel=1e-6)


def test_mesh_converges_to_brep_within_its_error_estimate(paper):
    c, solids = paper
    b = brep_mass(c, solids)
    m = mesh_mass(c, 1e-5, solids=solids, rtol=2e-3)
    assert m.method == "mesh"
    # the inscribed mesh is inside the solid: it never weighs more than the B-rep
    assert m.rotor_inertia <= b.rotor_inertia
    assert m.rotor_inertia == pytest.approx(b.rotor_inertia, rel=4e-3)
    assert m.clutch_mass == pytest.approx(b.clutch_mass, rel=4e-3)


def test_holes_mesh_and_brep_agree_analytic_says_it_is_blind(holes):
    c, solids = holes
    a, b = analytic_mass(build_section(c)), brep_mass(c, solids)
    m = mesh_mass(c, 1e-5, solids=solids, rtol=1e-3)
    drop = 1 - b.rotor_inertia / a.rotor_inertia  # what the holes take away
    assert drop > 5e-3
    assert abs(m.rotor_inertia / b.rotor_inertia - 1) < drop / 3
    assert any("does not see" in n for n in a.notes)
    assert any("hub holes" in n for n in b.notes + m.notes)


def test_mesh_error_falls_linearly_with_chord_height(paper):
    """Chord-height theory: sagitta δ ⇒ relative volume error ∝ δ/r (slope 1 in log–log)."""
    c, solids = paper
    key = ("rotor", "steel_1018")
    exact = brep_mass(c, {key: solids[key]}).parts["rotor"].inertia
    tols = np.array([4e-5, 2e-5, 1e-5, 5e-6])
    errs = [
        abs(
            mesh_mass(c, t, guard=False, solids={key: solids[key]}).parts["rotor"].inertia / exact
            - 1
        )
        for t in tols
    ]
    slope = np.polyfit(np.log(tols), np.log(errs), 1)[0]
    assert 0.7 < slope < 1.3, (slope, errs)


def test_coarse_thin_drum_unguarded_is_wrong_guard_refines():
    """A 0.05 mm drum meshed at 0.3 mm with a loose angular limit: the raw mesh is several %
    off (more than the holes' effect); the guard refines until the estimate is below rtol."""
    c = replace(preset("paper"), drum_thickness=0.05e-3)
    solids = material_solids(c)
    b = brep_mass(c, solids)
    raw = mesh_mass(c, 3e-4, angular_tolerance=6.0, guard=False, solids=solids)
    assert abs(raw.rotor_inertia / b.rotor_inertia - 1) > 0.02
    safe = mesh_mass(c, 3e-4, angular_tolerance=6.0, rtol=5e-3, solids=solids)
    assert abs(safe.rotor_inertia / b.rotor_inertia - 1) < 1e-2
    assert any("refined" in n for n in safe.notes)


def test_many_small_holes_coarse_mesh_cannot_see_them_guard_can():
    c = replace(preset("paper"), hub_holes=24, hub_hole_diameter=0.4e-3, hub_hole_pitch_radius=4e-3)
    solids = material_solids(c)
    a, b = analytic_mass(build_section(c)), brep_mass(c, solids)
    hole_effect = abs(a.rotor_inertia - b.rotor_inertia)
    raw = mesh_mass(c, 3e-4, angular_tolerance=6.0, guard=False, solids=solids)
    assert abs(raw.rotor_inertia - b.rotor_inertia) > 5 * hole_effect  # error swamps the holes
    safe = mesh_mass(c, 3e-4, angular_tolerance=6.0, rtol=1e-3, solids=solids)
    assert abs(safe.rotor_inertia - b.rotor_inertia) < 3e-3 * b.rotor_inertia


def test_guard_refuses_an_open_mesh():
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    check_mesh(box, "box")  # closed: accepted
    holed = trimesh.Trimesh(box.vertices, box.faces[:-1], process=True)
    # unguarded, the open mesh still yields a plausible-looking but wrong volume
    assert holed.volume != pytest.approx(box.volume, rel=1e-3)
    with pytest.raises(ParameterError, match="not watertight"):
        check_mesh(holed, "box")


def test_guard_refuses_when_it_cannot_converge(paper):
    c, solids = paper
    with pytest.raises(ParameterError, match="not converged"):
        mesh_mass(c, 1e-4, solids=solids, rtol=1e-9, max_refinements=1)


def test_bad_tolerance_is_named(paper):
    c, solids = paper
    with pytest.raises(ParameterError, match="tolerance"):
        mesh_mass(c, -1.0, solids=solids)


def test_thinnest_feature_is_the_thinnest_wall_or_the_hole_radius():
    """The paper preset's thinnest feature is the 0.2 mm fluid film of the shaft's bore
    clearance; 24 hub holes of 0.3 mm diameter have a 0.15 mm radius, thinner still (a
    mutant that doubled the diameter instead of halving it survived the suite)."""
    from geometry.mass import thinnest_feature

    c = preset("paper")
    assert thinnest_feature(c) == pytest.approx(0.2e-3, rel=1e-9)
    holes = replace(c, hub_holes=24, hub_hole_diameter=0.3e-3, hub_hole_pitch_radius=4e-3)
    assert thinnest_feature(holes) == pytest.approx(0.15e-3, rel=1e-9)
