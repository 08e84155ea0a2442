"""Yield torque from the gap fields, viscous drag from the gaps' shear, coil properties.

Yield torque of a sheared cylindrical interface of mid-radius r: T = 2π r² ∫ τy(H(z)) dz
(Bingham plastic at yield, [carlson-jolly2000] eq. 1, integrated over the field-carrying
length). Viscous torque of a cylindrical gap of width g and wetted length L at slip speed
ω: 2π η ω r³ L / g (thin-gap Couette flow, [white-viscous]); of a face film of height h
between radii r0, r1: π η ω (r1⁴ − r0⁴) / (2h) (Newtonian disk shear). Both
are linear in ω, so the damping c = dT/dω = T/ω exactly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.materials import MRF
from geometry.params import DrumClutch, broadcast_fields, valid
from geometry.regions import Regions, per_topology
from geometry.section import Section, build_section
from geometry.validation import ParameterError, check_choice, check_finite, check_range
from magnetics.circuit import (
    MagneticPath,
    _kernels,
    _mmf,
    band_h,
    path_from_regions,
    path_from_section,
    solve_flux,
    solve_path,
)
from magnetics.fem import build_grid, solve_fem
from magnetics.materials import FLUIDS, MATERIALS, Magnetic, MRFluid, magnetic

FloatArray = NDArray[np.float64]
RHO_CU_20 = 1.72e-8  # Ω·m at 20 °C [materials] (docs/references.md)
ALPHA_CU = 0.00393  # 1/K, copper resistivity temperature coefficient [materials]
METHODS = ("circuit", "fem")


def rpm_to_rad_s(rpm: float) -> float:
    return rpm * 2 * math.pi / 60.0


@dataclass(frozen=True)
class Drag:
    """Off-state (viscous) drag at one slip speed."""

    slip_speed: float  # rad/s
    torque: float  # N·m, all films
    damping: float  # N·m·s, dT/dω
    gap_torque: tuple[float, ...]  # per cylindrical gap, N·m
    face_torque: tuple[float, ...]  # per face film, N·m


def film_damping(rg: Regions, viscosity: float) -> tuple[list[Any], list[Any]]:
    """dT/dω (N·m·s) of every cylindrical gap and every face film of a region table (floats
    for one design, arrays for many): the viscous drag, written once."""
    gaps = []
    for sp in rg.films("cylinder"):
        r0, r1, z0, z1 = rg.bounds(sp)
        # Couette: T = 2π η ω r³ L / g (thin cylindrical gap at mid-radius)
        gaps.append(2 * np.pi * viscosity * ((r0 + r1) / 2) ** 3 * (z1 - z0) / (r1 - r0))
    faces = []
    for sp in rg.films("face"):
        r0, r1, z0, z1 = rg.bounds(sp)
        # Disk film: T = π η ω (r1⁴ − r0⁴) / (2h)
        faces.append(np.pi * viscosity * (r1**4 - r0**4) / (2 * (z1 - z0)))
    return gaps, faces


def viscous_drag(section: Section, slip_speed: float, fluid: MRFluid | None = None) -> Drag:
    """Viscous torque of every sheared film of ``section`` at ``slip_speed`` (rad/s)."""
    w = check_finite("slip_speed", slip_speed, " rad/s")
    if section.table is None:
        raise ParameterError("section: built by hand, without a region table; no drag")
    c_gap, c_face = film_damping(section.table, _fluid(section, fluid).viscosity)
    damping = float(sum(c_gap) + sum(c_face))
    return Drag(w, damping * w, damping, tuple(float(c * w) for c in c_gap),
                tuple(float(c * w) for c in c_face))  # fmt: skip


def _fluid(section: Section, fluid: MRFluid | None) -> MRFluid:
    if fluid is not None:
        return fluid
    name = section.region(f"gap{section.gaps[0].index}").material
    try:
        return FLUIDS[name]
    except KeyError:
        raise ParameterError(f"fluid = {name!r}: no rheology data") from None


@dataclass(frozen=True)
class Coil:
    """Coil at one current and temperature."""

    current: float  # A
    temperature: float  # °C
    resistance: float  # Ω
    power: float  # W, Joule
    wire_length: float  # m
    current_density: float  # A/m² in the copper
    ampere_turns: float  # A


def coil_properties(clutch: DrumClutch, current: float, temperature: float = 20.0) -> Coil:
    """Resistance, Joule power and current density of the coil."""
    i = check_finite("current", current, " A")
    t = check_range("temperature", temperature, -273.15, 1000.0, " °C")
    rho = RHO_CU_20 * (1 + ALPHA_CU * (t - 20.0))  # linear copper law [materials]
    length = clutch.coil_turns * math.pi * (clutch.coil_inner_radius + clutch.coil_outer_radius)
    area = math.pi * clutch.wire_diameter**2 / 4
    r = rho * length / area  # R = ρ l / A
    return Coil(i, t, r, i * i * r, length, i / area, clutch.coil_turns * i)


@dataclass(frozen=True)
class TorqueCurve:
    """Torque against current at a slip speed (total = yield + viscous)."""

    method: str
    currents: FloatArray  # A
    torque: FloatArray  # N·m, yield + viscous
    yield_torque: FloatArray  # N·m
    gap_labels: tuple[str, ...]
    gap_torque: FloatArray  # (C, K) yield torque per gap (and zone for the circuit)
    speed_rpm: float
    viscous_torque: float  # N·m at speed_rpm
    damping: float  # N·m·s


def torque_curve(
    clutch: DrumClutch | Section,
    currents: ArrayLike,
    method: str = "circuit",
    speed_rpm: float = 530.0,
    materials: Mapping[str, Magnetic] | None = None,
    fem_size: float | None = None,
) -> TorqueCurve:
    """Torque of ``clutch`` (or its already built section) at ``currents`` (A) by the
    circuit or the FEM."""
    check_choice("method", method, METHODS)
    rpm = check_finite("speed_rpm", speed_rpm, " rpm")
    cur = np.atleast_1d(np.asarray(currents, dtype=float))
    if cur.ndim != 1 or not np.all(np.isfinite(cur)):
        raise ParameterError("currents: must be a 1-D array of finite values (A)")
    section = clutch if isinstance(clutch, Section) else build_section(clutch)
    fluid = _fluid(section, None)
    if method == "circuit":
        path = path_from_section(section, materials)
        res = solve_path(path, cur[None, :], materials)
        per = _gap_torque(path, np.abs(res.flux), res.radial_mmf, materials, fluid)[0]
        labels = res.gap_label
    else:
        grid = build_grid(section, fem_size, materials)  # one grid, Newton warm-started
        sols, psi = [], None
        for i in cur:
            sols.append(solve_fem(section, float(i), materials=materials, grid=grid, psi0=psi))
            psi = sols[-1].psi
        per = np.array([s.gap_yield_torque(fluid) for s in sols])
        labels = tuple(f"gap{g.index}" for g in section.gaps)
    ty = per.sum(axis=-1)
    drag = viscous_drag(section, rpm_to_rad_s(rpm), fluid)
    return TorqueCurve(method, cur, ty + drag.torque, ty, labels, per, rpm, drag.torque,
                       drag.damping)  # fmt: skip


# ---- arrays of designs: one batch per drum count (geometry.regions.per_topology) ----------


def yield_torque_at(
    path: MagneticPath,
    current: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
) -> FloatArray:
    """Yield torque (N·m, shape S) of the S designs of ``path``, each at its current."""
    mats = MATERIALS if materials is None else materials
    cur = np.broadcast_to(np.asarray(current, dtype=float), path.turns.shape)
    kern = _kernels(path)
    phi = np.abs(solve_flux(path, (path.turns * cur)[:, None], mats, rtol=1e-7, kernels=kern))
    radial = 0.5 * _mmf(path, mats, phi, kern)["radial"]
    return _gap_torque(path, phi, radial, mats, fluid).sum(-1)[:, 0]


def max_torque_batch(
    fields: Mapping[str, ArrayLike],
    current: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
) -> FloatArray:
    """Yield torque (N·m, shape S) of S designs, each at its current (broadcast to S);
    NaN for designs that fail DrumClutch's validation."""
    p = broadcast_fields(fields)
    cur = np.broadcast_to(np.asarray(current, dtype=float), p["n_drums"].shape)

    def one(rg: Regions, rows: np.ndarray) -> dict[str, FloatArray]:
        return {"t": yield_torque_at(path_from_regions(rg, materials), cur[rows], materials,
                                     fluid)}  # fmt: skip

    return per_topology(p, valid(p), one)["t"]


def torque_grid_batch(
    fields: Mapping[str, ArrayLike],
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    n_table: int = 192,
) -> FloatArray:
    """Yield torque (S, C) of S designs at every one of C currents (``torque_table`` per
    drum count); NaN rows for designs that fail DrumClutch's validation."""
    p = broadcast_fields(fields)

    def one(rg: Regions, rows: np.ndarray) -> dict[str, FloatArray]:
        path = path_from_regions(rg, materials)
        return {"t": torque_table(path, currents, materials, fluid, n_table)}

    return per_topology(p, valid(p), one)["t"]


def torque_table(
    path: MagneticPath,
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    n_table: int = 192,
) -> FloatArray:
    """Yield torque (S, C) of the designs of ``path`` at every one of C currents.

    Tabulate-and-invert: the loop's MMF F(Φ) is strictly increasing, so it is tabulated
    on ``n_table`` fluxes per design (0 … the flux at the largest |N·I|, bracketed
    exactly) and inverted by monotone linear interpolation (one batched searchsorted).
    Relative error in torque ≲ 1e-3 at 192 points (tests/magnetics/test_circuit.py).
    """
    mats = MATERIALS if materials is None else materials
    cur = np.abs(np.asarray(currents, dtype=float).ravel())
    s = path.turns.size
    ni_max = path.turns * max(float(cur.max(initial=0.0)), 1e-12)
    phi_max = solve_flux(path, ni_max[:, None], mats)[:, 0] * (1 + 1e-9)
    grid = np.linspace(0.0, 1.0, n_table)[None, :] ** 1.5 * phi_max[:, None]  # (S, M)
    parts = _mmf(path, mats, grid)
    table = parts["total"]  # (S, M), increasing in each row
    ty = _gap_torque(path, grid, 0.5 * parts["radial"], mats, fluid).sum(-1)  # (S, M)
    ni = path.turns[:, None] * cur[None, :]  # (S, C)
    span = table[:, -1:] + ni.max(axis=1, keepdims=True) + 1.0
    offs = np.cumsum(np.concatenate([[0.0], span[:-1, 0]]))[:, None]
    j = np.searchsorted((table + offs).ravel(), (ni + offs).ravel()).reshape(s, -1)
    j = np.clip(j - np.arange(s)[:, None] * n_table, 1, n_table - 1)
    f0 = np.take_along_axis(table, j - 1, 1)
    f1 = np.take_along_axis(table, j, 1)
    u = np.clip((ni - f0) / np.maximum(f1 - f0, 1e-300), 0.0, 1.0)
    t0 = np.take_along_axis(ty, j - 1, 1)
    return t0 + u * (np.take_along_axis(ty, j, 1) - t0)


def _gap_torque(path, phi, radial, materials, fluid) -> FloatArray:  # type: ignore[no-untyped-def]
    """Yield torque (S, C, K) of every gap entry at gap flux ``phi`` ≥ 0 (S, C): the zone
    (uniform H over the steel overlap) plus the half band next to it (circuit docstring)."""
    mats = MATERIALS if materials is None else materials
    fl = FLUIDS[path.fluid] if fluid is None else fluid
    rmid = path.gap_r_mid[:, None, :]
    length = path.gap_len[:, None, :]
    b = np.abs(phi[:, :, None] / (2 * np.pi * rmid * length))
    h = magnetic(path.fluid, mats).h_dh(b)[0]
    hb, wb = band_h(path, radial, mats)
    tau = fl.tau_y(h) * length + (fl.tau_y(hb) * wb).sum(-1)  # ∫ τy dz, Pa·m
    return np.where(path.gap_mask[:, None, :], 2 * np.pi * rmid**2 * tau, 0.0)


def film_damping_total(rg: Regions, viscosity: float) -> Any:
    """dT/dω (N·m·s) of all films of the designs of a region table."""
    c_gap, c_face = film_damping(rg, viscosity)
    return sum(c_gap) + sum(c_face)


def viscous_batch(
    fields: Mapping[str, ArrayLike], slip_speed: ArrayLike, fluid: MRFluid | None = None
) -> tuple[FloatArray, FloatArray]:
    """(off-state torque N·m, damping N·m·s), shape S: ``film_damping`` per drum count."""
    p = broadcast_fields(fields)
    eta = (FLUIDS[MRF] if fluid is None else fluid).viscosity
    c = per_topology(p, valid(p), lambda rg, rows: {"c": film_damping_total(rg, eta)})["c"]
    return c * np.asarray(slip_speed, dtype=float), c
