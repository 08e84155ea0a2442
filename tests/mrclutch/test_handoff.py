"""The hand-offs of issue 42 beside FEMM and ONELAB: the material tables, the torque
map, the device description, the DXF and the drawing — each read back; bad options are
one line and exit 2; an unwritable folder leaves no file."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

import numpy as np
import pytest

from geometry import build_section, preset
from magnetics.materials import FLUIDS, MATERIALS, BHCurve
from mrclutch.cli.main import main
from mrclutch.design import design_preset
from mrclutch.handoff import MAP_COLUMNS, torque_map


def _rows(path: Path) -> list[dict[str, str]]:
    lines = [x for x in path.read_text().splitlines() if not x.startswith("# ")]
    return list(csv.DictReader(lines))


def test_materials_export_round_trips_every_table(tmp_path: Path) -> None:
    assert main(["tables", "--export", str(tmp_path)]) == 0
    index = _rows(tmp_path / "materials.csv")
    assert {r["name"] for r in index} >= {"steel_1018", "mrf_132dg", "stainless_304"}
    for r in index:
        m = MATERIALS[r["name"]]
        if isinstance(m, BHCurve):
            bh = _rows(tmp_path / f"{r['name']}_bh.csv")
            assert [float(x["B_T"]) for x in bh] == pytest.approx(m.b_table, rel=1e-9)
            assert [float(x["H_A_per_m"]) for x in bh] == pytest.approx(m.h_table, rel=1e-9)
            assert "source:" in (tmp_path / f"{r['name']}_bh.csv").read_text()
    fl = FLUIDS["mrf_132dg"]
    tau = _rows(tmp_path / "mrf_132dg_tau_y.csv")
    h = np.array([float(x["H_A_per_m"]) for x in tau])
    assert [float(x["tau_y_Pa"]) for x in tau] == pytest.approx(fl.tau_y(h), rel=1e-9)
    visc = _rows(tmp_path / "mrf_132dg_viscosity.csv")
    row40 = next(x for x in visc if float(x["T_C"]) == 40.0)
    assert float(row40["eta_Pa_s"]) == pytest.approx(0.112, rel=1e-9)  # the datasheet point


def test_torque_map_off_state_is_the_zero_current_row_and_rises_with_speed() -> None:
    """At 0 A the torque is the drag alone; the drag grows with the slip speed and falls
    as the fluid warms (its viscosity falls); the yield part does not depend on either."""
    m = torque_map(design_preset("paper"), [0.0, 2.0, 7.0], [0.0, 530.0], [20.0, 60.0])
    assert set(m) == set(MAP_COLUMNS) and m["current_A"].size == 12
    zero = m["current_A"] == 0
    assert np.allclose(m["torque_N_m"][zero], m["off_state_torque_N_m"][zero])
    assert np.allclose(m["torque_N_m"], m["yield_torque_N_m"] + m["off_state_torque_N_m"])
    at = {(s, t): m["off_state_torque_N_m"][zero & (m["slip_speed_rpm"] == s)
                                           & (m["fluid_temperature_C"] == t)][0]
          for s in (0.0, 530.0) for t in (20.0, 60.0)}  # fmt: skip
    assert at[(530.0, 20.0)] > at[(0.0, 20.0)] and at[(530.0, 20.0)] > at[(530.0, 60.0)]
    seven = m["yield_torque_N_m"][m["current_A"] == 7.0]
    assert np.ptp(seven) == 0.0 and seven[0] > 0.3


def test_torque_map_cli_csv_and_parquet(tmp_path: Path) -> None:
    assert main(["torque", "--current", "0,7", "--map", str(tmp_path / "m.csv"),
                 "--map-speeds-rpm", "0,530", "--map-temperatures-C", "20"]) == 0  # fmt: skip
    rows = _rows(tmp_path / "m.csv")
    assert len(rows) == 4 and list(rows[0]) == list(MAP_COLUMNS)
    assert main(["torque", "--current", "0,7", "--map", str(tmp_path / "m.parquet")]) == 0
    import pyarrow.parquet as pq

    assert pq.read_table(tmp_path / "m.parquet").num_rows == 2 * 4 * 3


def test_device_description_schema(tmp_path: Path) -> None:
    out = tmp_path / "dev.json"
    assert main(["device", "--preset", "paper", "--out", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["schema"] == "mrclutch.device/1"
    assert d["force_max_N"] > 0 and d["K_max_N_per_m"] > 0
    poly = np.array(d["passive_region"]["polygon_K_N_per_m_B_N_s_per_m"])
    assert poly.shape[1] == 2 and poly.shape[0] >= 3
    # the polygon starts at (largest passive K at B = 0, 0)
    assert poly[0] == pytest.approx([d["max_passive_K_N_per_m"], 0.0])
    assert len(d["passive_region"]["vertices_stable"]) == poly.shape[0]
    bw = [x["bandwidth_hz"] for x in d["bandwidth_hz"]]
    assert all(b > 0 for b in bw) and bw == sorted(bw)  # stiffer spring, wider band
    assert d["delay_s"] == pytest.approx(1e-3)
    assert d["damping_N_s_per_m"]["intrinsic_b1"] > 0


def test_dxf_has_a_layer_per_part_and_material(tmp_path: Path) -> None:
    import ezdxf

    assert main(["export", "--preset", "paper", "--format", "dxf", "--out", str(tmp_path)]) == 0
    doc = ezdxf.readfile(tmp_path / "paper.dxf")
    s = build_section(preset("paper"))
    polys = list(doc.modelspace().query("LWPOLYLINE"))
    assert len(polys) == len(s.regions)
    assert {p.dxf.layer for p in polys} == {f"{g.part}-{g.material}" for g in s.regions}
    core = s.region("core")
    pts = {tuple(round(c, 6) for c in p[:2]) for q in polys if q.dxf.layer == "housing-steel_1018"
           for p in q.get_points()}  # fmt: skip
    assert (round(core.r1 * 1e3, 6), round(core.z0 * 1e3, 6)) in pts


def test_drawing_carries_the_process_tolerance(tmp_path: Path) -> None:
    assert main(["export", "--preset", "paper", "--format", "drawing", "--out",
                 str(tmp_path)]) == 0  # fmt: skip
    svg = (tmp_path / "paper.svg").read_text()
    assert svg.startswith("<?xml") and "</svg>" in svg
    # the process defaults: IT band 0.02 mm -> ±0.01 mm on every diameter, runout 0.03 mm TIR
    assert svg.count("±0.01") >= 2 * 2 + 1 and "0.03 mm TIR" in svg
    assert "Ø25.800" in svg  # the housing: 2 × 12.9 mm


@pytest.mark.parametrize("argv", [
    ["export", "--format", "iges", "--out", "X"],
    ["export", "--format", "dxf", "--current", "3", "--out", "X"],
    ["torque", "--map", "X.xlsx"],
    ["torque", "--map", "X.csv", "--map-speeds-rpm", "fast"],
])  # fmt: skip
def test_bad_options_are_one_line_and_exit_2(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [str(tmp_path / a) if a.startswith("X") else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "error" in err
    assert not any(tmp_path.iterdir())


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
def test_unwritable_folder_leaves_no_file(tmp_path: Path) -> None:  # pragma: no cover
    tmp_path.chmod(0o500)
    try:
        assert main(["export", "--format", "femm", "--out", str(tmp_path / "x")]) == 2
    finally:
        tmp_path.chmod(0o700)
    assert not any(tmp_path.iterdir())


def test_a_failing_write_leaves_no_partial_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A disk that fills mid-write: one line, exit 2, and neither file nor temporary left
    (the output layer, geometry.atomic)."""
    import geometry.atomic as atomic

    real = atomic.os.fsync

    def full(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full)
    assert main(["export", "--format", "femm", "--out", str(tmp_path)]) == 2
    monkeypatch.setattr(atomic.os, "fsync", real)
    assert list(tmp_path.iterdir()) == []
