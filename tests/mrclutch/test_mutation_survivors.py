"""Tests for the survivors of the round's mutation run (issue 46, docs/testing.md).

``python benchmarks/mutation_run.py --run round`` plants one-expression errors in the
modules of the last two rounds and runs the tests that cover them, the doc-figure check
left out. Each test here kills a survivor that changes an answer a user can get; its
verdict, under ``[round."module:index"]`` in benchmarks/data/mutation_verdicts.toml, names
it. Each was checked by planting the same mutant by hand and seeing the test fail.
"""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from mrclutch import estimates
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


def test_sweep_rate_is_designs_timed_over_the_time_they_took(monkeypatch):
    """The sweep's speed estimate (``estimates.sweep_rate``; the announced time and the
    refusal without --yes above 10 min follow from it) on a clock that advances 0.125 s a
    call of the evaluator: the warm-up call ends at 0.125 s (t0), then chunks of 100 designs
    end at 0.25, 0.375 and 0.5 s, where 0.375 s ≥ 0.3 s stops the timing. Rate = 300
    designs / 0.375 s × 2 workers = 1600 designs/s, measured on 300. The mutant
    ``done * max(elapsed, 1e-9)`` (cli/commands/design.py:697 at d2d4f2c) gives 225."""
    clock = [0.0]

    def evaluator(fields):
        clock[0] += 0.125

    monkeypatch.setattr(estimates, "time", SimpleNamespace(perf_counter=lambda: clock[0]))
    monkeypatch.setattr(estimates, "use_compiled", lambda: None)  # no process-wide switch
    spec = SimpleNamespace(n_designs=10_000, chunk_size=100,
                           design_fields=lambda i: (None, {"gap": np.zeros(10_000)}))  # fmt: skip
    rate, done = estimates.sweep_rate(spec, evaluator, 2)
    assert done == 300
    assert rate == pytest.approx(1600.0, rel=1e-12)


def test_threshold_takes_the_crossing_nearest_the_value_in_p(monkeypatch):
    """``robust.threshold``: where the limit crosses K twice over its 10⁻³–10³ window, the
    crossing nearest the value in ``p`` (in log) is the threshold. A stand-in limit
    K·exp((u − u1)(u − u2)) of u = ln b1 crosses K at b1 = b0/2 and b1 = 100·b0, with b0 =
    0.01 N·s/m; the nearer is b0/2 = 0.005 N·s/m (|ln 0.5| = 0.69 < ln 100 = 4.6), and
    the limit falls through K there, so the verdict holds below it ("≤"). The mutant
    ``abs(best[0] + u0)`` (robust.py:487 at d2d4f2c) compares with |2 ln b0 − 0.69| = 9.9
    and takes b1 = 1.0."""
    from mrclutch import robust
    from mrclutch.haptics.actuator import TABLE2_MR

    K, b0 = 50.0, 0.01
    u1, u2 = math.log(b0 / 2), math.log(100 * b0)

    def limit(p):
        u = math.log(p.b1)
        return K * math.exp((u - u1) * (u - u2))

    monkeypatch.setitem(robust._LIMITS, "stable", limit)
    t = robust.threshold(replace(TABLE2_MR, b1=b0), K, "stable", "b1")
    assert t is not None
    assert t["value"] == pytest.approx(b0 / 2, rel=1e-8)
    assert t["sense"] == "≤"
