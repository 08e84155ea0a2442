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


def test_bad_inputs(tmp_path):
    with pytest.raises(ParameterError, match="tolerance"):
        export_clutch(preset("paper"), tmp_path, 0.0)
    with pytest.raises(ParameterError, match="not found"):
        read_step_parts(tmp_path / "nope.step")
    bad = tmp_path / "bad.step"
    bad.write_text("not a step file")
    with pytest.raises(ParameterError, match=r"bad\.step"):
        read_step_parts(bad)
