"""Tests for the survivors of the round's mutation run (issue 46, docs/testing.md).

``python benchmarks/mutation_run.py --run round`` plants one-expression errors in the
modules of the last two rounds and runs the tests that cover them, the doc-figure check
left out. Each test here kills a survivor that changes an answer a user can get; its
verdict, under ``[round."module:index"]`` in benchmarks/data/mutation_verdicts.toml, names
it. Each was checked by planting the same mutant by hand and seeing the test fail.
"""

from __future__ import annotations

import pytest

from mrclutch.design import design_preset
from mrclutch.optimize import pareto


class _Stop(Exception):
    """Raised by a progress report to end a search after its first generation."""


def test_pareto_runs_100_generations_by_default():
    """docs/optimize.md: the Pareto search runs "100 designs a generation for 100
    generations" unless told otherwise. ``progress`` is called (generations done,
    ``generations``) after each generation, so its first call names the total: 100 with
    the default; the mutant ``generations: int = 101`` (optimize.py:574 at d2d4f2c) gives
    101. The search is stopped at that first call (a population of 4: the total does not
    depend on it)."""
    totals: list[int] = []

    def first(done: int, total: int) -> None:
        totals.append(total)
        raise _Stop

    with pytest.raises(_Stop):
        pareto(design_preset("paper"), drum_counts=(2,), pop_size=4, members=1, progress=first)
    assert totals == [100]
