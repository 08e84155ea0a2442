"""The region table: its stations against closed forms, its topology, and one code path for
one design and for arrays of designs."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry import ParameterError, build_section, preset
from geometry.params import broadcast_fields, valid
from geometry.regions import by_drum_count, evaluate, layer, n_layers, per_topology, rho, table


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 8),
    gap_mm=st.floats(0.1, 1.0),
    t_out_mm=st.floats(0.05, 1.0),
    t_in_mm=st.floats(0.05, 1.0),
)
def test_stations_closed_form(n, gap_mm, t_out_mm, t_in_mm):
    """Pole radius = core + n(2g + t_out) + (n−1) t_in; envelope length = the sum of the
    axial stack; each drum's radii from its index."""
    g, to, ti = gap_mm * 1e-3, t_out_mm * 1e-3, t_in_mm * 1e-3
    c = replace(preset("paper"), n_drums=n, gap=g, drum_thickness=to, input_drum_thickness=ti)
    rc = c.drum_inner_diameter / 2 - g
    assert c.core_radius == pytest.approx(rc, rel=1e-12)
    assert c.pole_radius == pytest.approx(rc + n * (2 * g + to) + (n - 1) * ti, rel=1e-12)
    for i, (a, b) in enumerate(c.drum_radii_out):
        assert a == pytest.approx(rc + g + i * (2 * g + to + ti), rel=1e-12)
        assert b - a == pytest.approx(to, rel=1e-9)
    for i, (a, _b) in enumerate(c.drum_radii_in):
        assert a == pytest.approx(rc + (i + 1) * (2 * g + to) + i * ti, rel=1e-12)
    length = (c.shaft_length + 2 * c.end_cap_thickness + 3 * c.end_clearance + c.hub_thickness
              + 2 * c.zone_length + c.band_length)  # fmt: skip
    assert c.overall_length == pytest.approx(length, rel=1e-12)
    assert c.outer_radius == pytest.approx(
        c.pole_radius + c.sleeve_thickness + c.coil_depth + c.shell_thickness, rel=1e-12
    )


@pytest.mark.parametrize("n", [1, 2, 5])
def test_table_topology(n):
    """2n gaps, n output and n − 1 input drums, layers alternating gap | drum; gaps lie
    between an output and an input wall; every region name is unique."""
    rows = table(n)
    assert len({r.name for r in rows}) == len(rows)
    kinds = [layer(j)[0] for j in range(n_layers(n))]
    assert kinds[::2] == ["gap"] * (2 * n)
    assert kinds[1::2] == ["out", "in"] * (n - 1) + ["out"]
    # the drums counted from 1 outward, output and input each on their own: layer 1 is
    # out1, 3 in1, 5 out2, 7 in2, …; gap k is layer 2k
    assert [layer(j) for j in range(1, n_layers(n), 2)] == [
        (kind, j // 4 + 1) for j, kind in zip(range(1, n_layers(n), 2), kinds[1::2], strict=True)
    ]
    assert [layer(2 * k) for k in range(2 * n)] == [("gap", k) for k in range(2 * n)]
    gaps = [r for r in rows if r.film == "cylinder"]
    assert len(gaps) == 2 * n
    for k, gp in enumerate(gaps):
        assert (gp.r0, gp.r1) == (rho(2 * k), rho(2 * k + 1))
        inner, outer = gp.walls
        sides = {inner[:2], outer[:2]}
        assert sides in ({"co", "ou"}, {"ou", "in"}, {"ou", "sh"}), gp.walls


def test_one_design_and_many_share_one_code_path():
    """The section of one design (floats) and the table evaluated on arrays give the same
    numbers, because they are the same function of the fields."""
    rng = np.random.default_rng(3)
    f = broadcast_fields({"n_drums": rng.integers(1, 5, 12), "gap": rng.uniform(2e-4, 1e-3, 12)},
                         preset("paper"))  # fmt: skip
    ok = valid(f)
    got = per_topology(f, ok, lambda rg, rows: {"pole": rg.pole_radius, "len": rg.length})
    for i in range(12):
        c = replace(preset("paper"), n_drums=int(f["n_drums"][i]), gap=float(f["gap"][i]))
        assert got["pole"][i] == c.pole_radius
        s = build_section(c)
        assert got["len"][i] == s.envelope[1]


def test_groups_by_drum_count_and_blanks_invalid_rows():
    groups = by_drum_count(np.array([2, 1, 2, 3, 0]), np.array([1, 1, 1, 0, 0], bool))
    assert {k: v.tolist() for k, v in groups.items()} == {1: [1], 2: [0, 2]}
    f = broadcast_fields({"n_drums": [2, 0, 2.5, np.nan]}, preset("paper"))
    ok = valid(f)
    assert ok.tolist() == [True, False, False, False]
    out = per_topology(f, ok, lambda rg, rows: {"r": rg.outer_radius})
    assert np.isfinite(out["r"][0]) and np.isnan(out["r"][1:]).all()
    one = evaluate({k: v[:1] for k, v in f.items()}, 2)
    assert one.pole_radius[0] == preset("paper").pole_radius


def test_unknown_field_is_named():
    with pytest.raises(ParameterError, match="gapp: unknown DrumClutch field"):
        broadcast_fields({"gapp": [1.0]})
