"""CLI end to end: export, inertia (design and CAD file), view, bad input."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from test_help_files import CASES, _check_named

from mrclutch.cli.main import main

pytest.importorskip("build123d")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli")
    assert main(["export", "--preset", "paper", "--out", str(out), "--tolerance-mm", "0.02"]) == 0
    return out


def test_export_writes_step_and_stls(exported):
    """The STEP and a part's STLs, no temporary left, and every file named in ``export
    --help`` and the README (test_help_files.py's check of every command's files, whose
    case for export is this export: one CAD run, not two)."""
    names = {p.name for p in exported.iterdir()}
    assert {"clutch.step", "rotor.stl", "shaft.stl", "housing.stl"} <= names
    assert not [n for n in names if n.startswith(".")]  # no temp files left
    written = sorted(p.relative_to(exported) for p in exported.rglob("*") if p.is_file())
    _check_named("export", written, CASES["export"][1])


def test_inertia_json_three_methods(capsys):
    assert main(["inertia", "--preset", "paper", "--json"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)  # the JSON alone on stdout; the bar of its 4 steps on stderr
    assert "inertia: CAD solids built" in cap.err and "4/4" in cap.err
    ref = out["analytic"]["rotor_inertia_kg_m2"]
    for m in ("analytic", "mesh", "brep"):
        assert out[m]["rotor_inertia_kg_m2"] == pytest.approx(ref, rel=1e-2)
        assert out[m]["rotor_mass_kg"] > 0
    assert out["brep"]["rotor_inertia_kg_m2"] == pytest.approx(ref, rel=1e-6)
    d, length = out["envelope_m"]
    assert 0 < d <= 30e-3 and 0 < length <= 40e-3
    assert out["clutch_mass_kg"] == pytest.approx(out["analytic"]["clutch_mass_kg"], rel=1e-6)


def test_inertia_one_method_is_that_method_alone(capsys):
    """``--method analytic`` (issue 40: the interactive inertia, no CAD solids built) prints
    the analytic rows alone, the same numbers as the analytic row of all three; its clutch
    mass is the analytic one (exact for the preset's axisymmetric section)."""
    from geometry.mass import analytic_mass
    from geometry.params import preset
    from geometry.section import build_section

    assert main(["inertia", "--preset", "paper", "--json", "--method", "analytic"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert cap.err == ""  # no CAD step: no bar
    assert {"mesh", "brep"}.isdisjoint(out) and "analytic" in out
    ref = analytic_mass(build_section(preset("paper")))
    assert out["analytic"]["rotor_inertia_kg_m2"] == ref.rotor_inertia
    assert out["clutch_mass_kg"] == ref.clutch_mass


def test_inertia_of_step_and_stl_files(exported, capsys):
    assert main(["inertia", "--preset", "paper", "--json", "--method", "brep"]) == 0
    ref = json.loads(capsys.readouterr().out)["brep"]["parts"]["shaft"]
    step = exported / "clutch.step"
    args = ["inertia", str(step), "--json", "--density", "1000", "--part-density", "shaft=8000"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "brep"
    assert out["parts"]["shaft"]["inertia_kg_m2"] == pytest.approx(ref["inertia_kg_m2"], rel=1e-9)
    assert out["parts"]["shaft"]["mass_kg"] == pytest.approx(ref["mass_kg"], rel=1e-9)
    stl = exported / "shaft.stl"
    assert main(["inertia", str(stl), "--json", "--density", "8000"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["parts"]["shaft"]["inertia_kg_m2"] == pytest.approx(ref["inertia_kg_m2"], rel=2e-2)
    # about x the shaft (long, on the axis) has a different, larger-lever inertia
    assert main(["inertia", str(stl), "--json", "--density", "8000", "--axis", "x"]) == 0
    out_x = json.loads(capsys.readouterr().out)
    assert out_x["parts"]["shaft"]["inertia_kg_m2"] != pytest.approx(ref["inertia_kg_m2"], rel=0.1)


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["inertia", "--preset", "paper", "--tolerance-mm", "nan"], "--tolerance-mm = nan"),
        (["inertia", "--preset", "nope"], "preset = 'nope': unknown"),
        (["inertia", "missing.step", "--density", "1"], "not found"),
        (["inertia", "--preset", "paper", "--density", "1"], "STEP/STL file only"),
        (["inertia", "missing.step", "--method", "mesh"], "applies to a design"),
        (["export", "--preset", "paper", "--out", "{tmp}", "--tolerance-mm", "-1"], "> 0"),
    ],
)
def test_bad_input_one_line_exit_2(argv, fragment, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path / "o")) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and "\n" not in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_inertia_weighs_the_tools_own_step_export(exported, capsys):
    """Issue 16: the export's sidecar names each solid's material and density, so the
    STEP alone (no --density) gives the analytic rotor inertia and clutch mass (the STEP is
    exact geometry: B-rep volume integrals, 1e-6)."""
    side = json.loads((exported / "clutch.materials.json").read_text())
    mats = {(e["part"], e["material"]) for e in side["solids"]}
    assert {("rotor", "steel_1018"), ("rotor", "stainless_304"), ("coil", "coil")} <= mats
    assert main(["inertia", "--preset", "paper", "--json"]) == 0
    ref = json.loads(capsys.readouterr().out)["analytic"]
    assert main(["inertia", str(exported / "clutch.step"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["output_rotor"]["inertia_kg_m2"] == pytest.approx(
        ref["rotor_inertia_kg_m2"], rel=1e-6
    )
    assert out["output_rotor"]["mass_kg"] == pytest.approx(ref["rotor_mass_kg"], rel=1e-6)
    assert out["total"]["mass_kg"] == pytest.approx(ref["clutch_mass_kg"], rel=1e-6)
    assert out["parts"]["rotor"]["density_from"] == "sidecar"
    assert out["parts"]["rotor"]["materials"] == ["stainless_304", "steel_1018"]
    # a density on the command line wins over the sidecar for that part only
    argv = ["inertia", str(exported / "clutch.step"), "--json", "--part-density", "coil=1000"]
    assert main(argv) == 0
    parts = json.loads(capsys.readouterr().out)["parts"]
    assert parts["coil"]["density_kg_m3"] == 1000 and parts["coil"]["density_from"] == "option"
    assert parts["rotor"]["inertia_kg_m2"] == pytest.approx(out["parts"]["rotor"]["inertia_kg_m2"])


def test_sidecar_of_another_file_or_broken_is_refused(exported, tmp_path, capsys):
    import shutil

    step = tmp_path / "clutch.step"
    shutil.copy(exported / "clutch.step", step)
    side = json.loads((exported / "clutch.materials.json").read_text())
    side["solids"][0]["volume_mm3"] *= 1.5
    (tmp_path / "clutch.materials.json").write_text(json.dumps(side))
    assert main(["inertia", str(step)]) == 2
    assert "written for another file" in capsys.readouterr().err
    (tmp_path / "clutch.materials.json").write_bytes(b"\xff{")
    assert main(["inertia", str(step)]) == 2
    err = capsys.readouterr().err.strip()
    # the bounded reader names the file and why (geometry.reading): one line
    assert "materials sidecar" in err and "not UTF-8 text" in err and "\n" not in err


def test_part_density_errors(exported, tmp_path, capsys):
    import shutil

    step = str(shutil.copy(exported / "clutch.step", tmp_path / "bare.step"))  # no sidecar
    assert main(["inertia", step]) == 2
    assert "no density" in capsys.readouterr().err
    assert main(["inertia", step, "--density", "1", "--part-density", "rotr=7"]) == 2
    assert "rotr: no such part" in capsys.readouterr().err
    assert main(["inertia", step, "--part-density", "rotor"]) == 2
    assert "NAME=KG_M3" in capsys.readouterr().err


def test_view_screenshot_subprocess(tmp_path):
    """``view --screenshot`` in a process of its own (VTK's offscreen window), from a
    scratch folder: a real picture, the one file it leaves, named in ``view --help`` and
    the README (test_help_files.py's check of every command's files, whose case for view
    is this run: one VTK process, not two)."""
    args, user, _ = CASES["view"]
    r = subprocess.run(
        [sys.executable, "-m", "mrclutch", "view", "--preset", "paper", *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    written = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    assert written == [Path("v.png")] and (tmp_path / "v.png").stat().st_size > 10_000
    _check_named("view", written, user)


def test_stl_without_density_names_the_materials_file_beside_it(exported, tmp_path, capsys):
    """Issue 34: the hint points at the export's clutch.materials.json beside the STL and
    what it lists for that part (the rotor mixes two materials: weigh the STEP)."""
    import shutil

    assert main(["inertia", str(exported / "rotor.stl")]) == 2
    err = capsys.readouterr().err.strip()
    assert "clutch.materials.json beside it lists rotor" in err and "\n" not in err
    assert "stainless_304 8000 kg/m³" in err and "steel_1018 7870 kg/m³" in err
    assert "mrclutch inertia clutch.step" in err
    assert main(["inertia", str(exported / "shaft.stl")]) == 2
    err = capsys.readouterr().err
    assert "lists shaft: stainless_304 8000 kg/m³)" in err and "mixes" not in err
    alone = shutil.copy(exported / "coil.stl", tmp_path / "coil.stl")  # no sidecar here
    assert main(["inertia", str(alone)]) == 2
    assert "an STL carries no material" in capsys.readouterr().err
