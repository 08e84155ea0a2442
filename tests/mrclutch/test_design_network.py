"""mrclutch.design_network: evaluate's stages share one design's network (issue 40), and
reading the torque from it gives ``torque_curve``'s numbers to the last digit."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from geometry.materials import MaterialChoice
from geometry.section import build_section
from magnetics.drag import Support
from magnetics.network import network_from_regions
from magnetics.torque import torque_curve
from mrclutch.design import design_preset, load_design
from mrclutch.design_network import (
    network_curve,
    network_yield,
    section_fluid,
    section_network,
    solved_at,
)
from mrclutch.duty import GRID, design_context
from mrclutch.trust import _shared_features, circuit_trust, material_set

ROOT = Path(__file__).resolve().parents[2]


def _designs() -> list:
    paper = design_preset("paper")
    return [paper, load_design(ROOT / "examples" / "thin_drums.toml"),
            replace(paper, clutch=replace(paper.clutch, n_drums=2, gap=0.45e-3))]  # fmt: skip


@pytest.mark.parametrize("k", range(3))
def test_network_curve_is_torque_curves_network_branch_to_the_last_digit(k: int) -> None:
    """Every field of the TorqueCurve equal (not close) at currents, a speed, a fluid
    temperature and a support that are not the defaults."""
    d = _designs()[k]
    section, net = section_network(d.clutch, d.materials)
    cur = np.array([0.0, 1.3, 4.0, d.current_limit])
    support = Support(seal_torque=2e-3)
    ref = torque_curve(build_section(d.clutch, d.materials), cur, method="network",
                       speed_rpm=300.0, temperature=35.0, support=support)  # fmt: skip
    got = network_curve(section, net, cur, 300.0, 35.0, support)
    for name in ("currents", "torque", "yield_torque", "gap_torque"):
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name
    assert got.method == "network" and got.gap_labels == ref.gap_labels
    assert (got.speed_rpm, got.off_state_torque, got.damping) == (
        ref.speed_rpm, ref.off_state_torque, ref.damping)  # fmt: skip
    assert np.array_equal(network_yield(section, net, cur), ref.yield_torque)


@pytest.mark.parametrize("k", range(3))
def test_one_solve_at_the_limit_serves_the_torque_and_the_trust_check(k: int) -> None:
    """clutch_figures solves the network once at N·I_max (``solved_at``) and hands the loop
    fluxes to the torque curve and to the trust check: the curve read from them is
    torque_curve's own solve, every field to the bit, and the trust check's notes are
    those it gives solving on its own (the paper preset, thin drums, a 2-drum variant)."""
    d = _designs()[k]
    section, net = section_network(d.clutch, d.materials)
    i = d.current_limit
    flux = solved_at(net, i)
    ref = torque_curve(build_section(d.clutch, d.materials), [i], method="network",
                       speed_rpm=300.0, temperature=35.0)  # fmt: skip
    got = network_curve(section, net, [i], 300.0, 35.0, None, flux)
    for name in ("torque", "yield_torque", "gap_torque"):
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name
    assert circuit_trust(d.clutch, "network", i, d.materials, flux) == circuit_trust(
        d.clutch, "network", i, d.materials)  # fmt: skip
    key = material_set(d.materials)
    own = _shared_features(d.clutch, i, d.materials, key)
    read = _shared_features(d.clutch, i, d.materials, key, flux)
    assert (own is None) == (read is None) and (k != 0 or own is not None)  # paper: solved
    if own is not None:
        assert own.keys() == read.keys()
        assert all(np.array_equal(own[f], read[f]) for f in own)
    other = solved_at(net, 0.5 * i)  # fluxes of another current: another torque
    assert not np.array_equal(network_curve(section, net, [i], 300.0, 35.0, None,
                                            other).torque, ref.torque)  # fmt: skip


def test_one_network_per_design_built_once_and_equal_to_a_fresh_build() -> None:
    d = design_preset("paper")
    s1, n1 = section_network(d.clutch, d.materials)
    s2, n2 = section_network(replace(d.clutch), replace(d.materials))  # equal values
    assert s1 is s2 and n1 is n2  # the second reader gets the first one's network
    fresh = network_from_regions(build_section(d.clutch, d.materials).table)
    assert np.array_equal(n1.turns, fresh.turns) and n1.film_name == fresh.film_name
    other = replace(d.clutch, gap=d.clutch.gap + 1e-5)
    s3, n3 = section_network(other, d.materials)
    assert n3 is not n1 and s3.clutch.gap == other.gap
    assert s1.clutch == d.clutch


def test_the_fluid_is_the_designs() -> None:
    d = design_preset("paper")
    other = MaterialChoice(fluid="mrf_140cg")
    assert section_fluid(section_network(d.clutch, d.materials)[0]).name == "mrf_132dg"
    assert section_fluid(section_network(d.clutch, other)[0]).name == "mrf_140cg"


def test_the_duty_reads_the_same_cold_curve_as_torque_curve() -> None:
    """The duty's cold yield curve on the shared network is torque_curve's on GRID
    currents, exactly (its running maximum: the curve rises)."""
    d = design_preset("paper")
    ctx = design_context(d, d.current_limit)
    cur = np.linspace(0.0, d.current_limit, GRID)
    ref = torque_curve(build_section(d.clutch, d.materials), cur, method="network")
    assert np.array_equal(ctx.currents, cur)
    assert np.array_equal(ctx.yield_cold, np.maximum.accumulate(ref.yield_torque))
