"""The failure map: sweep each method into the region where it stops being trustworthy and
check that the tool warns (FidelityWarning) or refuses there — never a silent wrong
number — and that the default methods stay trusted on the paper preset."""

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from geometry.validation import ParameterError
from mrclutch.design import design_preset
from mrclutch.fidelity import circuit_torque, fem_torque, linear_torque
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.haptics.delay import pade_stable_stiffness
from mrclutch.haptics.model import bandwidth, bandwidth_lumped, max_stable_stiffness
from mrclutch.trust import (
    CIRCUIT_TORQUE_TRUST,
    FidelityWarning,
    circuit_trust,
    linear_circuit_trust,
    lumped_trust,
    mesh_trust,
    pade_trust,
)


@pytest.fixture(scope="module")
def paper():
    return design_preset("paper")


def _value_and_warned(fn, *a):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always", FidelityWarning)
        v = fn(*a)
    return v, any(issubclass(x.category, FidelityWarning) for x in w)


def test_linear_circuit_past_the_knee_warns(paper):
    errs, warned = [], []
    for i in (0.2, 0.5, 1.0, 2.0, 4.0, 7.0):
        d = replace(paper, operating=replace(paper.operating, max_current=i))
        lin, w = _value_and_warned(linear_torque, d)
        sat, _ = _value_and_warned(circuit_torque, d)
        errs.append(abs(lin / sat - 1))
        warned.append(w)
    assert not warned[0] and errs[0] < 0.05  # trusted at low current and right there
    assert warned[-1] and errs[-1] > 0.2  # past the knee: wrong, and it says so
    for e, w in zip(errs, warned, strict=True):
        assert w or e < 0.05, (errs, warned)  # never silently > 5 % off


def test_circuit_off_the_fem_warns(paper):
    """Sweep drum count, gap and zone length (off the map's nodes, so the interpolation and
    its margin are what is tested) and short zones outside the map: every design whose
    circuit torque is more than CIRCUIT_TORQUE_TRUST off the FEM (0.35 mm, within 0.5 % of
    the reference) is flagged."""
    cases = [  # (drums, gap, zone length)
        (2, 0.55e-3, 5.0e-3),
        (2, 0.85e-3, 7.5e-3),
        (1, 0.55e-3, 4.5e-3),
        (3, 0.85e-3, 5.0e-3),
        (4, 0.3e-3, 7.5e-3),
        (2, 0.7e-3, 1.5e-3),  # a short zone, outside the map
    ]
    flagged, errs = [], []
    for n, gap, zl in cases:
        d = replace(paper, clutch=replace(paper.clutch, n_drums=n, gap=gap, zone_length=zl))
        circ, warned = _value_and_warned(circuit_torque, d)
        err = abs(circ / fem_torque(d, 0.35e-3) - 1)
        assert warned or err < CIRCUIT_TORQUE_TRUST, (n, gap, zl, err)
        flagged.append(warned)
        errs.append(err)
    assert flagged[-1] and not flagged[0]
    assert max(errs) > CIRCUIT_TORQUE_TRUST  # the sweep does reach the failure region


def test_fast_evaluate_notes_an_untrusted_network(paper, monkeypatch):
    """The fast fidelity's torque is the reluctance network's. Its bound over every section
    dimension (magnetics.network_bound) stays within CIRCUIT_TORQUE_TRUST on the paper
    preset and on a half-thickness shell (which the five-axis map called off the map), so
    they carry no note. Where the bound is past the trust (here with the trust lowered
    below it), or the shell is outside the measured range, it is still used, and says so."""
    import mrclutch.trust as trust
    from magnetics.error_map import circuit_error
    from magnetics.network_bound import load
    from mrclutch.pipeline import evaluate

    thin = replace(paper, clutch=replace(paper.clutch, shell_thickness=0.7e-3))
    b = circuit_error(thin.clutch, "network", thin.current_limit).bound
    assert 0.0 < b < CIRCUIT_TORQUE_TRUST
    assert evaluate(thin).clutch.methods["torque"] == "network"
    assert not any("reluctance network" in n for n in evaluate(thin).clutch.notes)
    monkeypatch.setattr(trust, "CIRCUIT_TORQUE_TRUST", 0.9 * b)
    notes = evaluate(thin).clutch.notes
    assert any(n.startswith("reluctance network: torque") and "use the FEM" in n for n in notes)
    monkeypatch.undo()
    hi = load().ranges["shell_thickness"][1]
    shell = replace(paper, clutch=replace(paper.clutch, shell_thickness=1.05 * hi))
    assert any("reluctance network: off the measured error map" in n and "shell_thickness" in n
               for n in evaluate(shell).clutch.notes)  # fmt: skip
    assert not any("reluctance network" in n for n in evaluate(paper).clutch.notes)


def test_mesh_below_drum_thickness_is_refined_or_refused(paper):
    from geometry.mass import brep_mass, mesh_mass, thinnest_feature

    thin = replace(paper.clutch, drum_thickness=0.15e-3, input_drum_thickness=0.15e-3)
    tol = 0.2e-3  # coarser than the drum walls
    assert tol > thinnest_feature(thin) / 2 and mesh_trust(thin, tol)
    assert not mesh_trust(paper.clutch, 0.01e-3)
    try:
        rep = mesh_mass(thin, tolerance=tol, max_refinements=3)
    except ParameterError as exc:  # refused
        assert "not converged" in str(exc) or "watertight" in str(exc)
    else:  # refined, said so, and right
        assert any("refined" in n for n in rep.notes)
        assert rep.rotor_inertia == pytest.approx(brep_mass(thin).rotor_inertia, rel=5e-3)


def test_pade_at_high_K_tau_warns():
    flagged, errs = [], []
    for tau in (0.2e-3, 1e-3, 5e-3, 20e-3):
        p = replace(TABLE2_MR, delay=tau)
        k = pade_stable_stiffness(p, 1)
        errs.append(abs(k / max_stable_stiffness(p) - 1))
        flagged.append(bool(pade_trust(p, k, 1)))
    for e, f in zip(errs, flagged, strict=True):
        assert f or e < 0.01, (errs, flagged)
    assert any(flagged) and not all(flagged)


def test_lumped_bandwidth_near_the_transmission_mode_warns():
    K = 300.0
    flagged, errs = [], []
    for k in (4000.0, 200.0, 50.0, 20.0, 10.0):
        p = replace(TABLE2_MR, k=k, b=0.1)
        errs.append(abs(bandwidth_lumped(p, K) / bandwidth(p, K) - 1))
        flagged.append(bool(lumped_trust(p, K)))
    assert not flagged[0] and errs[0] < 0.05
    for e, f in zip(errs, flagged, strict=True):
        assert f or e < 0.05 or math.isnan(e), (errs, flagged)
    assert flagged[-1]


def test_default_methods_are_trusted_on_the_paper_preset(paper):
    from mrclutch.fidelity import haptic_params

    assert not circuit_trust(paper.clutch)  # fast path's torque method
    assert linear_circuit_trust(paper.clutch, 0.2) == ()
    p, k = haptic_params(paper)
    assert not lumped_trust(p, k)
    assert not pade_trust(p, max_stable_stiffness(p), 2)
    assert np.isfinite(bandwidth(p, k))
