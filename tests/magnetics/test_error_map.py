"""The circuit's measured error map: the interpolation (exact for multilinear data, NaN off
the grid), its bound (no margin at a node, the whole tolerance off the base preset), and
the stored numbers, re-measured so they cannot silently go stale."""

from dataclasses import replace

import numpy as np
import pytest

from geometry.params import preset
from magnetics.error_map import circuit_error, error_bound, load
from magnetics.interpolation import _interp, interpolate

AXES = {"n": (1, 2, 3), "x": (0.0, 1.0, 3.0), "y": (-1.0, 2.0)}


def _multilinear(n, x, y):
    return 0.3 + n * (0.5 * x - 0.2 * y + 0.7 * x * y)


def test_interpolation_reproduces_multilinear_data():
    nn, xx, yy = np.meshgrid(*AXES.values(), indexing="ij")
    grid = _multilinear(nn, xx, yy)
    rng = np.random.default_rng(0)
    x, y, n = rng.uniform(0, 3, 50), rng.uniform(-1, 2, 50), rng.integers(1, 4, 50)
    est = interpolate(AXES, grid, {"n": n, "x": x, "y": y})
    assert np.allclose(est, _multilinear(n, x, y), rtol=1e-12, atol=1e-12)


def test_off_the_grid_is_nan_and_a_nan_corner_only_counts_with_weight():
    grid = np.zeros((3, 3, 2))
    assert np.isnan(interpolate(AXES, grid, {"n": 1.5, "x": 0.5, "y": 0}))  # between counts
    assert np.isnan(interpolate(AXES, grid, {"n": 1, "x": 3.5, "y": 0}))
    assert np.isnan(interpolate(AXES, grid, {"n": 4, "x": 1.0, "y": 0}))
    grid[0, 2, :] = np.nan  # an invalid design at x = 3
    assert interpolate(AXES, grid, {"n": 1, "x": 1.0, "y": 0.5}) == 0.0  # on the node x = 1
    assert np.isnan(interpolate(AXES, grid, {"n": 1, "x": 2.0, "y": 0.5}))


def _local_variation(c):
    axes = dict(load().axes)
    grid = np.array(load().errors).reshape([len(v) for v in axes.values()])
    return _interp(axes, grid, {k: getattr(c, k) for k in axes})[2]


def test_bound_has_no_margin_on_a_node_a_margin_between_and_none_off_the_base():
    paper = preset("paper")
    e = circuit_error(paper)  # the paper preset is a node of the map
    assert e.bound == pytest.approx(abs(e.estimate), abs=1e-15) and not e.notes
    mid = replace(paper, gap=0.55e-3)  # half way between two gap nodes
    margin = load().range_factor * _local_variation(mid)
    assert margin > 0.01
    assert circuit_error(mid).bound == pytest.approx(abs(circuit_error(mid).estimate) + margin)
    off = replace(paper, shell_thickness=2e-3)  # on the node, but off the base preset
    assert np.isnan(circuit_error(off).estimate) and circuit_error(off).bound == np.inf
    assert "shell_thickness" in circuit_error(off).notes[0]
    assert "off the measured error map" in circuit_error(off).notes[0]
    holes = circuit_error(preset("paper-holes"))  # holes: invisible to both solvers
    assert holes.bound == e.bound
    outside = circuit_error(replace(paper, n_drums=9))
    assert np.isnan(outside.estimate) and outside.bound == np.inf
    assert "outside the measured error map" in outside.notes[0]


def test_stored_checks_lie_within_their_bounds():
    """RANGE_FACTOR is what the off-grid checks measured: every check is inside its bound."""
    paper = preset("paper")
    names = ("n_drums", "gap", "zone_length", "drum_inner_diameter", "drum_thickness")
    for row in load().checks:
        kw = dict(zip(names, row[:5], strict=True))
        c = replace(paper, **{**kw, "n_drums": int(row[0])})
        e = circuit_error(c)
        assert abs(row[5] - e.estimate) <= e.bound - abs(e.estimate) + 1e-12, row


def test_vectorised_bound_equals_the_single_design_one():
    from geometry.params import broadcast_fields

    paper = preset("paper")
    gaps = np.array([0.2e-3, 0.55e-3, 0.7e-3, 1.2e-3])
    est, bound, _ = error_bound(broadcast_fields({"gap": gaps, "n_drums": 3}, paper))
    for g, e, b in zip(gaps, est, bound, strict=True):
        one = circuit_error(replace(paper, gap=g, n_drums=3))
        assert (e, b) == pytest.approx((one.estimate, one.bound), nan_ok=True)


@pytest.mark.parametrize(
    "node", [dict(n_drums=2), dict(n_drums=1, gap=0.4e-3), dict(n_drums=4, zone_length=9e-3)]
)
def test_stored_map_holds(node):
    """Re-measure nodes of the stored map: the circuit against the reference FEM."""
    from magnetics.torque import torque_curve
    from mrclutch.design import design_preset

    d = design_preset("paper")
    c = replace(d.clutch, **node)
    i = [replace(d, clutch=c).current_limit]
    ref = torque_curve(c, i, method="fem", fem_size=load().reference_fem_size).yield_torque[0]
    err = torque_curve(c, i, method="circuit").yield_torque[0] / ref - 1
    assert err == pytest.approx(circuit_error(c).estimate, abs=2e-5)  # stored to 5 decimals


def test_a_dimension_off_the_maps_axes_moves_the_error_by_tens_of_percent():
    """Why a design off the map's axes gets no bound: halving the shell (1.4 → 0.7 mm)
    takes the circuit from +0.5 % to tens of percent off the FEM, far beyond any margin
    the map's local variation would give (issue 16: −34 %)."""
    from magnetics.torque import torque_curve
    from mrclutch.design import design_preset

    d = design_preset("paper")
    c = replace(d.clutch, shell_thickness=0.7e-3)
    i = [replace(d, clutch=c).current_limit]
    ref = torque_curve(c, i, method="fem", fem_size=load().reference_fem_size).yield_torque[0]
    err = torque_curve(c, i, method="circuit").yield_torque[0] / ref - 1
    assert abs(err) > 0.2, err
    assert circuit_error(c).bound == np.inf
