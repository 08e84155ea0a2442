"""The lumped thermal network: energy balance, closed forms, the transient against a
direct integration, the adiabatic current limit and the continuous rating."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geometry.params import broadcast_fields, preset
from geometry.regions import evaluate as regions_of
from geometry.section import build_section
from magnetics.circuit import path_from_section
from magnetics.drag import clutch_drag
from magnetics.thermal import (
    ALPHA_CU,
    adiabatic_current_density,
    churchill_chu_h,
    continuous_current,
    network,
    steady,
    time_constants,
    time_to_limits,
)
from magnetics.torque import continuous_torque, yield_torque_at

PAPER = preset("paper")
W = 530 * 2 * math.pi / 60


@pytest.fixture(scope="module")
def net():
    return network(build_section(PAPER).table)


def test_steady_state_conserves_energy(net):
    """Power in (coil at its own temperature + slip) = heat out to the air."""
    for current, slip in ((0.3, 0.0), (0.5, 1.5), (0.8, 0.2)):
        t = steady(net, current, slip)
        p_coil = current**2 * net.r20 * (1 + ALPHA_CU * (t[0] - 20.0))
        out = net.to_air * (t[2] - net.ambient)
        assert p_coil + slip == pytest.approx(out, rel=1e-10)
        assert t[0] >= t[2] and t[1] >= t[2] > net.ambient


def test_coil_runaway_is_infinite_not_negative(net):
    assert np.all(np.isinf(steady(net, 50.0)))


def test_continuous_current_reaches_exactly_one_limit(net):
    for slip in (0.0, 1.0, 2.0):
        i = float(continuous_current(net, 155.0, 130.0, slip))
        t = steady(net, i, slip)
        assert t[0] <= 155.0 + 1e-8 and t[1] <= 130.0 + 1e-8
        assert math.isclose(t[0], 155.0, rel_tol=1e-9) or math.isclose(t[1], 130.0, rel_tol=1e-9)
    assert continuous_current(net, 155.0, 130.0, 100.0) == 0.0  # slip heat alone too much


def test_transient_against_a_direct_integration(net):
    """time_to_limits against implicit-Euler steps of C dT/dt = −G T + q(T)."""
    i, slip = 3.0, 5.0
    t_wire, t_fluid = time_to_limits(net, i, slip, 155.0, 130.0)
    C, G = net.capacity, net.conductance
    dt, t = 1e-3, 0.0
    # each step solves (C/dt + G) T' = C/dt T + q(T): the matrix's inverse once, and the
    # 2.1e5 steps on plain floats (np.linalg.solve a step: 5.9 s of CPU, this ~0.5 s)
    (a, b, c), (d, e, f), (g, h, k) = np.linalg.inv(np.diag(C / dt) + G).tolist()
    c0, c1, c2 = (C / dt).tolist()
    heat, air = i**2 * net.r20, net.to_air * net.ambient
    T = [float(net.ambient)] * 3
    hit = [None, None]
    while t < 1.2 * t_fluid:
        r0 = c0 * T[0] + heat * (1 + ALPHA_CU * (T[0] - 20.0))
        r1, r2 = c1 * T[1] + slip, c2 * T[2] + air
        T = [a * r0 + b * r1 + c * r2, d * r0 + e * r1 + f * r2, g * r0 + h * r1 + k * r2]
        t += dt
        for j, lim in ((0, 155.0), (1, 130.0)):
            if hit[j] is None and T[j] >= lim:
                hit[j] = t
    assert hit[0] == pytest.approx(t_wire, rel=2e-3)
    assert hit[1] == pytest.approx(t_fluid, rel=2e-3)


def test_time_constants_are_positive_and_the_slowest_is_the_air(net):
    tau = time_constants(net)
    assert np.all(tau > 0) and tau[0] > 10 * tau[1]
    total_c = float(np.sum(net.capacity))
    # the slowest mode: the whole clutch against the air, τ ≈ ΣC / G_air
    assert tau[0] == pytest.approx(total_c / net.to_air, rel=0.05)


def test_adiabatic_limit_is_the_copper_heat_balance():
    """IEC 60949's K = √(c_v (β + 20)/ρ20) for copper: 226 A·s^½/mm² within 1 %."""
    c_v, rho20 = 3.45e6, 1.72e-8
    assert math.sqrt(c_v * (234.5 + 20) / rho20) == pytest.approx(226e6, rel=0.01)
    j = adiabatic_current_density(1.0, 20.0, 155.0)
    assert j == pytest.approx(226e6 * math.sqrt(math.log(389.5 / 254.5)), rel=1e-12)
    assert adiabatic_current_density(4.0, 20.0, 155.0) == pytest.approx(j / 2, rel=1e-12)


def test_churchill_chu_value():
    """A 25.8 mm cylinder 55 K above 20 °C air: Nu ≈ 6.8, h ≈ 7 W/(m²·K)."""
    h = churchill_chu_h(0.0258, 55.0, 20.0)
    assert 5.0 < h < 9.0


def _exact_continuous(rg, path, off, w=W):
    """Bisection with a full circuit solve at every step: the reference fixed point."""
    net = network(rg)
    lo, hi = 0.0, 20.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        t = float(yield_torque_at(path, mid)[0]) + off
        if mid <= float(continuous_current(net, 155.0, 130.0, t * w)):
            lo = mid
        else:
            hi = mid
    return lo, float(yield_torque_at(path, lo)[0]) + off


def _random_designs(n: int, seed: int) -> list[dict]:
    """Designs of the sweep's ranges (examples/random_sweep.toml)."""
    rng = np.random.default_rng(seed)
    return [
        dict(n_drums=int(rng.integers(1, 5)), gap=rng.uniform(0.2e-3, 1e-3),
             drum_thickness=rng.uniform(0.1e-3, 0.6e-3), zone_length=rng.uniform(3e-3, 9e-3),
             drum_inner_diameter=rng.uniform(6e-3, 18e-3))
        for _ in range(n)
    ]  # fmt: skip


def _chord_errors(designs: list[dict], passes: int) -> np.ndarray:
    """|relative error| (current, torque) of ``continuous_torque`` against the exact
    fixed point, one row per design."""
    from dataclasses import replace

    out = []
    for change in designs:
        s = build_section(replace(PAPER, **change))
        rg, path = s.table, path_from_section(s)
        off = clutch_drag(rg, W).torque
        i_fast, t_fast = continuous_torque(network(rg), path, W, off, 155.0, 130.0,
                                           passes=passes)  # fmt: skip
        i_exact, t_exact = _exact_continuous(rg, path, off)
        out.append((float(i_fast[0]) / i_exact - 1, float(t_fast[0]) / t_exact - 1))
    return np.abs(np.array(out))


def test_continuous_torque_chords_against_the_exact_fixed_point():
    """The sweep's rating (three chords, one circuit solve each) against bisection with a
    circuit solve at every step: within 1 % in current and torque on the preset and on
    random designs of the sweep's ranges."""
    err = _chord_errors([{}, *_random_designs(16, 3)], passes=3)
    assert err.max() < 0.01, err.max(0)


def test_one_chord_is_not_enough_off_the_preset():
    """Where the method breaks down: the single chord through I_a (the earlier rating)
    is good on the preset but tens of percent off where the slip heat pulls the answer
    far below I_a on the concave part of the torque curve."""
    assert _chord_errors([{}], passes=1).max() < 0.02
    assert _chord_errors(_random_designs(16, 3), passes=1)[:, 0].max() > 0.15


def test_network_of_a_batch_equals_one_design_at_a_time():
    gaps = np.array([0.3e-3, 0.7e-3])
    p = broadcast_fields({"gap": gaps}, PAPER)
    nb = network(regions_of(p, 2))
    for i, g in enumerate(gaps):
        from dataclasses import replace

        n1 = network(build_section(replace(PAPER, gap=float(g))).table)
        assert nb.conductance[i] == pytest.approx(n1.conductance, rel=1e-12)
        assert nb.capacity[i] == pytest.approx(n1.capacity, rel=1e-12)


def test_network_inverse_is_the_matrix_inverse():
    """The adjugate inverse the network stores equals numpy's LU inverse."""
    from magnetics.thermal import _inverse3

    a = np.random.default_rng(0).normal(size=(200, 3, 3))
    assert np.allclose(_inverse3(a) @ a, np.eye(3), atol=1e-10)
    net = network(build_section(PAPER).table)
    assert net.inverse == pytest.approx(np.linalg.inv(net.conductance), rel=1e-12)


def test_continuous_torque_chords_through_the_network():
    """The rating the fast path uses since the network became the default torque model:
    the secant on the network's slope T/I (``torque_at``, ``slope_rating``) against
    bisection with a network solve at every step, on the preset and on random designs of
    the sweep's ranges. Measured: up to 2.3e-4 in current and 1.1e-4 in torque (three
    chords through the network, before: 1.02 % and 0.49 %; the circuit's: 0.75 %, 0.33 %)."""
    from dataclasses import replace

    from magnetics.network import network_from_regions
    from magnetics.torque import network_yield_at

    out = []
    for change in [{}, *_random_designs(8, 3)]:
        s = build_section(replace(PAPER, **change))
        rg, path = s.table, path_from_section(s)
        off = clutch_drag(rg, W).torque
        at = network_yield_at(network_from_regions(rg))
        i_fast, t_fast = continuous_torque(network(rg), path, W, off, 155.0, 130.0,
                                           torque_at=at)  # fmt: skip
        net, lo, hi = network(rg), 0.0, 20.0
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            t = float(at(np.array([mid]))[0]) + off
            if mid <= float(continuous_current(net, 155.0, 130.0, t * W)):
                lo = mid
            else:
                hi = mid
        t_exact = float(at(np.array([lo]))[0]) + off
        out.append((float(i_fast[0]) / lo - 1, float(t_fast[0]) / t_exact - 1))
    err = np.abs(out)
    assert err[:, 0].max() < 5e-4 and err[:, 1].max() < 2.5e-4, err.max(0)


def test_network_rating_solves_each_row_twice_and_a_moved_row_once_more():
    """``slope_rating``'s solves, on the paper preset at 4 drums and 7 random 4-drum designs
    as one batch: the first at ``_SLOPE_TINY``·I_a (the slope at I → 0), the second at the
    fixed point of that slope's chord, a third (``rows=``) only on the rows whose model's
    fixed point lies more than ``_SLOPE_MOVED``·I₁ from I₁ (here some, not all); each at
    ``_SLOPE_RTOL`` (1e-6): the rating equals the one with every solve at 1e-10 to 1e-6
    (the answer is the model's, to ~1e-3 on bench_chords' 2000 designs, not the solve's)."""
    from dataclasses import replace

    from magnetics.circuit import path_from_regions
    from magnetics.drag import drag_terms, totals
    from magnetics.network import network_from_regions
    from magnetics.network.torque import _SLOPE_MOVED, _SLOPE_RTOL, _SLOPE_TINY
    from magnetics.thermal import continuous_current_sq
    from magnetics.torque import network_yield_at

    designs = [vars(replace(PAPER, n_drums=4)), *(vars(replace(PAPER, **c)) for c in
               _random_designs(40, 11) if c["n_drums"] == 4)][:8]  # fmt: skip
    p = broadcast_fields({k: np.array([d[k] for d in designs], float) for k in designs[0]})
    rg = regions_of(p, 4)
    path, tnet = path_from_regions(rg), network(rg)
    off = totals(drag_terms(rg, W))[0]
    i_a = np.sqrt(continuous_current_sq(tnet, 155.0, 130.0)(off * W))
    got, calls = {}, []
    for how in ("asked", "full"):
        at = network_yield_at(network_from_regions(rg))

        def traced(cur, rtol=1e-10, rows=None, at=at, how=how):  # type: ignore[no-untyped-def]
            if how == "asked":
                calls.append((np.array(cur), rtol, rows))
            return at(cur, rtol=rtol if how == "asked" else 1e-10, rows=rows)

        got[how] = continuous_torque(tnet, path, W, off, 155.0, 130.0, torque_at=traced)
    assert [c[1] for c in calls] == [_SLOPE_RTOL] * 3 and _SLOPE_RTOL == 1e-6
    np.testing.assert_array_equal(calls[0][0], _SLOPE_TINY * i_a)
    assert calls[0][2] is None and calls[1][2] is None
    moved = calls[2][2]
    i1, i2 = calls[1][0], got["asked"][0]
    assert 0 < moved.sum() < moved.size and calls[2][0].shape == (moved.sum(),)
    # the moved rows are solved where their model's answer lay, beyond _SLOPE_MOVED of
    # their solved point; the others' answer lies within it
    assert np.all(np.abs(calls[2][0] - i1[moved]) > _SLOPE_MOVED * i1[moved])
    assert np.all(np.abs(i2[~moved] - i1[~moved]) <= _SLOPE_MOVED * i1[~moved])
    np.testing.assert_allclose(got["asked"][1], got["full"][1], rtol=1e-6)
