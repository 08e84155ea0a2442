"""`mrclutch haptic` and `mrclutch compare` end to end."""

import json
import subprocess
import sys

import pytest

from mrclutch.cli.main import main
from mrclutch.haptics.model import METRIC_KEYS


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_haptic_json_keys_and_units(capsys):
    m = _json(capsys, ["haptic", "--actuator", "maxon-136209", "--stiffness", "200", "--json"])
    assert tuple(m) == (*METRIC_KEYS, "source", "nulls")  # nulls: the reason of each null
    assert m["nulls"] == {}  # this pair resonates: no null
    assert m["source"] == "maxon-136209, Table 1 catalogue"
    assert m["K_N_per_m"] == 200.0 and m["delay_s"] == 0.0
    assert m["m1_kg"] == pytest.approx(38.5e-3, abs=0.5e-3)
    # mm/ms at the edge, SI inside: the 75 mm lever multiplies m1 by (170/75)²
    m75 = _json(capsys, ["haptic", "--actuator", "maxon-136209", "--lever-mm", "75", "--json"])
    assert m75["m1_kg"] == pytest.approx(m["m1_kg"] * (170 / 75) ** 2, rel=1e-12)
    g = _json(
        capsys, ["haptic", "--gearing", "4", "--delay-ms", "2", "--workspace-mm", "25", "--json"]
    )
    base = _json(capsys, ["haptic", "--json"])
    assert g["m1_kg"] == pytest.approx(16 * base["m1_kg"]) and g["delay_s"] == 0.002
    assert g["K_N_per_m"] == pytest.approx(base["K_N_per_m"] * 4 * 2)  # F×4, d/2


def test_compare_json_and_plot(capsys, tmp_path):
    png = tmp_path / "out" / "cmp.png"
    r = _json(capsys, ["compare", "--json", "--plot", str(png)])
    assert set(r) >= {
        "mr",
        "em",
        "bandwidth_gain_lumped",
        "bandwidth_gain",
        "damping_ratio_mr_over_em",
        "stable",
    }
    assert tuple(r["mr"]) == METRIC_KEYS and tuple(r["em"]) == METRIC_KEYS
    assert r["mr"]["K_N_per_m"] == r["em"]["K_N_per_m"]
    assert 100 * r["bandwidth_gain_lumped"] == pytest.approx(52.8, abs=1.5)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in png.parent.iterdir()] == ["cmp.png"]  # no temp file left


def test_compare_text_has_closing_note(capsys):
    assert main(["compare", "--stiffness", "1000"]) == 0
    out = capsys.readouterr().out
    assert "MR: passive" not in out and "UNSTABLE" in out  # above the MR's 894 N/m limit


@pytest.mark.parametrize(
    ("argv", "name"),
    [
        (["haptic", "--lever-mm", "-170"], "--lever-mm"),
        (["haptic", "--lever-mm", "nan"], "--lever-mm"),
        (["haptic", "--stiffness", "0"], "--stiffness"),
        (["haptic", "--stiffness", "-5"], "--stiffness"),
        (["haptic", "--gearing", "0"], "--gearing"),
        (["haptic", "--workspace-mm", "0"], "--workspace-mm"),
        (["haptic", "--delay-ms", "-1"], "--delay-ms"),
        (["haptic", "--actuator", "maxon-999"], "--actuator"),
        (["compare", "--stiffness", "inf"], "--stiffness"),
    ],
)
def test_bad_input_one_line_exit_2(capsys, argv, name):
    assert main(argv) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and name in lines[0] and "must" in lines[0]


def test_bad_plot_path_leaves_no_file(tmp_path, capsys):
    target = tmp_path / "cmp.png"
    assert main(["compare", "--stiffness", "-1", "--plot", str(target)]) == 2
    assert not target.exists()


def test_fast_path_imports_nothing_heavy():
    code = (
        "import sys, io, contextlib\n"
        "from mrclutch.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['haptic', '--json'])\n"
        "heavy = [m for m in ('build123d', 'pyvista', 'vtk', 'skfem', 'matplotlib', 'trimesh')"
        " if m in sys.modules]\n"
        "print(heavy)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_subprocess_bad_input_no_traceback():
    r = subprocess.run(
        [sys.executable, "-m", "mrclutch", "haptic", "--actuator", "nope"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1
