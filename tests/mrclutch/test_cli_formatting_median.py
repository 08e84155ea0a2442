"""The FEM check's median line (mrclutch.cli.formatting._median) is statistics.median's
value to the bit, without importing statistics at every evaluate's start (issue 40)."""

import statistics

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from mrclutch.cli.formatting import _median


@given(st.lists(st.floats(0.0, 10.0, allow_nan=False), min_size=1, max_size=30))
def test_median_is_statistics_median(values: list[float]) -> None:
    assert _median(values) == statistics.median(values)
    assert _median(values + values) == statistics.median(values + values)  # ties, even n


def test_median_of_numpy_floats_and_even_counts() -> None:
    vals = [abs(x) for x in np.array([0.031, -0.002, 0.0125, 0.004])]
    assert _median(vals) == statistics.median(vals) == (0.004 + 0.0125) / 2
    assert _median([3.0, 1.0, 2.0]) == 2.0


def test_formatting_does_not_import_statistics(fresh_python) -> None:
    code = "import sys, mrclutch.cli.formatting\nprint('statistics' in sys.modules)"
    assert fresh_python(code).stdout.split() == ["False"]
