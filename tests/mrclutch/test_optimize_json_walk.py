"""Every null in ``optimize --json`` carries its reason (issue 44 item 4), as evaluate's do:
the command's JSON holds a ``nulls`` table (``mrclutch.pipeline.null_notes``, the one
table), and the walker of tests/mrclutch/test_json_walk.py finds no null, NaN or inf it
does not explain. A tiny search (a few generations of a small population) keeps it cheap;
the figures' nulls do not depend on how long the search ran."""

from __future__ import annotations

import json
from typing import Any

import pytest
from test_json_walk import unexplained

from mrclutch.cli.commands import optimize as optimize_cmd
from mrclutch.cli.commands import optimize_pareto as pareto_cmd
from mrclutch.cli.main import main


def _json(capsys, argv: list[str]) -> Any:
    code = main(argv)
    cap = capsys.readouterr()
    assert code in (0, 3), (argv, cap.err)  # 3: a requirement missed; the JSON is whole
    return json.loads(cap.out)


@pytest.mark.slow
def test_pareto_json_nominal_at_reference_has_no_unexplained_null(monkeypatch, capsys):
    """The Pareto set with --nominal, its members judged at reference fidelity: each
    member's fast row has no resonance (overdamped lever: NaN) and no duty asked
    (time at the duty torque inf), its reference evaluation no robust verdict (nominal),
    and the paper preset beside them no resonance; each has its reason in ``nulls``."""
    real = pareto_cmd.pareto
    monkeypatch.setattr(pareto_cmd, "pareto", lambda *a, **k: real(
        *a, **{**k, "pop_size": 16, "generations": 4, "members": 2}))  # fmt: skip
    data = _json(capsys, ["optimize", "--drums", "2", "--nominal", "--json", "--no-progress"])
    assert data["mode"] == "pareto" and data["fidelity"] == "reference"
    assert unexplained(data) == []
    nulls = data["nulls"]
    assert "no duty torque asked" in nulls["members/fast/time_at_duty_s"]
    assert "overdamped" in nulls["paper_preset/resonance_hz"]
    assert nulls["members/reference/robust"].startswith("not asked")
    assert not [k for k, r in nulls.items() if "no reason" in r]


def test_single_objective_json_has_no_unexplained_null(monkeypatch, capsys):
    """optimize --objective on the fast path, the worst case over the design's ranges: the
    ranges it does not declare (the delay's) are null, with their reason."""
    real = optimize_cmd.optimize
    monkeypatch.setattr(optimize_cmd, "optimize",
                        lambda *a, **k: real(*a, **k, maxiter=3, popsize=4))  # fmt: skip
    argv = ["optimize", "--objective", "bandwidth", "--drums", "1", "--tries", "1",
            "--no-verify", "--json", "--no-progress"]  # fmt: skip
    data = _json(capsys, argv)
    assert data["objective"] == "bandwidth"
    assert unexplained(data) == []
    assert "range is not given" in data["nulls"]["fast/robust/uncertainty/delay"]
