"""The time-harmonic eddy FEM (magnetics/fem/eddy.py): closed forms first, then the clutch
against the 1-D diffusion model of magnetics/eddy_lag.py."""

import itertools

import numpy as np
import pytest

from geometry.params import preset
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.eddy_lag import diffusion_mean_delay, diffusion_time_constant
from magnetics.fem.eddy import (
    WITH_STAINLESS,
    bias_current,
    cylinder_flux_ratio,
    diffusion_eddy,
    eddy_response,
    slab_flux_ratio,
    solid_cylinder,
)
from magnetics.laminations import Laminations
from magnetics.materials import MU0

MU, SIGMA, A = 500 * MU0, 5.8e6, 2.5e-3  # τ₁ = μσa²/j₁² ≈ 3.9 ms
OMEGA = 2 * np.pi * np.array([10.0, 100.0, 300.0, 1000.0])  # a/δ from 0.85 to 8.5


def test_closed_forms_low_frequency_and_skin_limit():
    """Both closed forms are 1 − jωT at low frequency (T the 1-D model's mean delay) and
    fall like the skin depth at high frequency (cylinder: |Φ/Φ₀| → √2·δ/a at −45°)."""
    w = np.array([1e-2])
    tau1 = diffusion_time_constant("cylinder", MU, SIGMA, A)
    t_cyl = float(diffusion_mean_delay("cylinder", tau1))
    t_slab = float(diffusion_mean_delay("slab", diffusion_time_constant("slab", MU, SIGMA, A)))
    assert -np.angle(cylinder_flux_ratio(w, MU, SIGMA, A))[0] / w[0] == pytest.approx(t_cyl, 1e-6)
    assert -np.angle(slab_flux_ratio(w, MU, SIGMA, A))[0] / w[0] == pytest.approx(t_slab, 1e-6)
    big = 2 * np.pi * 1e6
    delta = np.sqrt(2 / (big * MU * SIGMA))
    # thin skin: Φ/Φ₀ → 2/(ka) = √2·δ/a·e^{−jπ/4}: magnitude and −45° phase
    r = cylinder_flux_ratio([big], MU, SIGMA, A)[0]
    assert abs(r) == pytest.approx(np.sqrt(2) * delta / A, rel=0.02)
    assert np.degrees(np.angle(r)) == pytest.approx(-45.0, abs=1.0)


def test_cylinder_fem_matches_bessel_solution():
    """Stated tolerance: 32 elements across the radius → within 1 % of 2J₁(ka)/(ka J₀(ka))
    up to a = 8.5δ, and the delay within 0.5 % of μσa²/8."""
    ratio, delay = solid_cylinder(A, MU, SIGMA, OMEGA, elements=32)
    exact = cylinder_flux_ratio(OMEGA, MU, SIGMA, A)
    assert np.max(np.abs(ratio / exact - 1)) < 0.01
    assert abs(np.angle(exact[1], deg=True)) > 30  # a frequency where the lag is large
    assert delay == pytest.approx(MU * SIGMA * A**2 / 8, rel=5e-3)


def test_cylinder_fem_converges_at_second_order():
    """Bilinear elements: the flux ratio's error falls ~4× per halving of h (≥ 3× asserted
    at each frequency over 16 → 32 → 64 elements; measured 3.2–4.0), the delay's too
    (measured 3.2, 3.3: the 1/r weight near the axis slows the approach to 4)."""
    exact = cylinder_flux_ratio(OMEGA, MU, SIGMA, A)
    tau = MU * SIGMA * A**2 / 8
    errs, derr = [], []
    for n in (16, 32, 64):
        r, t = solid_cylinder(A, MU, SIGMA, OMEGA, elements=n)
        errs.append(np.abs(r / exact - 1))
        derr.append(abs(t / tau - 1))
    for a, b in itertools.pairwise(errs):
        assert np.all(a / b > 3.0)
    assert derr[0] / derr[1] > 3.0 and derr[1] / derr[2] > 3.0


@pytest.fixture(scope="module")
def paper():
    s = build_section(preset("paper"))
    return s, bias_current(s, 7.0)


def test_bias_current_is_half_the_peak_flux(paper):
    from magnetics.circuit import path_from_section, solve_flux

    s, ib = paper
    path = path_from_section(s)
    f = [float(solve_flux(path, [[path.turns[0] * i]])[0, 0]) for i in (ib, 7.0)]
    assert f[0] == pytest.approx(0.5 * f[1], rel=1e-6)
    assert 0 < ib < 3.5  # saturation: half the flux needs less than half the current


def test_clutch_delay_shares_sum_and_agree_with_the_phase(paper):
    """The parts' shares add up to the delay; the delay is the phase slope at low
    frequency (a 0.5 Hz solve); the 1-D model is within 15 % of the FEM on the preset,
    while its drums (shorted turns around the core's flux) are off by orders of
    magnitude; stainless adds a lag."""
    s, ib = paper
    fem = eddy_response(s, ib, [0.5, 50.0], size=1e-3)
    assert sum(fem.parts.values()) == pytest.approx(fem.delay, rel=1e-9)
    slope = -np.angle(fem.ratio[0]) / (2 * np.pi * 0.5)
    assert slope == pytest.approx(fem.delay, rel=2e-3)
    one_d = diffusion_eddy(s, ib, [50.0])
    assert abs(one_d.delay / fem.delay - 1) < 0.15
    assert fem.parts["drums"] > 100 * one_d.parts["drums"]
    # the first-order lag overstates the phase at 50 Hz; the full diffusion response less so
    assert np.angle(one_d.lag[0]) < np.angle(one_d.transfer[0]) < 0
    assert np.angle(one_d.lag[0]) < 1.5 * np.angle(fem.ratio[1])
    both = eddy_response(s, ib, [], size=1e-3, conductivity=WITH_STAINLESS)
    assert both.delay > fem.delay and both.parts["other"] > 0


def test_laminated_shell_cuts_the_shell_delay(paper):
    s, ib = paper
    solid = eddy_response(s, ib, [100.0], size=1e-3)
    lam = eddy_response(s, ib, [100.0], size=1e-3, laminations=Laminations(shell=0.5e-3))
    assert lam.parts["poles"] < 0.2 * solid.parts["poles"]
    assert lam.parts["core"] == pytest.approx(solid.parts["core"], rel=0.05)
    assert abs(np.angle(lam.ratio[0])) < abs(np.angle(solid.ratio[0]))


def test_validation(paper):
    s, ib = paper
    with pytest.raises(ParameterError, match="linearisation"):
        eddy_response(s, ib, linearisation="secant")
    with pytest.raises(ParameterError, match="frequencies"):
        eddy_response(s, ib, [-1.0], size=1e-3)
    with pytest.raises(ParameterError, match="conductivity"):
        eddy_response(s, ib, size=1e-3, conductivity={"steel_1018": -1.0})
    with pytest.raises(ParameterError, match="bias"):
        bias_current(s, 7.0, bias=1.5)


def test_laminated_response_at_zero_frequency_is_the_static_flux(paper):
    """At ω = 0 the laminations carry no eddy current: Φ(0)/Φ(0) = 1 exactly, so their
    matrix must not enter (its x/tanh x − 1 is 0.31·ν at the x → 1 guard, not its limit 0;
    a mutant that added it whenever the shell was laminated survived the suite)."""
    s, ib = paper
    lam = eddy_response(s, ib, [0.0, 100.0], size=1e-3, laminations=Laminations(shell=0.5e-3))
    assert lam.ratio[0] == pytest.approx(1.0, abs=1e-12)
    assert abs(lam.ratio[1]) < 1.0
