"""``evaluate --accuracy`` on a material set the error maps never saw (issue 44): the FEM is
chosen, and the reason says what holds for that set — no measured bound — instead of
quoting the bounds measured on steel 1018 and MRF-132DG."""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import pytest

from geometry.materials import DEFAULT_CHOICE, MaterialChoice
from geometry.validation import ParameterError
from magnetics.error_map import circuit_error
from magnetics.network_bound import DEFAULT_MATERIALS, network_bound, network_features
from mrclutch.design import design_preset
from mrclutch.trust import _shared_features, choose, circuit_trust, material_set


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


def _designs():  # type: ignore[no-untyped-def]
    """The paper preset and random variations of it inside the network bound's ranges (a
    drum count, the gap, the zone, the drum walls), with currents."""
    from geometry.params import preset

    rng = np.random.default_rng(44)
    base = preset("paper")
    out = [(base, 7.0)]
    while len(out) < 5:
        try:
            d = replace(
                base,
                n_drums=int(rng.integers(1, 5)),
                gap=rng.uniform(0.25e-3, 0.8e-3),
                zone_length=rng.uniform(3.5e-3, 8.5e-3),
                drum_thickness=rng.uniform(0.2e-3, 0.5e-3),
            )
        except ParameterError:
            continue
        out.append((d, float(rng.uniform(1.0, 8.0))))
    return out


def test_the_trust_checks_features_on_the_shared_network_are_the_bounds_own_bits() -> None:
    """circuit_trust hands network_bound the features solved on evaluate's shared network
    (section_network) instead of letting it build and solve its own: on the paper preset
    and random designs the features are the same bits as network_features', and the
    estimate, bound and notes are the same with and without them."""
    for d, cur in _designs():
        p = {f.name: getattr(d, f.name) for f in fields(d)}
        got = _shared_features(d, cur, DEFAULT_CHOICE, DEFAULT_MATERIALS)
        assert got is not None, d
        want = network_features(p, float(d.coil_turns) * cur)
        assert set(got) == set(want)
        for k in want:
            assert np.array_equal(got[k], want[k]), k
        assert network_bound(p, cur, features=got) == network_bound(p, cur)
        assert circuit_error(d, "network", cur, features=got) == circuit_error(d, "network", cur)


def test_the_trust_check_solves_nothing_for_a_design_the_bound_does_not_solve() -> None:
    """Outside the bound's ranges (N·I past 1200 A) or with other materials the bound
    solves nothing: neither does the shared path (it hands over None)."""
    d = design_preset("paper").clutch
    assert _shared_features(d, 7.0, DEFAULT_CHOICE, DEFAULT_MATERIALS) is not None
    assert _shared_features(d, 1e4 / d.coil_turns, DEFAULT_CHOICE, DEFAULT_MATERIALS) is None
    other = MaterialChoice(fluid="mrf_140cg")
    assert _shared_features(d, 7.0, other, material_set(other)) is None
    assert circuit_trust(d, "network", 1e4 / d.coil_turns)  # off the map: a note, no solve
