"""``evaluate_batch`` never raises on bad rows: they come back ``valid = 0``, the others
are evaluated as if alone, and a valid row holds no NaN (but the documented one)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from geometry.params import INTEGER_FIELDS, LENGTH_RANGES, DrumClutch
from mrclutch.pipeline import evaluate_batch

#: NaN by definition when the free lever is overdamped (haptics.model.resonance).
NAN_ALLOWED = {"resonance_hz"}


def _check(out: dict[str, np.ndarray], size: int) -> None:
    assert all(v.shape == (size,) for v in out.values())
    ok = out["valid"] == 1
    for key, col in out.items():
        if key not in NAN_ALLOWED:  # inf is a flag (circuit_error_bound: no bound known)
            assert not np.any(np.isnan(col[ok])), key
        assert np.all(np.isnan(col[~ok]) | (key == "valid")), key


def test_one_bad_row_does_not_fail_the_batch_and_the_good_row_is_unchanged():
    alone = evaluate_batch({"gap": [0.7e-3]})
    out = evaluate_batch({"gap": [0.7e-3, -1.0, math.nan, 1e-20]})
    assert out["valid"].tolist() == [1, 0, 0, 0]
    for key in alone:
        np.testing.assert_array_equal(out[key][:1], alone[key])
    _check(out, 4)


@pytest.mark.parametrize("bad", [math.nan, 2.5, 0.0, 21.0, -1.0, math.inf])
def test_bad_drum_counts_are_invalid_rows(bad):
    out = evaluate_batch({"n_drums": [2.0, bad]})
    assert out["valid"].tolist() == [1, 0]
    _check(out, 2)


def test_empty_and_all_invalid_batches_give_columns():
    empty = evaluate_batch({"gap": np.zeros(0)})
    assert empty and all(v.shape == (0,) for v in empty.values())
    bad = evaluate_batch({"gap": [-1.0, math.nan]})
    assert bad["valid"].tolist() == [0, 0]
    _check(bad, 2)


FIELDS = [n for n, *_ in LENGTH_RANGES] + sorted(INTEGER_FIELDS)
EXTREMES = [0.0, -1.0, 1e-300, 1e-20, 1e-5, 1e-4, 1e-3, 0.3, 1e300, math.nan, math.inf, 1.0, 2.0]
EXTREMES += [2.5, 20.0, 140.0]  # drum and turn counts, a fractional one among them
VALUES = st.one_of(st.sampled_from(EXTREMES), st.floats(allow_nan=True, allow_infinity=True))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    changes=st.lists(st.tuples(st.sampled_from(FIELDS), VALUES), min_size=1, max_size=3),
    rows=st.integers(1, 4),
)
def test_fuzz_evaluate_batch_never_raises(changes, rows):
    # row 0 is the paper clutch, the others carry the fuzzed values
    fields = {name: np.full(rows + 1, v) for name, v in changes}
    for name, col in fields.items():
        col[0] = getattr(DrumClutch(), name)
    out = evaluate_batch(fields)
    assert out["valid"][0] == 1
    _check(out, rows + 1)
