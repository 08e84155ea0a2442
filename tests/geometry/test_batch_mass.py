"""The vectorised analytic mass is the section's, design by design; validity mirrors params."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry import ParameterError, build_section, preset
from geometry.mass import analytic_batch, analytic_mass
from geometry.params import broadcast_fields
from geometry.section import PARTS


@settings(max_examples=40, deadline=None)
@given(
    n=st.lists(st.integers(1, 5), min_size=1, max_size=5),
    gap_mm=st.floats(0.1, 1.0),
    t_mm=st.floats(0.05, 1.0),
    zone_mm=st.floats(2.0, 10.0),
    turns=st.integers(50, 146),  # 146 = most 28 AWG turns in the 2.5 × 8.5 mm window
)
def test_batch_equals_section_per_design(n, gap_mm, t_mm, zone_mm, turns):
    base = preset("paper")
    fields = {
        "n_drums": np.array(n),
        "gap": gap_mm * 1e-3,
        "drum_thickness": t_mm * 1e-3,
        "zone_length": zone_mm * 1e-3,
        "coil_turns": turns,
    }
    res = analytic_batch(fields)
    for k, n_k in enumerate(n):
        c = replace(base, n_drums=n_k, gap=gap_mm * 1e-3, drum_thickness=t_mm * 1e-3,
                    zone_length=zone_mm * 1e-3, coil_turns=turns)  # fmt: skip
        s = build_section(c)
        a = analytic_mass(s)
        assert res["valid"][k]
        for p in PARTS:
            assert res[f"mass_{p}"][k] == pytest.approx(a.parts[p].mass, rel=1e-12)
            assert res[f"inertia_{p}"][k] == pytest.approx(a.parts[p].inertia, rel=1e-12)
        assert res["rotor_inertia"][k] == pytest.approx(a.rotor_inertia, rel=1e-12)
        assert res["clutch_mass"][k] == pytest.approx(a.clutch_mass, rel=1e-12)
        assert (res["diameter"][k], res["length"][k]) == pytest.approx(s.envelope, rel=1e-12)


CASES = [
    {"gap": 0.05e-3},
    {"gap": float("nan")},
    {"drum_thickness": -1e-3},
    {"n_drums": 0},
    {"coil_turns": 1000},
    {"drum_inner_diameter": 0.5e-3},
    {"hub_holes": 6, "hub_hole_diameter": 5e-3},
    {"hub_holes": 40, "hub_hole_diameter": 1.0e-3},
    {"wire_diameter": 4e-3},
    {"shaft_radius": 20e-3},
    {"hub_holes": 6},
    {"n_drums": 3, "gap": 0.2e-3},
]


@pytest.mark.parametrize("change", CASES)
def test_valid_flag_agrees_with_post_init(change):
    try:
        replace(preset("paper"), **change)
        ok = True
    except ParameterError:
        ok = False
    assert bool(analytic_batch(change)["valid"][0]) == ok


def test_chunked_equals_unchunked():
    import geometry.mass as m

    rng = np.random.default_rng(1)
    f = {"gap": rng.uniform(0.1e-3, 1e-3, 3 * m.BATCH_CHUNK + 7), "n_drums": 3}
    whole = m._analytic_chunk(broadcast_fields(f))
    split = analytic_batch(f)
    np.testing.assert_array_equal(whole["rotor_inertia"], split["rotor_inertia"])
