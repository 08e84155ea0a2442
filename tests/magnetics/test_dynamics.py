"""Response time from the geometry (magnetics/dynamics.py): closed forms first."""

from dataclasses import replace

import numpy as np
import pytest

from geometry.params import preset
from geometry.regions import per_topology
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.circuit import path_from_section
from magnetics.dynamics import (
    Amplifier,
    current_rise,
    flux_linkage,
    lag_bandwidth,
    lag_step,
    torque_response,
)
from magnetics.eddy_lag import (
    diffusion_mean_delay,
    diffusion_response,
    diffusion_step,
    diffusion_time_constant,
)
from magnetics.laminations import Laminations
from magnetics.materials import MU0, linear_materials

PAPER = preset("paper")


def _response(c=PAPER, current=7.0, **kw):
    return torque_response(build_section(c).table, current, **kw)


# ---- diffusion series ------------------------------------------------------------------------


@pytest.mark.parametrize("shape", ["slab", "cylinder"])
def test_diffusion_series_mean_delay_and_first_mode(shape):
    """∫(1 − Φ/Φ∞) dt equals the closed-form mean delay (μσd²/12, μσa²/8); late in the
    step the first mode alone remains: 1 − Φ/Φ∞ → c₁ e^{−t/τ₁}."""
    tau1 = 1e-3
    # 0.05 µs steps over the first τ₁ (where the 200 modes still count), 2 µs after it: the
    # trapezoid's error 1.5e-7 of the mean (4e5 even 0.1 µs steps: 1.2e-7 at 12x the CPU
    # and 0.6 GB of temporaries)
    t = np.concatenate([np.linspace(0, 1e-3, 20001), np.linspace(1e-3, 40e-3, 20001)[1:]])
    y = diffusion_step(shape, tau1, t)
    assert y[0] == pytest.approx(0.0, abs=3e-3)  # the series' remainder, 200 modes
    mean = np.trapezoid(1 - y, t)
    assert mean == pytest.approx(float(diffusion_mean_delay(shape, tau1)), rel=2e-3)
    c1 = 8 / np.pi**2 if shape == "slab" else 4 / 2.404825557695773**2
    late = np.array([3e-3, 5e-3])
    np.testing.assert_allclose(1 - diffusion_step(shape, tau1, late), c1 * np.exp(-late / tau1),
                               rtol=1e-4)  # fmt: skip


def test_slab_response_is_tanh_x_over_x():
    """The partial fractions sum to the slab's closed form tanh(x)/x, x = (d/2)√(sμσ)."""
    mu, sigma, d = 500 * MU0, 5.8e6, 2e-3
    tau1 = diffusion_time_constant("slab", mu, sigma, d)
    assert tau1 == pytest.approx(mu * sigma * d**2 / np.pi**2)
    w = np.array([10.0, 1e3, 3e4])
    x = 0.5 * d * np.sqrt(1j * w * mu * sigma)
    np.testing.assert_allclose(diffusion_response("slab", tau1, 1j * w, n=20000), np.tanh(x) / x,
                               rtol=2e-4)  # fmt: skip


def test_thicker_shell_slower_eddy():
    a, b = _response(), _response(replace(PAPER, shell_thickness=2.0e-3))
    assert b.eddy["back_iron"].tau1[0] > a.eddy["back_iron"].tau1[0]


# ---- electrical ---------------------------------------------------------------------------------


def test_linear_limit_inductance_is_n2_total_permeance():
    """Linear steel and fluid: L = N²·P_total, P_total from the elements' reluctances
    (ln(r1/r0)/(2πμL) radially, l/(μA) axially [roters1941]): shell in series with
    (stack ∥ leakage)."""
    mur_s, mur_f = 800.0, 5.0
    mats = linear_materials(mur_s, mur_f)
    p = path_from_section(build_section(PAPER), mats)
    ms, mf = mur_s * MU0, mur_f * MU0

    def radial(r0, r1, length, mu, mask=None):
        safe = np.where(length > 0, length, 1.0)
        r = np.log(r1 / r0) / (2 * np.pi * mu * safe)
        return np.sum(np.where(length > 0 if mask is None else mask, r, 0.0), axis=-1)

    r_st = (radial(p.gap_r0, p.gap_r1, p.gap_len, mf, p.gap_mask)
            + radial(p.drum_r0, p.drum_r1, p.drum_len, ms, p.drum_mask)
            + p.core_len / (ms * p.core_area))  # fmt: skip
    r_sh = radial(p.pole_r0, p.pole_r1, p.pole_len, ms) + p.back_len / (ms * p.back_area)
    r_tot = r_sh + r_st / (1 + p.leak_permeance * r_st)
    expected = p.turns**2 / r_tot
    lam, L = flux_linkage(p, [[1e-3, 2.0]], mats)
    np.testing.assert_allclose(L[0], expected[0], rtol=1e-9)
    np.testing.assert_allclose(lam[0] / np.array([1e-3, 2.0]), expected[0], rtol=1e-9)


def test_incremental_inductance_is_dlambda_di():
    p = path_from_section(build_section(PAPER))
    i = np.array([0.5, 2.0, 5.0, 7.0])
    h = 1e-4
    lp, _ = flux_linkage(p, (i + h)[None], None)
    lm, _ = flux_linkage(p, (i - h)[None], None)
    _, L = flux_linkage(p, i[None])
    np.testing.assert_allclose(L[0], (lp - lm)[0] / (2 * h), rtol=2e-3)
    assert np.all(np.diff(L[0]) < 0)  # saturation: L falls with the current


def test_more_turns_more_inductance_slower_rise():
    base = _response(replace(PAPER, coil_turns=100), current=2.0)
    more = _response(current=2.0)  # 140 turns
    assert more.inductance_zero[0] > base.inductance_zero[0]
    assert more.tau_electrical[0] > base.tau_electrical[0]


def test_rise_closed_forms():
    """Infinite voltage: the first-order loop, 10–90 % = τ_a ln 9. Instant loop, linear
    coil: i(t) = (V/R)(1 − e^{−tR/L}), so t(i) = −(L/R) ln(1 − R i/V)."""
    mats = linear_materials(1e6, 1.0)  # linear, far from saturation
    p = path_from_section(build_section(PAPER), mats)
    _, L = flux_linkage(p, [[1.0]], mats)
    big = current_rise(p, 2.0, 1.0, Amplifier(supply_voltage=1e4, current_bandwidth_hz=500), mats)
    assert big.rise_time[0] == pytest.approx(np.log(9) / (2 * np.pi * 500), rel=1e-9)
    R, V, i_end = 2.0, 3.0, 1.0
    fast = current_rise(p, R, i_end, Amplifier(supply_voltage=V, current_bandwidth_hz=1e7), mats,
                        nodes=16)  # fmt: skip
    t = lambda i: -(L[0, 0] / R) * np.log(1 - R * i / V)  # noqa: E731
    assert fast.t10[0] == pytest.approx(t(0.1), rel=1e-6)
    assert fast.t90[0] == pytest.approx(t(0.9), rel=1e-4)


def test_higher_voltage_faster_and_too_low_voltage_is_inf():
    low = _response(amplifier=Amplifier(supply_voltage=18.0))
    high = _response(amplifier=Amplifier(supply_voltage=48.0))
    assert high.tau_electrical[0] < low.tau_electrical[0]
    short = _response(amplifier=Amplifier(supply_voltage=12.0))  # R·I = 13.4 V
    assert np.isinf(short.tau_electrical[0])


@pytest.mark.parametrize("c", [PAPER, replace(PAPER, n_drums=1), replace(PAPER, gap=0.3e-3)])
@pytest.mark.parametrize("current", [3.0, 7.0])
def test_rise_fast_model_against_solved_ends(c, current):
    """The sweep's rise (3 + 3 nodes, estimated ends corrected to first order) against
    64 + 64 nodes between solved ends: within 2 %."""
    fast = _response(c, current, nodes=3)
    ref = current_rise(path_from_section(build_section(c)), fast.resistance, current,
                       Amplifier(), nodes=64)  # fmt: skip
    assert fast.rise.t90[0] == pytest.approx(ref.t90[0], rel=0.02)
    assert fast.tau_electrical[0] == pytest.approx(ref.time_constant[0], rel=0.02)


# ---- laminations, options ------------------------------------------------------------


def test_laminated_shell_and_core_shorten_the_eddy_lag():
    solid = _response()
    lam = _response(laminations=Laminations(core=0.5e-3, shell=0.5e-3))
    assert lam.eddy["back_iron"].tau1[0] < solid.eddy["back_iron"].tau1[0]
    assert lam.eddy["core"].tau1[0] < solid.eddy["core"].tau1[0]
    assert lam.tau_eddy[0] < 0.2 * solid.tau_eddy[0]
    assert lam.equivalent_delay[0] < solid.equivalent_delay[0]


@pytest.mark.parametrize(
    ("cls", "kw", "msg"),
    [
        (Amplifier, {"supply_voltage": 0.0}, "supply_voltage = 0"),
        (Amplifier, {"current_bandwidth_hz": -1.0}, "current_bandwidth_hz = -1"),
        (Laminations, {"shell": -1e-3}, "shell = -0.001"),
    ],
)
def test_inputs_validated(cls, kw, msg):
    with pytest.raises(ParameterError, match=msg):
        cls(**kw)


# ---- lags ---------------------------------------------------------------------------------------


def test_single_lag_step_63_percent_and_two_lags_closed_form():
    assert lag_step([[2e-3]], [2e-3])[0, 0] == pytest.approx(1 - np.exp(-1), abs=1e-9)
    t = np.array([1e-4, 1e-3, 5e-3])
    a, b = 1e-3, 3e-4
    exact = 1 - (a * np.exp(-t / a) - b * np.exp(-t / b)) / (a - b)
    np.testing.assert_allclose(lag_step([[a, b]], t)[0], exact, atol=1e-9)
    assert lag_step([[a, b]], [0.0, -1.0])[0].tolist() == [0.0, 0.0]


def test_lag_bandwidth():
    w = lag_bandwidth([[1e-3, 0.0], [1e-3, 1e-3]])
    assert w[0] == pytest.approx(1e3, rel=1e-9)  # single lag: 1/T
    assert w[1] == pytest.approx(np.sqrt(np.sqrt(2) - 1) * 1e3, rel=1e-9)


def test_batch_matches_one_by_one():
    """One physics for one design or a batch: per_topology's rows equal single calls."""
    from geometry.params import broadcast_fields, valid

    p = broadcast_fields({"shell_thickness": [1.2e-3, 1.6e-3], "coil_turns": [120, 140]}, PAPER)
    ok = valid(p)
    out = per_topology(p, ok, lambda rg, rows: {"d": torque_response(rg, 5.0).equivalent_delay})
    for j, (t, n) in enumerate([(1.2e-3, 120), (1.6e-3, 140)]):
        one = _response(replace(PAPER, shell_thickness=t, coil_turns=n), 5.0)
        assert out["d"][j] == pytest.approx(one.equivalent_delay[0], rel=1e-12)
