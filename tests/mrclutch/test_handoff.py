"""The hand-offs of issue 42 beside FEMM and ONELAB: the material tables, the torque
map, the device description, the DXF and the drawing — each read back; bad options are
one line and exit 2; an unwritable folder leaves no file."""

from __future__ import annotations

import csv
import json
import os
import re
from pathlib import Path
from xml.etree import ElementTree

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


def test_materials_export_has_hysteresis_tau_y_of_t_and_life(tmp_path: Path) -> None:
    """Issue 41's data in the tables: each steel's Hc, Br and Js, each fluid's τy(T) (its
    table and its coefficient at 20 °C) and lifetime dissipated energy, with sources and
    the fields marked unverified — read back against the library."""
    from geometry.materials import RECORDS, is_builtin
    from magnetics.hot import phi_at, tau_y_coefficient, tau_y_factor
    from magnetics.hysteresis import HYSTERESIS

    assert main(["tables", "--export", str(tmp_path)]) == 0
    steels = {r["name"]: r for r in _rows(tmp_path / "hysteresis.csv")}
    assert set(steels) == set(HYSTERESIS) >= {"steel_1018", "pure_iron"}
    for name, hy in HYSTERESIS.items():
        r = steels[name]
        assert float(r["coercivity_A_per_m"]) == pytest.approx(hy.coercivity, rel=1e-9)
        assert float(r["remanence_T"]) == pytest.approx(hy.remanence, rel=1e-9)
        assert float(r["saturation_polarisation_T"]) == pytest.approx(hy.saturation, rel=1e-9)
        assert r["source"] == hy.source
        fields = ("hysteresis.coercivity_A_per_m", "hysteresis.remanence_T")
        marked = [f for f in fields if f in RECORDS[name].get("unverified", [])]
        assert r["unverified"].split() == (marked or ["-"])
    index = {r["name"]: r["tables"].split() for r in _rows(tmp_path / "materials.csv")}
    assert "hysteresis.csv" in index["steel_1018"] and "fluids.csv" in index["mrf_132dg"]
    fluids = {r["name"]: r for r in _rows(tmp_path / "fluids.csv")}
    assert set(fluids) == set(FLUIDS)
    for name, fl in FLUIDS.items():
        r = fluids[name]
        # the tables' 10 significant digits (a user's fuzzed fluid has more than a library's)
        assert float(r["iron_fraction"]) == pytest.approx(fl.phi, rel=1e-9)
        assert float(r["tau_y_max_Pa"]) == pytest.approx(fl.tau_y_max, rel=1e-9)
        life = r["lifetime_dissipated_energy_J_per_m3"]
        assert (life == "") if fl.lifetime_energy is None else (
            float(life) == pytest.approx(fl.lifetime_energy, rel=1e-9))  # fmt: skip
        if not is_builtin(name):  # a user's fluid file an earlier test in this process read
            continue  # (the registry is the process's): no library record to read back
        assert float(life) == fl.lifetime_energy  # every library fluid has its figure
        assert float(r["tau_y_temperature_coefficient_per_K"]) == pytest.approx(
            tau_y_coefficient(fl), rel=1e-9)  # fmt: skip
        assert r["lifetime_dissipated_energy_source"] == RECORDS[name][
            "lifetime_dissipated_energy_source"]  # fmt: skip
        assert "lifetime_dissipated_energy" in r["unverified"].split()  # as the files say
        table = _rows(tmp_path / f"{name}_tau_y_temperature.csv")
        t = np.array([float(x["T_C"]) for x in table])
        assert (t[0], t[-1]) == fl.temperature_range
        ratio = np.array([float(x["tau_y_ratio"]) for x in table])
        assert ratio == pytest.approx(tau_y_factor(fl, t), rel=1e-9)
        phi = [float(x["iron_fraction"]) for x in table]
        assert phi == pytest.approx(phi_at(fl.phi, fl.carrier_expansion, t), rel=1e-9)
        assert ratio[t == 20.0] == pytest.approx(1.0) and np.all(np.diff(ratio) < 0)
        head = (tmp_path / f"{name}_tau_y_temperature.csv").read_text().split("\n", 2)[1]
        assert head.startswith("# source: ") and "[carlson]" in head


def test_torque_map_off_state_is_the_zero_current_row_and_rises_with_speed() -> None:
    """At 0 A the torque is the drag alone; the drag grows with the slip speed and falls
    as the fluid warms (its viscosity falls); the yield part does not depend on the speed
    and falls with the temperature by τy(T)/τy(20 °C) (magnetics.hot, as in a duty)."""
    from magnetics.hot import tau_y_factor
    from magnetics.torque import torque_curve

    design = design_preset("paper")
    m = torque_map(design, [0.0, 2.0, 7.0], [0.0, 530.0], [20.0, 60.0])
    assert set(m) == set(MAP_COLUMNS) and m["current_A"].size == 12
    zero = m["current_A"] == 0
    assert np.allclose(m["torque_N_m"][zero], m["off_state_torque_N_m"][zero])
    assert np.allclose(m["torque_N_m"], m["yield_torque_N_m"] + m["off_state_torque_N_m"])
    at = {(s, t): m["off_state_torque_N_m"][zero & (m["slip_speed_rpm"] == s)
                                           & (m["fluid_temperature_C"] == t)][0]
          for s in (0.0, 530.0) for t in (20.0, 60.0)}  # fmt: skip
    assert at[(530.0, 20.0)] > at[(0.0, 20.0)] and at[(530.0, 20.0)] > at[(530.0, 60.0)]
    seven = m["yield_torque_N_m"][m["current_A"] == 7.0]  # (20, 0), (20, 530), (60, 0), ...
    assert seven[0] == seven[1] and seven[2] == seven[3] and seven[0] > 0.3
    factor = tau_y_factor(FLUIDS["mrf_132dg"], 60.0)
    assert seven[2] / seven[0] == pytest.approx(factor, rel=1e-12) and factor < 0.99
    # each (speed, temperature) block: the tool's own torque curve there, τy(T) aside
    s = build_section(design.clutch, design.materials)
    for sp in (0.0, 530.0):
        for t in (20.0, 60.0):
            tc = torque_curve(s, [0.0, 2.0, 7.0], speed_rpm=sp, temperature=t,
                              support=design.support)  # fmt: skip
            at = (m["slip_speed_rpm"] == sp) & (m["fluid_temperature_C"] == t)
            assert m["off_state_torque_N_m"][at] == pytest.approx(tc.off_state_torque, rel=1e-12)
            assert m["yield_torque_N_m"][at] == pytest.approx(
                tc.yield_torque * tau_y_factor(FLUIDS["mrf_132dg"], t), rel=1e-12)  # fmt: skip


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


def test_device_schema_is_documented_key_for_key(tmp_path: Path) -> None:
    """docs/handoff.md's table names every key of the device JSON (nested ones as
    ``outer.inner``) and no key it does not hold: the schema a framework codes against."""
    import re

    from mrclutch.handoff import device_description

    d = device_description(design_preset("paper"), n_k=3)
    keys = set()
    for k, v in d.items():
        keys |= {f"{k}.{kk}" for kk in v} if isinstance(v, dict) else {k}
    doc = (Path(__file__).resolve().parents[2] / "docs/handoff.md").read_text()
    section = doc.split("## The device description", 1)[1].split("\n## ", 1)[0]
    rows = [line.split("|")[1] for line in section.splitlines() if line.startswith("| `")]
    documented = {k for cell in rows for k in re.findall(r"`([\w.]+)`", cell)}
    assert documented == keys
    assert len(d["bandwidth_hz"]) == 2  # n_k stiffnesses, 0 left out


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
    root = ElementTree.fromstring(svg)  # well-formed SVG, text kept as text
    assert root.tag.endswith("svg")
    texts = "".join(root.itertext())
    assert "±0.01" in texts and "0.03 mm TIR" in texts
    # the process defaults: IT band 0.02 mm -> ±0.01 mm on every diameter, runout 0.03 mm TIR
    assert svg.count("±0.01") >= 2 * 2 + 1 and "0.03 mm TIR" in svg
    assert "Ø25.800" in svg  # the housing: 2 × 12.9 mm


def test_drawing_reads_the_design_files_process(tmp_path: Path) -> None:
    """A design file's ``[process]`` band 0.05 mm and runout 0.1 mm: ±0.025 mm on every
    diameter, 0.1 mm TIR, and not the defaults'."""
    f = tmp_path / "shop.toml"
    f.write_text('name = "shop"\n[clutch]\nbase = "paper"\n'
                 "[process]\ntolerance_mm = 0.05\nrunout_mm = 0.1\n")  # fmt: skip
    assert main(["export", str(f), "--format", "drawing", "--out", str(tmp_path)]) == 0
    texts = "".join(ElementTree.parse(tmp_path / "shop.svg").getroot().itertext())
    assert texts.count("±0.025") >= 5 and "0.1 mm TIR" in texts
    assert "±0.01 " not in texts and "0.03 mm TIR" not in texts


@pytest.mark.parametrize("argv", [
    ["export", "--format", "iges", "--out", "X"],
    ["export", "--format", "dxf", "--current", "3", "--out", "X"],
    ["export", "--format", "step", "--current", "3", "--out", "X"],
    ["export", "--format", "femm", "--tolerance-mm", "0.1", "--out", "X"],
    ["torque", "--map", "X.xlsx"],
    ["torque", "--map", "X.csv", "--map-speeds-rpm", "fast"],
    ["torque", "--map", "X.csv", "--map-temperatures-C", "20,500"],
    ["torque", "--map", "X.csv", "--json"],
    ["torque", "--map", "X.csv", "--speed-rpm", "100"],
    ["torque", "--map", "X.csv", "--fluid-temperature-C", "60"],
    ["torque", "--map", "X.csv", "--method", "both"],
    ["export", "--format", "femm", "--current", "nan", "--out", "X"],
    ["device", "--preset", "nope", "--out", "X.json"],
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


#: each hand-off's command line, its output written under OUT
WRITERS = {
    "femm": ["export", "--format", "femm", "--out", "OUT"],
    "onelab": ["export", "--format", "onelab", "--out", "OUT"],
    "dxf": ["export", "--format", "dxf", "--out", "OUT"],
    "drawing": ["export", "--format", "drawing", "--out", "OUT"],
    "tables": ["tables", "--export", "OUT"],
    "device": ["device", "--out", "OUT/d.json"],
    "map-csv": ["torque", "--current", "0,7", "--map", "OUT/m.csv", "--map-speeds-rpm", "0",
                "--map-temperatures-C", "20"],
    "map-parquet": ["torque", "--current", "0,7", "--map", "OUT/m.parquet",
                    "--map-speeds-rpm", "0", "--map-temperatures-C", "20"],
}  # fmt: skip


def _argv(name: str, out: Path) -> list[str]:
    return [a.replace("OUT", str(out)) for a in WRITERS[name]]


@pytest.mark.parametrize("name", list(WRITERS))
def test_a_failing_write_leaves_no_partial_file(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A disk that fills mid-write: one line, exit 2, and neither file nor temporary left
    (the output layer, geometry.atomic) — every hand-off, the Parquet and SVG writers'
    own temporary files included."""
    import geometry.atomic as atomic

    def full(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full)
    assert main(_argv(name, tmp_path)) == 2
    monkeypatch.undo()
    err = capsys.readouterr().err.strip()
    if name == "drawing":  # its progress (bar and steps, issue 40) before the error
        progress = re.compile(r"export: +\d+%\||export: loading matplotlib$|export: drawing ")
        err = "\n".join(ln for ln in err.splitlines() if not progress.match(ln)).strip()
    assert len(err.splitlines()) == 1 and "No space left on device" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", list(WRITERS))
def test_a_folder_that_cannot_be_made_leaves_nothing(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The output folder under a plain file (refused even to root): one line, exit 2, and
    the file beside it untouched, nothing else."""
    (tmp_path / "f").write_text("keep")
    assert main(_argv(name, tmp_path / "f" / "out")) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "error" in err
    assert [p.name for p in tmp_path.iterdir()] == ["f"] and (tmp_path / "f").read_text() == "keep"


def test_a_disk_full_at_the_second_file_keeps_the_first_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each file appears whole or not at all: the .fem written, the disk full at the .lua —
    exit 2, the .fem complete (it reads back), no .lua and no temporary file."""
    import geometry.atomic as atomic
    from magnetics.export.femm import read_fem

    real, calls = atomic.os.fsync, []

    def second_fails(fd: int) -> None:
        calls.append(fd)
        if len(calls) > 2:  # the .fem's file and folder flushes pass, the .lua's fails
            raise OSError(28, "No space left on device")
        real(fd)

    monkeypatch.setattr(atomic.os, "fsync", second_fails)
    assert main(["export", "--format", "femm", "--out", str(tmp_path)]) == 2
    monkeypatch.undo()
    assert [p.name for p in tmp_path.iterdir()] == ["paper.fem"]
    assert read_fem((tmp_path / "paper.fem").read_text()).labels


def test_each_handoff_is_in_its_help_and_the_readme_tour() -> None:
    """Every hand-off file and option is named in the command's --help and in the README's
    tour (test_help_files checks the commands' default outputs; these are --format's), the
    help read in this process (test_help_files' ``_help``: 80 columns, a terminal's default)."""
    from test_help_files import _help as helptext

    root = Path(__file__).resolve().parents[2]
    tour = (root / "README.md").read_text().split("## A tour of the command line", 1)[1]
    tour = tour.split("\n## ", 1)[0]

    export = helptext("export")
    for fmt, names in {"femm": ("NAME.fem", "NAME.lua"), "onelab": ("NAME.geo", "NAME.pro"),
                       "dxf": ("NAME.dxf",), "drawing": ("NAME.svg",)}.items():  # fmt: skip
        assert fmt in export and all(n in export for n in names), fmt
        assert fmt in tour.split("mrclutch export --out DIR --format", 1)[1].split("\n")[0]
    torque = helptext("torque")
    assert "--map FILE.csv|.parquet" in torque and "--map-temperatures-C" in torque
    assert "--map FILE.csv" in tour and "mrclutch tables --export DIR" in tour
    assert "mrclutch device" in tour and "--out FILE.json" in helptext("device")
    assert "hysteresis.csv" in helptext("tables") and "fluids.csv" in helptext("tables")
