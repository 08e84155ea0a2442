"""``scale``'s bandwidth changes on a non-default fluid (issue 44): negative at the base
design's K (not a bug: the same K on more moving mass), said so beside the figure, with the
change at the route's own K_max next to it."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest

from geometry.materials import MaterialChoice
from mrclutch.cli.main import main
from mrclutch.design import design_preset
from mrclutch.scaling import scaling_study

M140 = '[clutch]\nbase = "paper"\n[materials]\nfluid = "mrf_140cg"\n'


@pytest.fixture(scope="module")
def study():
    return scaling_study(
        replace(design_preset("paper"), materials=MaterialChoice(fluid="mrf_140cg"))
    )


def test_the_same_k_bandwidth_falls_by_eq1_and_the_own_k_max_one_rises(study):
    """Eq. 1, ω = √(K/(m1+m2)): at one K the ratio is √(m_tot0/m_tot), e.g. +37.6 % moving
    mass → 1/√1.376 − 1 = −14.7 %; at the route's own K_max = F_max/d ∝ torque it is
    √(torque ratio · m_tot0/m_tot), e.g. √(2.561/1.376) − 1 = +36.4 % for 4 drums."""
    _, routes, _ = study
    grew = [r for r in routes if r.changes["total_moving_mass"] > 0]
    assert grew  # more drums and a larger diameter add moving mass
    for r in routes:
        dm = r.changes["total_moving_mass"]
        same = r.changes["bandwidth_lumped_same_K"]
        own = r.changes["bandwidth_lumped_own_K"]
        assert same == pytest.approx(1 / math.sqrt(1 + dm) - 1, rel=1e-9, abs=1e-12)
        assert own == pytest.approx(math.sqrt(r.torque_ratio / (1 + dm)) - 1, rel=1e-6, abs=1e-9)
        if r.torque_ratio >= 2.0 - 1e-6:
            assert same < 0 < own
        if same < 0:  # every negative figure carries its reason
            assert r.note and "Eq. 1" in r.note and "own K_max" in r.note
            assert f"{same:+.1%}" in r.note and f"{own:+.1%}" in r.note
        else:
            assert r.note is None


def test_cli_says_why_beside_the_figures(tmp_path, capsys):
    f = tmp_path / "m140.toml"
    f.write_text(M140)
    assert main(["scale", str(f), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["base"]["K_N_per_m"] > 0 and data["base"]["bandwidth_lumped_hz"] > 0
    for r in data["routes"]:
        if r["changes"]["bandwidth_lumped_same_K"] < 0:
            assert "a cost, not an error" in r["note"]
    assert main(["scale", str(f)]) == 0
    text = capsys.readouterr().out
    assert "at its own K_max" in text and "the added mass lowers it" in text
    assert text.count("% at the base K_max") == 3  # one line per route


def test_twenty_drums_answer_with_the_drums_route_out_of_reach():
    """20 drums is the most a design takes (geometry.params.INT_RANGES): the drums route
    cannot add one, so its row stays at 20 (torque 1×) with a note, and the longer-drum and
    larger-diameter routes still answer (the study was refused as a whole before)."""
    paper = design_preset("paper")
    twenty = replace(paper, clutch=replace(paper.clutch, n_drums=20))
    _, routes, notes = scaling_study(twenty)
    by = {r.name: r for r in routes}
    assert by["more drums"].value == 20 and by["more drums"].torque_ratio == pytest.approx(1.0)
    assert any(n.startswith("more drums") and "up to 20 drums" in n for n in notes)
    assert any(r.torque_ratio == pytest.approx(2.0, rel=1e-6) for r in routes)
