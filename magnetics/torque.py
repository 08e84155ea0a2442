"""Yield torque from the gap fields, the torque–current curve, coil properties.

Yield torque of a sheared cylindrical interface of mid-radius r: T = 2π r² ∫ τy(H(z)) dz
(Bingham plastic at yield, [carlson-jolly2000] eq. 1, integrated over the field-carrying
length). The clutch's torque at a current is that plus its off-state drag at the slip
speed: every drag term (films, bearings, seal) is in ``magnetics.drag``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

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
from magnetics.drag import ROOM_TEMPERATURE, Drag, Support, clutch_drag
from magnetics.fem import build_grid, solve_fem
from magnetics.materials import FLUIDS, MATERIALS, Magnetic, MRFluid, magnetic
from magnetics.thermal import Network, coil_resistance, continuous_current_sq

FloatArray = NDArray[np.float64]
METHODS = ("circuit", "fem")


def rpm_to_rad_s(rpm: float) -> float:
    return rpm * 2 * math.pi / 60.0


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
    r_in, r_out = clutch.coil_inner_radius, clutch.coil_outer_radius
    r = float(coil_resistance(vars(clutch), r_in, r_out, t))  # R = ρ(T) l / A
    length = clutch.coil_turns * math.pi * (r_in + r_out)
    area = math.pi * clutch.wire_diameter**2 / 4
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
    off_state_torque: float  # N·m: every drag term at speed_rpm (magnetics.drag)
    damping: float  # N·m·s: dT/dω of the drag
    drag: Drag


def torque_curve(
    clutch: DrumClutch | Section,
    currents: ArrayLike,
    method: str = "circuit",
    speed_rpm: float = 530.0,
    materials: Mapping[str, Magnetic] | None = None,
    fem_size: float | None = None,
    temperature: float = ROOM_TEMPERATURE,
    support: Support | None = None,
) -> TorqueCurve:
    """Torque of ``clutch`` (or its already built section) at ``currents`` (A) by the
    circuit or the FEM, the drag at ``speed_rpm`` and fluid ``temperature`` (°C) added."""
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
    if section.table is None:
        raise ParameterError("section: built by hand, without a region table; no drag")
    drag = clutch_drag(section.table, rpm_to_rad_s(rpm), temperature, support, fluid)
    return TorqueCurve(method, cur, ty + drag.torque, ty, labels, per, rpm, drag.torque,
                       drag.damping, drag)  # fmt: skip


# ---- arrays of designs: one batch per drum count (geometry.regions.per_topology) ----------


def yield_torque_at(
    path: MagneticPath,
    current: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    rtol: float = 1e-7,
) -> FloatArray:
    """Yield torque (N·m, shape S) of the S designs of ``path``, each at its current (flux
    solved to the relative tolerance ``rtol``)."""
    mats = MATERIALS if materials is None else materials
    cur = np.broadcast_to(np.asarray(current, dtype=float), path.turns.shape)
    kern = _kernels(path)
    phi = np.abs(solve_flux(path, (path.turns * cur)[:, None], mats, rtol=rtol, kernels=kern))
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


def continuous_torque(
    net: Network,
    path: MagneticPath,
    slip_speed: Any,
    off_torque: Any,
    wire_limit: float,
    fluid_limit: float,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
) -> tuple[Any, Any]:
    """(current A, torque N·m), shape S: the largest torque the clutch holds forever while
    slipping at ``slip_speed``, its coil's Joule heat and its slip heat T·ω both in the
    thermal network, within the wire's and the fluid's limits.

    I_a: the continuous current with the drag's slip heat only (an upper bound). One
    circuit solve gives T(I_a); below I_a the torque is taken on the chord from
    (0, T_off) to (I_a, T(I_a)) (within 2 % of the exact fixed point on the preset,
    tests/magnetics/test_thermal.py), and the fixed point I = I_cont(ω·T(I)) is found by
    bisection on the closed form of ``continuous_current``."""
    w = np.abs(np.asarray(slip_speed, dtype=float))
    off = np.asarray(off_torque, dtype=float)
    i_max_sq = continuous_current_sq(net, wire_limit, fluid_limit)
    i_a = np.sqrt(np.maximum(i_max_sq(off * w), 0.0))
    # the chord is good to ~1 %: a 1e-4 flux tolerance is plenty
    t_a = yield_torque_at(path, i_a, materials, fluid, rtol=1e-4) + off
    slope = np.where(i_a > 0, (t_a - off) / np.where(i_a > 0, i_a, 1.0), 0.0)
    lo, hi = np.zeros_like(i_a), i_a
    for _ in range(32):  # the bracket shrinks 2^32-fold
        mid = 0.5 * (lo + hi)
        ok = mid * mid <= i_max_sq((off + slope * mid) * w)
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return lo, np.where(i_a > 0, off + slope * lo, 0.0)
