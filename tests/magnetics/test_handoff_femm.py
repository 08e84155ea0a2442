"""The FEMM 4.2 hand-off (magnetics.export.femm): the .fem read back has every region with
its material, every B–H point, the coil's circuit and turns, A = 0 on the box and a
conforming outline; docs/femm/paper.fem is what its command writes."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from geometry import build_section, preset
from geometry.outline import section_outline
from magnetics.export.femm import EXTENSION_T, MU0, fem_box, problem, read_fem, write_fem, write_lua
from magnetics.materials import MATERIALS, BHCurve
from mrclutch.cli.main import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def paper():  # type: ignore[no-untyped-def]
    s = build_section(preset("paper"))
    p = problem(s, 7.0, "paper")
    return s, p, read_fem(write_fem(p))


def _face(f, x, y):  # type: ignore[no-untyped-def]
    return next(lab for lab in f.labels if math.isclose(lab["x"], x, abs_tol=1e-9)
                and math.isclose(lab["y"], y, abs_tol=1e-9))  # fmt: skip


def test_every_region_is_a_labelled_block_of_its_material(paper) -> None:  # type: ignore[no-untyped-def]
    s, _p, f = paper
    names = [b["blockname"] for b in f.blocks]
    assert f.header["problemtype"] == "axisymmetric" and f.header["lengthunits"] == "millimeters"
    for g in s.regions:
        lab = _face(f, 0.5e3 * (g.r0 + g.r1), 0.5e3 * (g.z0 + g.z1))
        assert names[lab["block"] - 1] == g.material, g.name
        assert lab["meshsize"] <= 0.25 + 1e-12
    air = [lab for lab in f.labels if names[lab["block"] - 1] == "air"]
    assert len(air) == len(f.labels) - len(s.regions) >= 1


def test_every_bh_point_is_there_in_femms_conventions(paper) -> None:  # type: ignore[no-untyped-def]
    """Origin, the table, one point 1 T on: (B_n + 1, H_n + 1/μ0) = H_n + 795775 A/m."""
    _s, _p, f = paper
    for b in f.blocks:
        m = MATERIALS[b["blockname"]]
        if not isinstance(m, BHCurve):
            assert b["bh"] == [] and b["mu_x"] == pytest.approx(m.mu_r)
            continue
        pts = b["bh"]
        assert pts[0] == (0.0, 0.0)
        assert [p[0] for p in pts[1:-1]] == pytest.approx(list(m.b_table), rel=1e-9)
        assert [p[1] for p in pts[1:-1]] == pytest.approx(list(m.h_table), rel=1e-9)
        assert pts[-1][0] == pytest.approx(m.b_table[-1] + EXTENSION_T)
        assert pts[-1][1] - m.h_table[-1] == pytest.approx(EXTENSION_T / MU0, rel=1e-9)


def test_the_coil_is_a_series_circuit_of_its_turns(paper) -> None:  # type: ignore[no-untyped-def]
    s, _p, f = paper
    (c,) = f.circuits
    assert c["circuitname"] == "coil" and c["circuittype"] == 1 and c["totalamps_re"] == 7.0
    coil = s.region("coil")
    lab = _face(f, 0.5e3 * (coil.r0 + coil.r1), 0.5e3 * (coil.z0 + coil.z1))
    assert lab["circuit"] == 1 and lab["turns"] == s.clutch.coil_turns == 140
    assert sum(lab["circuit"] for lab in f.labels) == 1


def test_a_is_zero_on_the_tools_box_and_nowhere_else(paper) -> None:  # type: ignore[no-untyped-def]
    s, _p, f = paper
    rb, z0, z1 = (x * 1e3 for x in fem_box(s))
    assert f.boundaries[0]["bdryname"] == "A=0" and f.boundaries[0]["bdrytype"] == 0
    for a, b, bdry in f.segments:
        (xa, ya), (xb, yb) = f.points[a], f.points[b]
        on = (math.isclose(xa, rb) and math.isclose(xb, rb)) or any(
            math.isclose(ya, z) and math.isclose(yb, z) for z in (z0, z1))  # fmt: skip
        assert bdry == (1 if on else 0)
    assert max(x for x, _ in f.points) == pytest.approx(rb)


def test_the_outline_is_conforming() -> None:
    """No node lies inside a segment (a T-junction would leave two faces unjoined), no two
    segments repeat, and each segment is axis-aligned — on 1, 2 and 5 drums."""
    from dataclasses import replace

    for n in (1, 2, 5):
        s = build_section(replace(preset("paper"), n_drums=n))
        o = section_outline(s, fem_box(s))
        assert len(set(o.segments)) == len(o.segments)
        for a, b in o.segments:
            (ra, za), (rb, zb) = o.nodes[a], o.nodes[b]
            assert ra == rb or za == zb
            for r, z in o.nodes:
                inside_r = ra == rb == r and min(za, zb) < z < max(za, zb)
                inside_z = za == zb == z and min(ra, rb) < r < max(ra, rb)
                assert not (inside_r or inside_z), (n, (r, z))


def test_the_lua_script_draws_the_same_problem(paper) -> None:  # type: ignore[no-untyped-def]
    s, p, f = paper
    lua = write_lua(p, [2, 7])
    assert lua.count("mi_addnode(") == len(f.points)
    assert lua.count("mi_addsegment(") == len(f.segments)
    assert lua.count("mi_addblocklabel(") == len(f.labels)
    assert lua.count('mi_setsegmentprop("A=0"') == sum(1 for *_, b in f.segments if b == 1)
    assert "currents = {2, 7}" in lua and f"ngaps = {len(s.gaps)}" in lua
    for name in p.materials:
        m = MATERIALS[name]
        n = len(m.b_table) + 2 if isinstance(m, BHCurve) else 0
        assert lua.count(f'mi_addbhpoint("{name}",') == n


def test_docs_femm_paper_is_what_the_command_writes(tmp_path: Path) -> None:
    """docs/femm/paper.fem and .lua: `mrclutch export --preset paper --format femm --out
    docs/femm` writes them byte for byte (regenerate with that command)."""
    assert main(["export", "--preset", "paper", "--format", "femm", "--out", str(tmp_path)]) == 0
    for ext in (".fem", ".lua"):
        assert (tmp_path / f"paper{ext}").read_text() == (ROOT / "docs/femm" / f"paper{ext}"
                                                           ).read_text()  # fmt: skip
    f = read_fem((ROOT / "docs/femm/paper.fem").read_text())
    assert len(f.labels) > len(build_section(preset("paper")).regions)


def test_read_fem_refuses_a_short_section() -> None:
    p = problem(build_section(preset("paper")), 2.0)
    text = write_fem(p).replace("[NumPoints] = ", "[NumPoints] = 9999", 1)
    with pytest.raises(ValueError, match="fewer lines follow"):
        read_fem(text)


def test_fem_rows_have_femm_42s_fields(paper) -> None:  # type: ignore[no-untyped-def]
    """Each row as FEMM 4.2's reader takes it [femm42]: a point `x y property group`, a
    segment `n0 n1 max-side boundary hidden group` (-1: automatic), a block label
    `x y block mesh-size circuit magdir group turns external` (mesh size in mm, -1 for the
    automatic mesh in air); a B-H line `B H`."""
    _s, p, _f = paper
    text = write_fem(p).splitlines()

    def rows(key: str) -> list[list[str]]:
        i = next(k for k, line in enumerate(text) if line.startswith(f"[{key}]"))
        n = int(text[i].split("=")[1])
        return [text[i + 1 + j].split() for j in range(n)]

    assert {len(r) for r in rows("NumPoints")} == {4}
    segs = rows("NumSegments")
    assert {len(r) for r in segs} == {6} and {r[2] for r in segs} == {"-1"}
    labels = rows("NumBlockLabels")
    assert {len(r) for r in labels} == {9}
    air = [r for r in labels if r[2] == "1"]  # block 1 is air
    assert air and all(r[3] == "-1" for r in air)
    assert all(0 < float(r[3]) <= 0.25 for r in labels if r[2] != "1")
    assert all(r[8] == "0" and r[5] == "0" for r in labels)  # not external, no magnet
    bh = [line.split() for line in text if line.startswith("      ")]
    assert bh and {len(r) for r in bh} == {2}
