"""Every DrumClutch field has a physical range, the whole clutch a plausibility envelope,
and the scalar check (``DrumClutch``) and the batch check (``valid``) agree row by row."""

from __future__ import annotations

import math
from dataclasses import fields, replace

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from geometry import ParameterError, preset
from geometry.params import (
    FIELD_NAMES,
    INT_RANGES,
    LENGTH_RANGES,
    MAX_OUTER_DIAMETER,
    MIN_FEATURE,
    DrumClutch,
    broadcast_fields,
    valid,
)


def _scalar_ok(change: dict) -> bool:
    try:
        replace(preset("paper"), **change)
    except ParameterError:
        return False
    return True


def _batch_ok(change: dict) -> bool:
    return bool(valid(broadcast_fields({k: [v] for k, v in change.items()}, preset("paper")))[0])


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        ({"shaft_bore_clearance": 10e-3}, "shaft_bore_clearance = 0.01 m: the front cap's bore"),
        ({"shaft_bore_clearance": 0.4}, "shaft_bore_clearance = 0.4 m: must be in"),
        ({"end_clearance": 1e-18}, "end_clearance = 1e-18 m: must be in [1e-05, 0.3] m"),
        ({"end_clearance": 1e-20}, "end_clearance = 1e-20 m: must be in"),
        ({"wire_insulation": 1e300}, "wire_insulation = 1e+300 m: must be in [0, 0.001] m"),
        ({"wire_diameter": 1e-300}, "wire_diameter = 1e-300 m: must be in [1e-05, 0.01] m"),
        ({"shell_thickness": 1e-20}, "shell_thickness = 1e-20 m: must be in"),
        ({"hub_hole_diameter": math.inf}, "hub_hole_diameter = inf: must be finite"),
        ({"n_drums": 20, "drum_thickness": 20e-3, "gap": 5e-3}, "the clutch is 1.2194 m across"),
    ],
)
def test_fuzzed_inputs_fail_naming_the_field_and_the_range(change, fragment):
    with pytest.raises(ParameterError) as exc:
        replace(preset("paper"), **change)
    assert fragment in str(exc.value)
    assert not _batch_ok(change)  # the batch applies the same rule


@pytest.mark.parametrize(("name", "lo", "hi", "lo_open"), LENGTH_RANGES)
def test_every_length_has_a_closed_range_and_its_ends_agree_in_both_checks(name, lo, hi, lo_open):
    assert not lo_open and 0 <= lo < hi <= MAX_OUTER_DIAMETER
    assert name == "wire_insulation" or lo >= MIN_FEATURE
    for v in (lo * (1 - 1e-9) - 1e-300, hi * (1 + 1e-9)):  # just outside: both refuse
        assert not _scalar_ok({name: v}) and not _batch_ok({name: v})
    for v in (lo, hi):  # the ends: both give the same answer (other rules may refuse)
        assert _scalar_ok({name: v}) == _batch_ok({name: v})


def test_every_field_has_a_rule():
    named = {n for n, *_ in LENGTH_RANGES} | {n for n, *_ in INT_RANGES}
    assert named == set(FIELD_NAMES)


def test_design_file_errors_use_the_file_key_and_mm():
    with pytest.raises(ParameterError) as exc:
        DrumClutch.from_mm({"end_clearance_mm": 1e-15}, base=preset("paper"), where="f.toml")
    assert str(exc.value) == "f.toml: end_clearance_mm = 1e-15 mm: must be in [0.01, 300] mm"
    with pytest.raises(ParameterError, match=r"shaft_bore_clearance_mm = 10 mm: the front cap"):
        DrumClutch.from_mm({"shaft_bore_clearance_mm": 10}, base=preset("paper"))


def test_the_envelope_admits_the_paper_clutch_and_refuses_a_large_one():
    c = preset("paper")
    assert 2 * c.outer_radius < MAX_OUTER_DIAMETER
    big = {"n_drums": 20, "drum_thickness": 20e-3, "gap": 5e-3}
    with pytest.raises(ParameterError, match="MAX_OUTER_DIAMETER"):
        replace(c, **big)


# ---- fuzzing ------------------------------------------------------------------------------
EXTREMES = [0.0, -0.0, -1.0, 1e-300, 1e-20, 1e-5, 1e-3, 0.3, 1.0, 1e300, math.nan, math.inf,
            -math.inf]  # fmt: skip
FLOATS = st.one_of(st.sampled_from(EXTREMES), st.floats(allow_nan=True, allow_infinity=True))
LENGTHS = [n for n, *_ in LENGTH_RANGES]
INTS = st.one_of(st.integers(-5, 200_000), st.sampled_from([0, 1, 2, 3, 20, 21, 10**9]))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(FIELD_NAMES),
    fvalue=FLOATS,
    ivalue=INTS,
)
def test_fuzz_drumclutch_either_names_the_field_or_is_valid(name, fvalue, ivalue):
    value = ivalue if name in {n for n, *_ in INT_RANGES} else fvalue
    try:
        c = replace(preset("paper"), **{name: value})
    except ParameterError as exc:
        msg = str(exc)
        assert "\n" not in msg
        assert name in msg or "the clutch is" in msg, msg  # the field, or the envelope
        assert not _batch_ok({name: value})
        return
    assert _batch_ok({name: value})
    assert all(math.isfinite(getattr(c, f.name)) for f in fields(c))
    assert 0 < c.core_radius < c.outer_radius and 2 * c.outer_radius <= MAX_OUTER_DIAMETER
