"""magnetics.ripple: the runout ripple's closed form against the sector model simulated."""

from __future__ import annotations

import numpy as np
import pytest

from magnetics.ripple import (
    derivatives,
    eccentric_torque,
    gap_derivatives,
    mean_shift,
    ripple_amplitude,
)
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
