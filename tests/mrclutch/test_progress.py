"""Progress with an estimate for the long jobs (issue 40): the bar helper, and the
optimiser's generations reported as they finish."""

from __future__ import annotations

from mrclutch.cli.progress import bar
from mrclutch.design import design_preset
from mrclutch.optimize import pareto


def test_bar_counts_to_what_is_done_on_stderr(capsys):
    """``done(n)`` sets the count (a smaller n is ignored, n past the total is the total);
    the bar is drawn on stderr with its rate, nothing on stdout; disabled, nothing at all."""
    with bar(4, "job", "step") as done:
        for n in (1, 3, 2, 9):
            done(n)
    out = capsys.readouterr()
    assert out.out == "" and "job" in out.err and "4/4" in out.err
    with bar(4, "job", "step", enabled=False) as done:
        done(2)
    assert capsys.readouterr() == ("", "")


def test_pareto_reports_each_generation():
    """NSGA-II's generations are reported as (done, total) after each one: 1, 2, 3 of 3."""
    seen = []
    pareto(design_preset("paper"), drum_counts=(2,), pop_size=8, generations=3, members=1,
           progress=lambda n, total: seen.append((n, total)))  # fmt: skip
    assert seen == [(1, 3), (2, 3), (3, 3)]
