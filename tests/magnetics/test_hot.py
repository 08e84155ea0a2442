"""Issue 41, item 3: τy(T) by dilution, the thermal march with the coil's R(T) and the
load fed back (magnetics.hot), and the fluid's life (magnetics.life)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from geometry.params import broadcast_fields, preset
from geometry.regions import evaluate as regions_of
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics import thermal
from magnetics.hot import Load, march, phi_at, tau_y_coefficient, tau_y_factor
from magnetics.life import fluid_volume, life_hours, mean_power
from magnetics.materials import FLUIDS

FLUID = FLUIDS["mrf_132dg"]


def test_tau_y_factor_hand_worked() -> None:
    """φ0 = 0.32, β = 7e-4 1/K, 120 °C (ΔT = 100 K): the carrier's share grows to
    0.68 × 1.07 = 0.7276, so φ = 0.32/(0.32 + 0.7276) = 0.305460 and
    τy/τy0 = (0.305460/0.32)^1.5239 = 0.931588. At 20 °C the factor is 1."""
    fl = replace(FLUID, phi=0.32, carrier_expansion=7e-4)
    assert phi_at(0.32, 7e-4, 120.0) == pytest.approx(0.305460, rel=1e-5)
    assert tau_y_factor(fl, 120.0) == pytest.approx(0.931588, rel=1e-5)
    assert tau_y_factor(fl, 20.0) == pytest.approx(1.0, abs=1e-15)
    # a planted error in the exponent (φ^1 instead of φ^1.5239) is 4.5 % off: caught
    assert abs(0.305460 / 0.32 - tau_y_factor(fl, 120.0)) > 0.02


def test_tau_y_coefficient_hand_worked_and_is_the_slope() -> None:
    """−1.5239 × (1 − 0.32) × 7e-4 = −7.25376e-4 1/K (−0.0725 %/K), the slope of the
    factor at 20 °C (central difference); a fluid with no expansion has none."""
    fl = replace(FLUID, phi=0.32, carrier_expansion=7e-4)
    assert tau_y_coefficient(fl) == pytest.approx(-7.25376e-4, rel=1e-6)
    slope = (tau_y_factor(fl, 20.5) - tau_y_factor(fl, 19.5)) / 1.0
    assert slope == pytest.approx(tau_y_coefficient(fl), rel=1e-3)
    bare = replace(FLUID, carrier_expansion=None)
    assert tau_y_coefficient(bare) is None
    assert float(tau_y_factor(bare, 100.0)) == 1.0


def _one_node() -> thermal.Network:
    """A coil of 10 J/K tied by 1 W/K to a core and housing of 1e12 J/K (they stay at
    ambient), R20 = 1 Ω."""
    g = np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
    return thermal.Network(np.array([10.0, 1e12, 1e12]), g, 1.0, 1.0, 20.0,
                           thermal._inverse3(g))  # fmt: skip


def test_march_hand_worked_coil_with_its_resistance_law() -> None:
    """2 A through R(T) = 1 Ω (1 + 0.00393 (T − 20)) into 1 W/K, C = 10 J/K:
    C dΔT/dt = 4 (1 + αΔT) − ΔT, so ΔT∞ = 4/(1 − 4α) = 4/0.98428 = 4.063884 K and
    τ = 10/0.98428 s; at 10 s ΔT = 4.063884 (1 − e^−0.98428) = 4.063884 × 0.626292 =
    2.545177 K. Exact for any step count under a constant load. Without the R(T) term
    (α = 0) it would be 4 (1 − e^−1) = 2.528482: 0.66 % off, caught."""
    net = _one_node()
    for steps in (1, 7, 50):
        m = march(net, lambda t: Load(2.0, 0.0), 10.0, steps)
        assert m.final[0] - 20.0 == pytest.approx(2.545177, rel=1e-6)
        assert m.final[1] == pytest.approx(20.0, abs=1e-6)
    assert abs(2.528482 - 2.545177) / 2.545177 > 5e-3


def test_march_slip_power_heats_the_core_node() -> None:
    """The slip power goes into the core (node 1): with no current the coil only follows
    it; a planted swap of the two inputs would heat the coil first."""
    rg = build_section(preset("paper")).table
    net = thermal.network(rg, 20.0, 130.0)
    m = march(net, lambda t: Load(0.0, 5.0), 20.0, 20)
    assert m.final[1] > m.final[0] > 20.0


def test_march_equals_the_exact_transient_at_the_fluid_limit() -> None:
    """Paper preset, 7 A and 0.42 N·m × 55.5 rad/s held: ``thermal.time_to_limits`` (modal
    solution) gives the time the core reaches 130 °C; the march (constant load, so exact)
    reaches 130 °C at that time."""
    rg = build_section(preset("paper")).table
    net = thermal.network(rg, 20.0, 130.0)
    p = 0.42 * 530 * 2 * math.pi / 60
    _, t_fluid = thermal.time_to_limits(net, 7.0, p, 1e9, 130.0)
    m = march(net, lambda t: Load(7.0, p), t_fluid, 5)
    assert m.final[1] == pytest.approx(130.0, abs=1e-6)


def test_march_feedback_reads_the_temperatures() -> None:
    """A load that cuts its current once the coil passes 30 °C: the march holds it near
    30 °C (within one step's rise), which a march ignoring the feedback would not."""
    net = _one_node()
    m = march(net, lambda t: Load(2.0 if t[0] < 22.0 else 0.0, 0.0), 200.0, 2000)
    assert 21.5 < m.temperatures[-1, 0] < 22.2
    assert m.currents[0] == 2.0 and 0.0 in m.currents


def test_march_and_load_refuse_bad_input() -> None:
    with pytest.raises(ParameterError, match="duration"):
        march(_one_node(), lambda t: Load(1.0, 0.0), 0.0)
    with pytest.raises(ParameterError, match="steps"):
        march(_one_node(), lambda t: Load(1.0, 0.0), 1.0, 0)
    with pytest.raises(ParameterError, match="current"):
        Load(-1.0, 0.0)


def test_life_hand_worked() -> None:
    """2.8 mL at LDE 5e12 J/m³ holds 1.4e7 J: at 1 W, 1.4e7/3600 = 3888.9 h. A duty of
    0.2 N·m a quarter of the time and 1 mN·m otherwise at 55.5 rad/s dissipates
    (0.25 × 0.2 + 0.75 × 0.001) × 55.5 = 2.816625 W (a planted swap of f and 1 − f gives
    8.4 W)."""
    assert life_hours(2.8e-6, 1.0, 5e12) == pytest.approx(3888.8889, rel=1e-7)
    assert mean_power(0.2, 0.001, 55.5, 0.25) == pytest.approx(2.816625, rel=1e-12)
    assert math.isnan(life_hours(2.8e-6, 1.0, None))
    assert life_hours(2.8e-6, 0.0, 5e12) == math.inf
    with pytest.raises(ParameterError, match="on_fraction"):
        mean_power(0.2, 0.0, 1.0, 1.5)


def test_fluid_volume_sums_the_fluid_regions_and_batches() -> None:
    """The paper preset's four drum films alone hold Σ π (r1² − r0²) L = 2.498 mL (each
    region's bounds); with the face films and the cavity 2.80 mL — the paper clutch's
    ~2.8 mL (issue 41). The batch path gives the same number per row, and a wider gap
    holds more."""
    rg = build_section(preset("paper")).table
    films = sum(math.pi * (b[1] ** 2 - b[0] ** 2) * (b[3] - b[2])
                for b in (rg.bounds(sp) for sp in rg.films("cylinder")))  # fmt: skip
    total = fluid_volume(rg)
    assert films * 1e6 == pytest.approx(2.498, abs=2e-3)
    assert total * 1e6 == pytest.approx(2.8, rel=0.02)
    p = broadcast_fields({"gap": np.array([preset("paper").gap, 1.2 * preset("paper").gap])},
                         preset("paper"))  # fmt: skip
    vols = fluid_volume(regions_of(p, preset("paper").n_drums))
    assert vols[0] == pytest.approx(total, rel=1e-12)
    assert vols[1] > vols[0]


def _march_per_step(net, load, duration, steps):  # type: ignore[no-untyped-def]
    """The oracle: ``march``'s step with G' and e^{−Mh} rebuilt at every step (the loop as
    it was before the reuse of a held current's matrices)."""
    from magnetics.hot import _expm_sym
    from magnetics.thermal import ALPHA_CU

    cap = np.asarray(net.capacity, dtype=float).reshape(3)
    g0 = np.asarray(net.conductance, dtype=float).reshape(3, 3)
    r20 = float(np.asarray(net.r20).reshape(()))
    to_air = float(np.asarray(net.to_air).reshape(()))
    a, c = r20 * ALPHA_CU, r20 * (1 - 20 * ALPHA_CU)
    h = duration / steps
    s = np.sqrt(cap)
    t = np.full(3, float(net.ambient))
    temps, cur, pw = [t.copy()], [], []
    for _ in range(steps):
        ld = load(t)
        x = ld.current**2
        g = g0.copy()
        g[0, 0] -= x * a
        q = np.array([x * c, ld.slip_power, to_air * net.ambient])
        t_star = np.linalg.solve(g, q)
        t = t_star + (1 / s) * (_expm_sym(g, s, h) @ (s * (t - t_star)))
        temps.append(t.copy())
        cur.append(ld.current)
        pw.append(ld.slip_power)
    return np.array(temps), np.array(cur), np.array(pw)


def test_march_reusing_a_held_currents_matrices_is_bit_identical() -> None:
    """``march`` reuses G' and e^{−Mh} while the current is bit-equal to the last step's
    (a peak hold's first steps): the temperatures, currents and powers are the same bits
    as the per-step oracle's, on the paper preset and on random designs and loads — a held
    current, one that then rises with the core temperature, and one that alternates
    between two values (a reuse keyed on anything but the last step's current fails it)."""
    rng = np.random.default_rng(44)
    base = preset("paper")
    designs = [base] + [
        replace(base, gap=base.gap * rng.uniform(0.8, 1.2),
                zone_length=base.zone_length * rng.uniform(0.8, 1.2))
        for _ in range(3)
    ]  # fmt: skip
    for k, d in enumerate(designs):
        net = thermal.network(build_section(d).table, 20.0, 130.0)
        i0, p = (7.0, 23.0) if k == 0 else (rng.uniform(1, 8), rng.uniform(0, 30))
        knee = 20.0 + rng.uniform(5, 40)
        loads = (
            lambda t, i0=i0, p=p, knee=knee: Load(
                i0 if t[1] < knee else min(i0 * (1 + 0.01 * (t[1] - knee)), 1.5 * i0), p),
            lambda t, i0=i0, p=p: Load(i0 if int(t[0] * 10) % 2 else 0.5 * i0, p + t[1] / 10),
        )  # fmt: skip
        for load in loads:
            m = march(net, load, 120.0, 300)
            temps, cur, pw = _march_per_step(net, load, 120.0, 300)
            assert len(set(cur.tolist())) > 1 and len(set(cur.tolist())) < len(cur)
            assert np.array_equal(m.temperatures, temps)
            assert np.array_equal(m.currents, cur) and np.array_equal(m.slip_powers, pw)
