"""``fidelity --json`` walked with the checker of tests/mrclutch/test_json_walk.py (issue 44
item 4): no NaN, inf or null without its reason, on the paper preset. The stability and
bandwidth methods only (half a minute); the inertia, torque and eddy rows solve CAD and FEM
(minutes) and are not walked here."""

from __future__ import annotations

import json

import pytest
from test_json_walk import unexplained

import mrclutch.cli.commands.fidelity as fidelity_cmd
from mrclutch.cli.main import main
from mrclutch.fidelity import registry


@pytest.mark.slow
def test_fidelity_json_of_the_cheap_methods_has_no_unexplained_figure(tmp_path, capsys,
                                                                       monkeypatch):  # fmt: skip
    ms = tuple(m for m in registry() if m.quantity in ("stability", "bandwidth"))
    assert len(ms) >= 3
    monkeypatch.setattr(fidelity_cmd, "registry", lambda: ms)
    argv = ["fidelity", "--preset", "paper", "--out", str(tmp_path), "--repeats", "1", "--json"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["rows"]) == len(ms)
    assert unexplained(doc) == []
    assert unexplained(json.loads((tmp_path / "fidelity.json").read_text())) == []
