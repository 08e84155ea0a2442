"""Torque ripple from the rotors' runout (issue 41, item 2). SI units.

Each rotor's drum surfaces run out by its total indicated runout R (TIR) about the
common axis: an eccentricity e = R/2 that turns with the rotor (the design's process
table, ``mrclutch.process``). The input rotor turns at ω_in, the output at ω_out, so the relative
eccentricity of the two drum sets is the vector e_rel(t) = e_in·e^{iω_in t} − e_out·e^{iω_out t},
of squared length

    |e_rel|² = e_in² + e_out² − 2·e_in·e_out·cos((ω_in − ω_out)·t).

Sector model: the steel walls are equipotentials, so each angular sector of the films
carries the torque density of a concentric clutch of its local film thickness
g(θ) = g − |e_rel|·cos θ. The torque is the mean over θ of T(g(θ)), T(g) the clutch's
yield torque with every film at thickness g; to second order

    ⟨T(g − e cos θ)⟩ = T(g) + (e²/4)·T''(g)   (⟨cos θ⟩ = 0, ⟨cos² θ⟩ = 1/2)

— the first-order term dT/dg·e·cos θ averages out round the circumference. With |e_rel|²
above, the torque oscillates at the slip frequency f = (ω_in − ω_out)/2π with amplitude
(half peak-to-peak)

    ΔT = e_in·e_out·|T''(g)| / 2      (``ripple_amplitude``)

about a mean shifted by (e_in² + e_out²)·T''/4 (``mean_shift``).

T'' comes from central finite differences of the reluctance network's torque with the
gap changed (``gap_derivatives``): the design rebuilt at g ± h (its drums re-stacked, so
the films' radii move by a few h too, a second-order share stated in docs/hysteresis.md),
checked by Richardson: the difference at h and 2h agrees to O(h²) (``fd_check``). The five
designs of the stencil are one network of five rows, solved at once (``stencil_torque``).

Where it breaks down: every film is moved by the same eccentricity (alternate films open
and close together in the sector model; on a rigid rotor they do: the inner and outer
film of one drum see ∓e, which the second-order term does not distinguish); tilt and
out-of-roundness (a second harmonic in θ, which does not average out at second order the
same way) are not modelled; the sector model ignores the circumferential flux the
eccentric steel carries between sectors.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry.materials import DEFAULT_CHOICE
from geometry.params import MIN_GAP, DrumClutch, broadcast_fields
from geometry.regions import Regions, per_topology
from geometry.validation import ParameterError, check_positive
from magnetics.materials import Magnetic
from magnetics.network import network_from_regions
from magnetics.network.torque import network_gap_torque

#: Finite-difference step on the gap, m (1 % of the paper's 0.7 mm films).
GAP_STEP = 7e-6


def ripple_amplitude(d2_torque: ArrayLike, ecc_in: ArrayLike, ecc_out: ArrayLike) -> Any:
    """ΔT = e_in·e_out·|T''|/2, N·m: the ripple's half peak-to-peak (module docstring),
    from T'' (N·m/m²) and the two rotors' eccentricities (m)."""
    return np.asarray(ecc_in) * np.asarray(ecc_out) * np.abs(d2_torque) / 2  # sector model


def mean_shift(d2_torque: ArrayLike, ecc_in: ArrayLike, ecc_out: ArrayLike) -> Any:
    """(e_in² + e_out²)·T''/4, N·m: the mean torque's change from the runout."""
    return (np.asarray(ecc_in) ** 2 + np.asarray(ecc_out) ** 2) * np.asarray(d2_torque) / 4


def eccentric_torque(torque_of_gap: Any, gap: float, ecc: float, n: int = 64) -> float:
    """⟨T(g − e·cos θ)⟩ over θ by the n-point trapezoid rule (exact for a trigonometric
    polynomial of degree < n): the sector model without the second-order truncation."""
    th = 2 * np.pi * np.arange(n) / n
    return float(np.mean(torque_of_gap(gap - ecc * np.cos(th))))


@dataclass(frozen=True)
class GapDerivatives:
    """dT/dg and d²T/dg² of the yield torque at one current, and the check."""

    current: float  # A
    torque: float  # N·m at the nominal gap
    first: float  # N·m/m
    second: float  # N·m/m²
    fd_check: float  # |T''(h) − T''(2h)| / |T''(h)|: O(h²) agreement of the two steps


def derivatives(t: ArrayLike, h: float) -> tuple[float, float, float]:
    """(T', T'', check) from T at g − 2h, g − h, g, g + h, g + 2h: central differences
    T' = (T₊ − T₋)/2h, T'' = (T₊ − 2T₀ + T₋)/h², the check against the 2h-step T''."""
    tm2, tm1, t0, tp1, tp2 = (float(x) for x in np.asarray(t, dtype=float))
    first = (tp1 - tm1) / (2 * h)  # central difference, O(h²)
    second = (tp1 - 2 * t0 + tm1) / h**2  # central second difference, O(h²)
    second_2h = (tp2 - 2 * t0 + tm2) / (2 * h) ** 2
    check = abs(second - second_2h) / max(abs(second), 1e-300)
    return first, second, check


def gap_derivatives(
    clutch: DrumClutch,
    current: float,
    materials: Any = None,
    step: float = GAP_STEP,
    magnetic_table: Mapping[str, Magnetic] | None = None,
) -> GapDerivatives:
    """dT/dg, d²T/dg² of the network's yield torque at ``current`` A, every film's gap
    moved by ±step, ±2·step (module docstring). ``materials``: the design's
    MaterialChoice (None: the defaults)."""
    check_positive("step", step, " m")
    # within 2·step of the geometry's smallest gap the stencil moves up so that every point
    # is a valid design: the derivatives are then taken at most 2·step above the gap
    centre = max(clutch.gap, MIN_GAP + 2 * step)
    gaps = centre + step * np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    if gaps[0] <= 0:
        raise ParameterError(f"step = {step:g} m: larger than half the gap ({clutch.gap:g} m)")
    for g in gaps:  # every point a valid design (DrumClutch's checks name one that is not)
        replace(clutch, gap=float(g))
    t = [float(x) for x in stencil_torque(clutch, gaps, current, materials, magnetic_table)]
    first, second, check = derivatives(t, step)
    return GapDerivatives(float(current), t[2], first, second, check)


def stencil_torque(
    clutch: DrumClutch,
    gaps: ArrayLike,
    current: float,
    materials: Any = None,
    magnetic_table: Mapping[str, Magnetic] | None = None,
) -> np.ndarray:
    """The network's yield torque (N·m) of ``clutch`` with every film at each of ``gaps``
    (m), all at ``current`` A: the designs as rows of one region table and one network
    (``per_topology``), solved at once — per row the numbers of ``torque_curve`` on each
    design alone."""
    p = broadcast_fields({"gap": np.asarray(gaps, dtype=float)}, clutch)

    def one(rg: Regions, rows: np.ndarray) -> dict[str, np.ndarray]:
        net = network_from_regions(rg, magnetic_table)
        cur = np.full((rows.size, 1), float(current))
        return {"t": network_gap_torque(net, cur, magnetic_table)[:, 0].sum(axis=-1)}

    ok = np.ones(p["gap"].size, dtype=bool)
    return per_topology(p, ok, one, DEFAULT_CHOICE if materials is None else materials)["t"]
