"""magnetics.ripple: the runout ripple's closed form against the sector model simulated,
and the network's dT/dg against the FEM's (magnetics/fem/gap_shape.py)."""

from __future__ import annotations

import importlib.util
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.fem.gap_shape import fem_gap_derivatives, moved_lines
from magnetics.fem.grid import _lines
from magnetics.ripple import (
    derivatives,
    eccentric_torque,
    gap_derivatives,
    mean_shift,
    ripple_amplitude,
    stencil_torque,
)
from magnetics.torque import torque_curve
from mrclutch.design import design_preset

A, G = 1e-3, 0.7e-3  # a test clutch T(g) = A/g N·m (A in N·m·m)


def torque(g: np.ndarray) -> np.ndarray:
    return A / np.asarray(g)


def test_derivatives_of_a_known_curve() -> None:
    """T = A/g at g = 0.7 mm: T' = −A/g² = −2040.8 N·m/m, T'' = 2A/g³ = 5.8309e6 N·m/m²."""
    h = 7e-6
    t = torque(G + h * np.array([-2, -1, 0, 1, 2]))
    first, second, check = derivatives(t, h)
    assert first == pytest.approx(-2040.816, rel=1e-3)
    assert second == pytest.approx(5.8309e6, rel=1e-3)
    assert check < 1e-3


def test_sector_mean_against_its_closed_form() -> None:
    """⟨A/(g − e cos θ)⟩ = A/(g√(1 − ε²)) [abramowitz-stegun]; ε = 0.1: 1.0050378·A/g;
    second order T + e²T''/4 = (1 + ε²/2)·A/g = 1.005·A/g."""
    e = 0.1 * G
    exact = eccentric_torque(torque, G, e)
    assert exact == pytest.approx(1.0050378 * A / G, rel=1e-7)
    assert A / G + e**2 / 4 * 2 * A / G**3 == pytest.approx(1.005 * A / G, rel=1e-12)


def test_ripple_amplitude_against_the_rotating_rotors() -> None:
    """e_in = 10 µm, e_out = 20 µm turning at different speeds: the sector mean oscillates
    with half peak-to-peak e_in·e_out·T''/2 = 10e-6·20e-6·5.8309e6/2 = 5.831e-4 N·m and
    mean shift (e_in² + e_out²)·T''/4 = 7.289e-4 N·m. Using R for R/2, e² for e_in·e_out
    or dropping the 1/2 fails here."""
    e_in, e_out = 10e-6, 20e-6
    phase = np.linspace(0, 2 * np.pi, 72, endpoint=False)
    e_rel = np.abs(e_in - e_out * np.exp(1j * phase))  # relative eccentricity over a slip turn
    t = np.array([eccentric_torque(torque, G, e) for e in e_rel])
    d2 = 2 * A / G**3
    assert (t.max() - t.min()) / 2 == pytest.approx(5.831e-4, rel=5e-3)
    assert float(ripple_amplitude(d2, e_in, e_out)) == pytest.approx(5.831e-4, rel=1e-3)
    assert t.mean() - A / G == pytest.approx(float(mean_shift(d2, e_in, e_out)), rel=5e-3)
    assert float(mean_shift(d2, e_in, e_out)) == pytest.approx(7.289e-4, rel=1e-3)


def test_paper_gap_curvature_converges() -> None:
    """The network's T'' of the paper clutch at 7 A: the steps h and h/2 agree to 2 %
    (central differences, O(h²)); T decreases with the gap (T' < 0)."""
    d = design_preset("paper")
    a = gap_derivatives(d.clutch, 7.0, d.materials)
    b = gap_derivatives(d.clutch, 7.0, d.materials, step=3.5e-6)
    assert a.first < 0 and a.second > 0
    assert b.second == pytest.approx(a.second, rel=0.02)
    assert a.fd_check < 0.02


@pytest.mark.parametrize("n_drums", [1, 3])
def test_the_stencil_solved_at_once_is_each_design_solved_alone(n_drums: int) -> None:
    """The five designs of the stencil as one network of five rows (issue 40): each row's
    torque is torque_curve's on that design alone, to rounding (the rows' regions are
    evaluated on arrays: at most a few ulp, against T'' × h² ≈ 1e-5 of T), and
    gap_derivatives is the stencil's central differences of them."""
    d = design_preset("paper")
    c = replace(d.clutch, n_drums=n_drums)
    gaps = c.gap + 7e-6 * np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    alone = np.array([torque_curve(build_section(replace(c, gap=float(g)), d.materials),
                                   [5.0]).yield_torque[0] for g in gaps])  # fmt: skip
    together = stencil_torque(c, gaps, 5.0, d.materials)
    assert together.shape == (5,)
    np.testing.assert_allclose(together, alone, rtol=4e-16 * 4, atol=0)
    assert np.all(np.diff(alone) < 0)  # five distinct designs, not one repeated
    gd = gap_derivatives(c, 5.0, d.materials)
    assert gd.torque == together[2]
    assert gd.second == (together[3] - 2 * together[2] + together[1]) / 7e-6**2


def test_a_stencil_point_that_is_no_design_is_named() -> None:
    """A gap whose stencil leaves the valid designs is refused by DrumClutch's own check,
    naming the parameter, before any network is built."""
    c = design_preset("paper").clutch
    with pytest.raises(ParameterError, match=r"gap = 0.0061 m: must be in \[0.0001, 0.005\]"):
        gap_derivatives(c, 5.0, step=2e-3)  # the stencil's top: 2.1 + 2 × 2 mm


# ---- the FEM's check of the network's dT/dg (magnetics/fem/gap_shape.py) ---------------


def _fem_ripple():  # type: ignore[no-untyped-def]
    """benchmarks/measure_fem_ripple.py as a module (its designs, currents, tolerance)."""
    spec = importlib.util.spec_from_file_location("measure_fem_ripple", FEM_RIPPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


FEM_RIPPLE = Path(__file__).resolve().parents[2] / "benchmarks" / "measure_fem_ripple.py"
FEM_SIZE = 0.5e-3  # m: the test's mesh (~2–4 s a design); the benchmark's table is at 0.25 mm


def test_moved_lines_keep_the_cells_and_hit_every_edge() -> None:
    """The nominal grid moved to g + 7 µm: the same number of lines, in order, and every
    region edge of the moved section is one of them (no element straddles two materials);
    a fresh grid there has 4 more r lines at 0.35 mm (why the difference is taken on moved
    grids). A section of another drum count is refused in one line."""
    c = design_preset("paper").clutch
    nominal = build_section(c)
    moved = build_section(replace(c, gap=c.gap + 7e-6))
    rs, zs = moved_lines(nominal, moved, 0.35e-3)
    r0, z0 = _lines(nominal, 0.35e-3, "uniform")
    assert rs.size == r0.size and zs.size == z0.size
    assert np.all(np.diff(rs) > 0) and np.all(np.diff(zs) > 0)
    for g in moved.regions:
        for x, ln in ((g.r0, rs), (g.r1, rs), (g.z0, zs), (g.z1, zs)):
            assert np.min(np.abs(ln - x)) < 1e-12
    assert _lines(moved, 0.35e-3, "uniform")[0].size == r0.size + 4
    with pytest.raises(ParameterError, match="edges do not match"):
        moved_lines(nominal, build_section(replace(c, n_drums=3)), 0.35e-3)


@pytest.mark.slow
def test_fem_derivative_is_smooth_in_the_step() -> None:
    """On moved grids the FEM's dT/dg of the paper preset at 2 A with h = 7 µm and 3.5 µm
    agree to 0.5 % (one discretisation, differentiated: O(h²)); fresh grids at 0.35 mm
    give 10 % apart at 7 A (measured while building this)."""
    c = design_preset("paper").clutch
    a = fem_gap_derivatives(c, [2.0], size=FEM_SIZE, step=7e-6)
    b = fem_gap_derivatives(c, [2.0], size=FEM_SIZE, step=3.5e-6)
    assert a.first[0] < 0
    assert b.first[0] == pytest.approx(a.first[0], rel=5e-3)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper", "one_drum", "five_drums"])
def test_network_dT_dg_against_the_fem(name: str) -> None:
    """The network's log-sensitivity S = (g/T)·dT/dg against the FEM's (moved grids at
    0.5 mm) at 2 A and 7 A, within 2B/0.435: B the network's torque error bound at the
    design (magnetics.network_bound), 0.435 the change of ln g over which that error swings
    through its band (benchmarks/measure_fem_ripple.py DELTA_LN_GAP). Also the sign of
    dT/dg (the 5-drum clutch's saturated core makes it rise with the gap at 7 A) and the
    torques themselves within 2B + 1.5 % (the FEM's own error at 0.5 mm)."""
    bench = _fem_ripple()
    rows = bench.compare(name, FEM_SIZE)
    for current, r in rows.items():
        assert np.sign(r["network_dT_dg_N_m_per_m"]) == np.sign(r["fem_dT_dg_N_m_per_m"]), current
        assert abs(r["S_difference"]) <= r["S_tolerance"], (current, r)
        assert r["network_T_N_m"] == pytest.approx(
            r["fem_T_N_m"], rel=2 * r["network_bound"] + 0.015
        ), current
