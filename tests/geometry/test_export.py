"""STEP/STL export: round trip, watertight STLs, atomic writes."""

import pytest

from geometry import ParameterError, preset

pytest.importorskip("build123d")
trimesh = pytest.importorskip("trimesh")
from geometry.export import export_clutch, read_step_parts, write_stl  # noqa: E402


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("export")
    return export_clutch(preset("paper-holes"), out, 2e-5)


def test_step_round_trip_keeps_names_and_volumes(exported):
    back = exported.step_volumes_mm3
    assert set(back) == set(exported.volumes_mm3) >= {"rotor", "shaft", "housing", "fluid"}
    for name, v in exported.volumes_mm3.items():
        assert back[name] == pytest.approx(v, rel=1e-6)
    assert set(read_step_parts(exported.step)) == set(back)


def test_every_stl_is_watertight_and_close_to_the_brep(exported):
    for name, path in exported.stl.items():
        mesh = trimesh.load_mesh(path)
        assert mesh.is_watertight, name
        # inscribed at 0.02 mm chord height: a little smaller than the exact solid
        assert mesh.volume == pytest.approx(exported.volumes_mm3[name], rel=1e-2)
        assert mesh.volume < exported.volumes_mm3[name]
    assert "rotor" in {p.stem for p in exported.stl.values()}


def test_interrupted_write_leaves_the_old_file(tmp_path, monkeypatch):
    from geometry.cad import part_solids

    shape = part_solids(preset("paper"))["shaft"]
    dest = tmp_path / "shaft.stl"
    dest.write_bytes(b"old")

    def boom(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(trimesh.Trimesh, "export", boom)
    with pytest.raises(KeyboardInterrupt):
        write_stl(shape, dest, 1e-5)
    assert dest.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["shaft.stl"]  # no temp file left


def test_the_folder_holds_the_export_alone(exported):
    """The staging folder is gone once the files are in place, and each path returned is
    in the folder asked for."""
    out = exported.step.parent
    names = {p.name for p in out.iterdir()}
    assert names == {"clutch.step", "clutch.materials.json"} | {f"{n}.stl" for n in exported.stl}
    assert exported.materials.parent == out
    assert all(p.parent == out for p in exported.stl.values())


def _interrupt_second_stl(monkeypatch):
    import geometry.export as ex

    real, calls = ex.write_stl, []

    def write_stl_then_ctrl_c(shape, path, *args):
        calls.append(path)
        if len(calls) == 2:  # clutch.step, its sidecar and one STL written
            raise KeyboardInterrupt
        return real(shape, path, *args)

    monkeypatch.setattr(ex, "write_stl", write_stl_then_ctrl_c)
    return calls


@pytest.mark.slow
def test_an_interrupted_export_is_absent_and_a_previous_one_stays_whole(tmp_path, monkeypatch):
    """Ctrl-C after clutch.step and one STL: a folder the call made is gone again, and a
    folder holding a previous export keeps every one of its files as they were (a STEP
    without its STLs, or a new STEP beside old STLs, was the defect); no staging folder."""
    calls = _interrupt_second_stl(monkeypatch)
    fresh = tmp_path / "fresh"
    with pytest.raises(KeyboardInterrupt):
        export_clutch(preset("paper"), fresh, 1e-4, check=False)
    assert len(calls) == 2 and not fresh.exists()

    old = tmp_path / "old"
    old.mkdir()
    before = {n: f"old {n}" for n in ("clutch.step", "clutch.materials.json", "rotor.stl",
                                      "notes.txt")}  # fmt: skip
    for name, text in before.items():
        (old / name).write_text(text)
    calls.clear()
    with pytest.raises(KeyboardInterrupt):
        export_clutch(preset("paper"), old, 1e-4, check=False)
    assert len(calls) == 2
    assert {p.name: p.read_text() for p in old.iterdir()} == before


@pytest.mark.slow
def test_a_failed_round_trip_writes_nothing(tmp_path, monkeypatch):
    import geometry.export as ex

    monkeypatch.setattr(ex, "read_step_parts", lambda step: {})  # every part lost
    out = tmp_path / "cad"
    with pytest.raises(ParameterError, match="missing after re-import"):
        export_clutch(preset("paper"), out, 1e-4)
    assert not out.exists()


def test_bad_inputs(tmp_path):
    with pytest.raises(ParameterError, match="tolerance"):
        export_clutch(preset("paper"), tmp_path, 0.0)
    with pytest.raises(ParameterError, match="not found"):
        read_step_parts(tmp_path / "nope.step")
    bad = tmp_path / "bad.step"
    bad.write_text("not a step file")
    with pytest.raises(ParameterError, match=r"bad\.step"):
        read_step_parts(bad)


def test_coarse_mesh_losing_volume_is_noted(tmp_path):
    """Issue 16: a chord height far beyond the CLI's ceiling loses a third of the shaft;
    export says so part by part (the fine export of the fixture has no note)."""
    res = export_clutch(preset("paper"), tmp_path, 0.1)
    noted = {n.split(".stl")[0] for n in res.notes}
    assert "shaft" in noted
    for name in noted:
        assert abs(res.stl_volumes_mm3[name] / res.volumes_mm3[name] - 1) > 0.01


def test_fine_export_has_no_volume_note_and_a_sidecar(exported):
    assert exported.notes == ()
    for name, v in exported.volumes_mm3.items():
        assert exported.stl_volumes_mm3[name] == pytest.approx(v, rel=1e-2)
    assert exported.materials.name == "clutch.materials.json"


def test_tolerance_ceiling_is_one_line_with_the_limit():
    from geometry.cad import MAX_RELATIVE_TOLERANCE, check_tolerance, clutch_size

    c = preset("paper")
    top = MAX_RELATIVE_TOLERANCE * clutch_size(c)
    assert check_tolerance("t", top, c) == top
    with pytest.raises(ParameterError, match=r"--tolerance-mm = 100 mm: must be <= 0\.588 mm"):
        check_tolerance("--tolerance-mm", 0.1, c, scale=1e3)


@pytest.mark.slow
def test_the_materials_choice_reaches_the_step_sidecar(tmp_path):
    """Each solid's material, label and density in ``clutch.materials.json`` are the
    design's choice (aluminium housing, MRF-140CG, Hiperco shell), and the STEP's part
    colour is its dominant material's."""
    from geometry.cad import part_material
    from geometry.export import read_materials
    from geometry.materials import COLOUR, DENSITY, MaterialChoice

    ch = MaterialChoice(fluid="MRF-140CG", shell="Hiperco 50", housing="aluminium 6061")
    res = export_clutch(preset("paper"), tmp_path, 1e-4, check=False, materials=ch)
    side = read_materials(res.step)
    mats = {e["material"]: e for e in side.values()}
    assert {"mrf_140cg", "hiperco_50", "aluminium_6061"} <= set(mats)
    assert "stainless_304" in mats  # the bands and hub stay stainless
    for m in ("mrf_140cg", "hiperco_50", "aluminium_6061"):
        assert mats[m]["density_kg_m3"] == DENSITY[m]
    assert mats["hiperco_50"]["label"] == "Hiperco 50 (Co-Fe)"
    assert part_material("housing", ch) == "hiperco_50"
    assert COLOUR[part_material("fluid", ch)] != COLOUR["mrf_132dg"]
