"""The vectorised layout is the section's image: compare them design by design."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry import ParameterError, build_section, preset
from geometry.batch import layout


@settings(max_examples=30, deadline=None)
@given(
    n=st.lists(st.integers(1, 5), min_size=1, max_size=6),
    gap_mm=st.floats(0.1, 1.0),
    t_mm=st.floats(0.05, 1.0),
)
def test_layout_matches_section(n, gap_mm, t_mm):
    base = preset("paper")
    lay = layout({"n_drums": np.array(n), "gap": gap_mm * 1e-3, "drum_thickness": t_mm * 1e-3})
    assert lay.size == len(n)
    for s_i, n_i in enumerate(n):
        c = replace(base, n_drums=n_i, gap=gap_mm * 1e-3, drum_thickness=t_mm * 1e-3)
        sec = build_section(c)
        assert lay.core_radius[s_i] == pytest.approx(c.core_radius, rel=1e-12)
        assert lay.pole_radius[s_i] == pytest.approx(c.pole_radius, rel=1e-12)
        assert lay.outer_radius[s_i] == pytest.approx(c.outer_radius, rel=1e-12)
        assert lay.overall_length[s_i] == pytest.approx(c.overall_length, rel=1e-12)
        mask = lay.gap_mask[s_i]
        assert mask.sum() == len(sec.gaps)
        for k, gap in enumerate(sec.gaps):
            assert lay.gap_r_inner[s_i, k] == pytest.approx(gap.r_inner, rel=1e-12)
            assert lay.gap_r_outer[s_i, k] == pytest.approx(gap.r_outer, rel=1e-12)
            assert lay.gap_z0[s_i, k] == pytest.approx(gap.z0, rel=1e-12)
            assert lay.gap_z1[s_i, k] == pytest.approx(gap.z1, rel=1e-12)
        zA, zB = sec.zones
        assert (lay.zA0[s_i], lay.zA1[s_i], lay.zB0[s_i], lay.zB1[s_i]) == pytest.approx(
            (zA.z0, zA.z1, zB.z0, zB.z1), rel=1e-12
        )
        out = np.column_stack([lay.out_r0[s_i], lay.out_r1[s_i]])[lay.out_mask[s_i]]
        assert out == pytest.approx(np.array(c.drum_radii_out), rel=1e-12)


def test_unknown_field_is_named():
    with pytest.raises(ParameterError, match="gapp: unknown DrumClutch field"):
        layout({"gapp": [1.0]})
