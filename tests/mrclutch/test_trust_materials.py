"""``evaluate --accuracy`` on a material set the error maps never saw (issue 44): the FEM is
chosen, and the reason says what holds for that set — no measured bound — instead of
quoting the bounds measured on steel 1018 and MRF-132DG."""

from __future__ import annotations

from dataclasses import replace

import pytest

from geometry.materials import MaterialChoice
from mrclutch.design import design_preset
from mrclutch.trust import choose


@pytest.mark.parametrize(
    ("choice", "mset"),
    [
        (MaterialChoice(fluid="mrf_140cg"), "steel_1018+mrf_140cg"),
        (
            MaterialChoice(core="hiperco_50", drums="hiperco_50", shell="hiperco_50"),
            "hiperco_50+mrf_132dg",
        ),
    ],
)
def test_the_fem_reason_on_an_unmeasured_set_names_the_set_not_the_default_bounds(choice, mset):
    """At 10 % the paper preset takes the saturating circuit (its map's bound there is
    0.5 %, tests/mrclutch/test_fidelity.py); with another fluid or steel neither fast model
    has a measured bound (both inf, torque_error_bound), so the FEM is chosen and the note
    must say so — once it read "bound 0.5 %" and "bound 2.1 %", the 1018/132DG figures."""
    paper = design_preset("paper")
    assert choose(paper, 0.1).torque == "circuit"
    pick = choose(replace(paper, materials=choice), 0.1)
    assert pick.torque == "fem"
    (why,) = [n for n in pick.notes if n.startswith("torque within")]
    assert f"never measured with the materials {mset}" in why
    assert "saturating circuit" in why and "reluctance network" in why
    assert "by its measured map" not in why and "bound 0.5%" not in why
    assert "bound 2.1%" not in why
    assert "unverified for this set" in why  # the FEM's mesh-error bound: measured on 1018


def test_the_default_set_still_quotes_its_measured_bounds():
    """The paper preset at 0.3 %: neither fast bound meets it (circuit 0.5 %, network
    2.1 %), so the FEM, with both measured bounds quoted as the reason."""
    pick = choose(design_preset("paper"), 0.003)
    assert pick.torque == "fem"
    (why,) = [n for n in pick.notes if n.startswith("torque within")]
    assert "by its measured map (bound 0.5%)" in why
    assert "cannot be had at their speed" in why
    assert "never measured" not in why
