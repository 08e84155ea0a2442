"""Yield torque from the gap fields, the torque–current curve, coil properties.

Yield torque of a sheared cylindrical interface of mid-radius r: T = 2π r² ∫ τy(H(z)) dz
(Bingham plastic at yield, [carlson-jolly2000] eq. 1, integrated over the field-carrying
length). The clutch's torque at a current is that plus its off-state drag at the slip
speed: every drag term (films, bearings, seal) is in ``magnetics.drag``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.numerics import illinois
from geometry.params import DrumClutch, broadcast_fields, valid
from geometry.regions import Regions, per_topology
from geometry.section import Section, build_section
from geometry.validation import ParameterError, check_choice, check_finite, check_range
from magnetics.circuit import (
    MagneticPath,
    _kernels,
    _mmf,
    path_from_regions,
    path_from_section,
    solve_flux,
    solve_path,
)
from magnetics.drag import ROOM_TEMPERATURE, Drag, Support, clutch_drag
from magnetics.fem import MESHES, build_grid, solve_fem
from magnetics.fluid import MRFluid
from magnetics.materials import FLUIDS, MATERIALS, Magnetic, magnetic
from magnetics.network import Network, network_from_regions
from magnetics.network.torque import (  # noqa: F401  (the network's torque, importable here)
    CONVENTIONS,
    DEFAULT_CONVENTION,
    network_film_torque,
    network_gap_torque,
    network_torque_and_flux,
    network_torque_batch,
    network_yield_at,
    slope_rating,
)
from magnetics.thermal import Network as ThermalNetwork
from magnetics.thermal import coil_resistance, continuous_current_sq

FloatArray = NDArray[np.float64]
#: "network": the reluctance ladder generated from the section (magnetics.network; the
#: default: within 1.6 % of the FEM on the paper preset and ±10 % on all of the 848
#: measured designs, docs/magnetics.md); "circuit": the single saturating loop (tuned at
#: the paper preset, far off elsewhere); "fem": the axisymmetric FEM reference.
METHODS = ("network", "circuit", "fem")


def rpm_to_rad_s(rpm: float) -> float:
    return rpm * 2 * math.pi / 60.0


def section_fluid(section: Section) -> MRFluid:
    """The fluid of the section's films (its first gap's); ParameterError without rheology
    data."""
    name = section.region(f"gap{section.gaps[0].index}").material
    try:
        return FLUIDS[name]
    except KeyError:
        raise ParameterError(f"fluid = {name!r}: no rheology data") from None


def _fluid(section: Section, fluid: MRFluid | None) -> MRFluid:
    return fluid if fluid is not None else section_fluid(section)


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
    method: str = "network",
    speed_rpm: float = 530.0,
    materials: Mapping[str, Magnetic] | None = None,
    fem_size: float | None = None,
    temperature: float = ROOM_TEMPERATURE,
    support: Support | None = None,
    fem_mesh: str = "uniform",
    convention: str = DEFAULT_CONVENTION,
    network: Network | None = None,
    flux: FloatArray | None = None,
) -> TorqueCurve:
    """Torque of ``clutch`` (or its already built section) at ``currents`` (A) by the
    circuit, the network or the FEM (``METHODS``), the drag at ``speed_rpm`` and fluid
    ``temperature`` (°C) added. ``network``: the section's reluctance network already
    built with ``materials`` (``network_from_regions``; mrclutch.design_network keeps one
    per design), solved in place of building it again; ``flux``: its loop fluxes (1, C, ·)
    at ``currents`` if already solved there (``solve_network``), read instead of solving.
    ``fem_mesh``: the FEM's "uniform" grid (the error map's reference) or its "graded" one
    (as accurate at the same ``fem_size`` on the paper preset with ~3× fewer unknowns,
    magnetics.fem.grid; benchmarks/bench_fem_speed.py). ``convention``: how each gap's
    torque reads the field across its thickness (``CONVENTIONS``), in both solvers."""
    check_choice("method", method, METHODS)
    check_choice("convention", convention, CONVENTIONS)
    check_choice("fem_mesh", fem_mesh, MESHES)
    rpm = check_finite("speed_rpm", speed_rpm, " rpm")
    cur = np.atleast_1d(np.asarray(currents, dtype=float))
    if cur.ndim != 1 or not np.all(np.isfinite(cur)):
        raise ParameterError("currents: must be a 1-D array of finite values (A)")
    section = clutch if isinstance(clutch, Section) else build_section(clutch)
    fluid = _fluid(section, None)
    if method == "circuit":
        path = path_from_section(section, materials)
        res = solve_path(path, cur[None, :], materials)
        per = _gap_torque(path, np.abs(res.flux), res.radial_mmf, materials, fluid,
                          convention)[0]  # fmt: skip
        labels = res.gap_label
    elif method == "network":
        if section.table is None:
            raise ParameterError("section: built by hand, without a region table; no network")
        net = network if network is not None else network_from_regions(section.table, materials)
        if flux is None:
            per = network_gap_torque(net, cur[None, :], materials, fluid, convention)[0]
        else:
            mats = MATERIALS if materials is None else materials
            per = network_film_torque(net, flux, mats, fluid, convention)[0]
        labels = tuple(f"{f}_{z}" for z in ("A", "B") for f in net.film_name)
    else:
        # One grid (its forms' current-independent parts and the Newton preconditioner kept
        # on it); currents in increasing |I|, each Newton started from the last field.
        grid = build_grid(section, fem_size, materials, mesh=fem_mesh)
        per = np.empty((cur.size, len(section.gaps)))
        psi = None
        for k in np.argsort(np.abs(cur), kind="stable"):
            sol = solve_fem(section, float(cur[k]), materials=materials, grid=grid, psi0=psi)
            per[k], psi = sol.gap_yield_torque(fluid, materials, convention), sol.psi
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
    convention: str = DEFAULT_CONVENTION,
) -> FloatArray:
    """Yield torque (N·m, shape S) of the S designs of ``path``, each at its current (flux
    solved to the relative tolerance ``rtol``)."""
    return yield_torque_and_flux(path, current, materials, fluid, rtol, None, convention)[0]


def yield_torque_and_flux(
    path: MagneticPath,
    current: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    rtol: float = 1e-7,
    start: FloatArray | None = None,
    convention: str = DEFAULT_CONVENTION,
) -> tuple[FloatArray, FloatArray]:
    """``yield_torque_at`` and the gap flux (S, 1) it solved for (a warm start for a nearby
    current: ``continuous_torque``'s ``hint``); ``start``: a first flux guess (S, 1)."""
    return _solved_point(path, current, materials, fluid, rtol, start, convention)[:2]


def _solved_point(path, current, materials, fluid, rtol, start=None,  # type: ignore[no-untyped-def]
                  convention=DEFAULT_CONVENTION):  # fmt: skip
    """(yield torque (S,), gap flux (S, 1), dF/dΦ there (S, 1)) at ``current``."""
    mats = MATERIALS if materials is None else materials
    cur = np.broadcast_to(np.asarray(current, dtype=float), path.turns.shape)
    kern = _kernels(path)
    phi = np.abs(solve_flux(path, (path.turns * cur)[:, None], mats, rtol=rtol, kernels=kern,
                            start=start))  # fmt: skip
    m = _mmf(path, mats, phi, kern)
    t = _gap_torque(path, phi, 0.5 * m["radial"], mats, fluid, convention).sum(-1)[:, 0]
    return t, phi, m["dtotal"]


def max_torque_batch(
    fields: Mapping[str, ArrayLike],
    current: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    convention: str = DEFAULT_CONVENTION,
) -> FloatArray:
    """Yield torque (N·m, shape S) of S designs, each at its current (broadcast to S);
    NaN for designs that fail DrumClutch's validation."""
    p = broadcast_fields(fields)
    cur = np.broadcast_to(np.asarray(current, dtype=float), p["n_drums"].shape)

    def one(rg: Regions, rows: np.ndarray) -> dict[str, FloatArray]:
        return {"t": yield_torque_at(path_from_regions(rg, materials), cur[rows], materials,
                                     fluid, convention=convention)}  # fmt: skip

    return per_topology(p, valid(p), one)["t"]


def torque_grid_batch(
    fields: Mapping[str, ArrayLike],
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    n_table: int = 192,
    convention: str = DEFAULT_CONVENTION,
) -> FloatArray:
    """Yield torque (S, C) of S designs at every one of C currents (``torque_table`` per
    drum count); NaN rows for designs that fail DrumClutch's validation."""
    p = broadcast_fields(fields)

    def one(rg: Regions, rows: np.ndarray) -> dict[str, FloatArray]:
        path = path_from_regions(rg, materials)
        return {"t": torque_table(path, currents, materials, fluid, n_table, convention)}

    return per_topology(p, valid(p), one)["t"]


def torque_table(
    path: MagneticPath,
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    n_table: int = 192,
    convention: str = DEFAULT_CONVENTION,
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
    ty = _gap_torque(path, grid, 0.5 * parts["radial"], mats, fluid, convention).sum(-1)
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


def _gap_torque(path, phi, radial, materials, fluid, convention=DEFAULT_CONVENTION):  # type: ignore[no-untyped-def]
    """Yield torque (S, C, K) of every gap entry at gap flux ``phi`` ≥ 0 (S, C): the zone
    (B = Φ/(2π r L) over the steel overlap) plus the half band next to it, where the radial
    potential falls linearly: B(r, u) = F_r·u/(r·S_b) = q1·u/r, u ∈ (0, 1) (circuit
    docstring), so the band's ∫ τy dz at radius r = (b/2)·∫0^1 τy(H(q u)) du = (b/2)·C(q)/q
    with q = q1/r (``_yield_table``).

    ``convention`` "mid-line": r = the gap's mid radius. "weakest-layer": the torque an
    annulus transmits is the same at every r (steady shear), so it yields where r²·τy is
    least ([carlson-jolly2000] eq. 1 per layer): T = 2π·∫ min_r r²·τy(H(r, z)) dz. At each
    z the field is c/r, so f(r) = r²·g(c/r), g(B) = τy(H(B)), has
    d ln f/d ln r = 2 − e(B), e = d ln g/d ln B: f rises with r wherever e < 2, and its
    minimum is at r0, r1 or an interior r = c/B* where e falls through 2 as B falls
    (``_YieldTable.turns``, empty for MRF-132DG: e ≤ 1.93, so there the minimum is the
    inner wall r0, exactly)."""
    mats = MATERIALS if materials is None else materials
    check_choice("convention", convention, CONVENTIONS)
    tab = _yield_table(magnetic(path.fluid, mats), FLUIDS[path.fluid] if fluid is None else fluid)
    length = path.gap_len[:, None, :]
    band = (0.5 * path.band_len)[:, None, None]
    phi = phi[:, :, None]  # one flux through every gap (the loop)
    c = phi / (2 * np.pi * length)  # B·r in the zone, T·m
    q1 = np.abs(radial[:, :, None] / path.band_reluctance[:, None, None])  # band: B·r at u = 1
    if convention == "mid-line":
        r = path.gap_r_mid[:, None, :]
        zone = r**2 * tab.tau(np.abs(c / r))
        bandt = r**2 * tab.mean_tau(q1 / r)
    else:
        r0, r1 = path.gap_r0[:, None, :], path.gap_r1[:, None, :]
        zone = np.minimum(r0**2 * tab.tau(np.abs(c / r0)), r1**2 * tab.tau(np.abs(c / r1)))
        for bs in tab.turns:  # interior minima (none for MRF-132DG)
            r = np.clip(np.abs(c) / bs, r0, r1)
            zone = np.minimum(zone, r**2 * tab.tau(np.abs(c / r)))
        if tab.turns.size == 0:  # f rises with r at every u: the inner wall, exactly
            bandt = np.minimum(r0**2 * tab.mean_tau(q1 / r0), r1**2 * tab.mean_tau(q1 / r1))
        else:  # the minimum moves with u: Gauss–Legendre over u of min_r r²·τy
            x, w = np.polynomial.legendre.leggauss(32)
            bandt = 0.0
            for uk, wk in zip(0.5 * (x + 1), 0.5 * w, strict=True):
                cu = q1 * uk
                m = np.minimum(r0**2 * tab.tau(cu / r0), r1**2 * tab.tau(cu / r1))
                for bs in tab.turns:
                    r = np.clip(cu / bs, r0, r1)
                    m = np.minimum(m, r**2 * tab.tau(cu / r))
                bandt = bandt + wk * m
    tau = zone * length + band * bandt  # ∫ r²·τy dz, Pa·m³
    return np.where(path.gap_mask[:, None, :], 2 * np.pi * tau, 0.0)


@dataclass(frozen=True)
class _YieldTable:
    """τy(H(B)) of one fluid on a uniform B grid, and its running integral
    C(B) = ∫0^B τy(H(b)) db (trapezoid on the grid); past the grid's end H ≥ 2 MA/m, where
    tanh(6.33e-6·H) = 1 to 1e-11, so τy = τy,max there. ``turns``: the B* where
    e = d ln τy/d ln B falls through 2 as B falls (the interior minima of r²·τy(H(c/r))
    in r, ``_gap_torque``)."""

    step: float
    tau_grid: FloatArray
    cum: FloatArray
    tau_max: float
    turns: FloatArray

    def _at(self, table: FloatArray, x: FloatArray) -> FloatArray:
        """Linear interpolation of ``table`` at x ≥ 0 by direct index (uniform grid);
        x past the end gets the last value."""
        t = x * (1.0 / self.step)
        np.minimum(t, table.size - 1.0, out=t)
        i = np.minimum(t.astype(np.intp), table.size - 2)
        lo = table[i]
        return lo + (t - i) * (table[i + 1] - lo)

    def tau(self, b: FloatArray) -> FloatArray:
        """τy(H(|B|)), Pa."""
        return self._at(self.tau_grid, b)

    def mean_tau(self, q: FloatArray) -> FloatArray:
        """(1/q)·∫0^q τy(H(b)) db, Pa: τy averaged over a linear B ramp from 0 to q."""
        past = np.maximum(q - self.step * (self.cum.size - 1), 0.0)
        c = self._at(self.cum, q) + self.tau_max * past
        return np.where(q > 0, c / np.where(q > 0, q, 1.0), 0.0)


@functools.lru_cache(maxsize=16)
def _yield_table(bh: Magnetic, fluid: MRFluid, n: int = 8192) -> _YieldTable:
    """The table of ``bh``'s fluid with ``fluid``'s yield law, built once per pair."""
    b_end = float(bh.b_of_h(2e6))
    grid = np.linspace(0.0, b_end, n)
    tau = fluid.tau_y(bh.h_of_b(grid))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (tau[1:] + tau[:-1]) * np.diff(grid))])
    # e = d ln τy/d ln B between grid nodes; B* where e > 2 above and ≤ 2 below
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.diff(np.log(tau[1:])) / np.diff(np.log(grid[1:]))
    e = np.nan_to_num(e, nan=0.0)
    turns = grid[2:-1][(e[:-1] <= 2.0) & (e[1:] > 2.0)]
    return _YieldTable(float(grid[1]), tau, cum, fluid.tau_y_max, turns)


def continuous_torque(
    net: ThermalNetwork,
    path: MagneticPath,
    slip_speed: Any,
    off_torque: Any,
    wire_limit: float,
    fluid_limit: float,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    passes: int = 3,
    hint: tuple[FloatArray, FloatArray] | None = None,
    convention: str = DEFAULT_CONVENTION,
    torque_at: Any = None,
) -> tuple[Any, Any]:
    """(current A, torque N·m), shape S: the largest torque the clutch holds forever while
    slipping at ``slip_speed``, its coil's Joule heat and its slip heat T·ω both in the
    thermal network, within the wire's and the fluid's limits.

    I_a: the continuous current with the drag's slip heat only (an upper bound). Between
    0 and I_a the yield torque is taken on the chord from the origin through the curve at
    the last answer I_k (one circuit solve), and I_{k+1} = I_cont(ω·(T_off + T_k/I_k·I))
    is found on the closed form of ``continuous_current``; ``passes`` chords. ``hint``:
    (current (S,), flux (S, 1)) of a solve already done (the peak), the first solve's
    warm start. Against the exact fixed point on 40 random designs of the sweep's ranges:
    1 pass (the chord through I_a alone) is off by up to 43 % in current, 2 passes 5.7 %,
    3 passes 0.75 % (torque 0.33 %) (tests/magnetics/test_thermal.py). ``torque_at``: the
    reluctance network's curve (the default torque model, ``network_yield_at``) in place
    of the circuit's chords: the fixed point by a secant on its slope T/I
    (``magnetics.network.torque.slope_rating``); ``path`` then only sizes the batch."""
    mats = MATERIALS if materials is None else materials
    w = np.abs(np.asarray(slip_speed, dtype=float))
    off = np.asarray(off_torque, dtype=float)
    i_max_sq = continuous_current_sq(net, wire_limit, fluid_limit)
    i_a = np.sqrt(np.maximum(i_max_sq(off * w), 0.0))
    i_a = np.broadcast_to(i_a, path.turns.shape).copy()  # (S,), also for one design

    def fixed_point(model: Any, rtol: float, rows: Any = None) -> FloatArray:
        """The root of h(I) = I² − I_cont²(ω·(T_off + T(I))) on [0, I_a], T = ``model``(I)
        (S,) clipped at 0 (so h(I_a) ≥ 0), to ``rtol`` of I_a; of the rows of the mask
        ``rows`` only (None: all; the others 0)."""
        x_all = i_a.copy()

        def h(act: np.ndarray, x: FloatArray) -> FloatArray:
            x_all[act] = x
            return (x_all * x_all - i_max_sq((off + np.maximum(model(x_all), 0.0)) * w))[act]

        hi = i_a if rows is None else np.where(rows, i_a, 0.0)
        every, lo = np.arange(i_a.size), np.zeros_like(i_a)
        h_hi = h(every, hi.copy())  # ≥ 0: I_a bounds the answer
        return illinois(h, lo, hi, h(every, lo), h_hi, rtol)

    if torque_at is not None:  # the network's curve: a secant on its slope T/I
        i, t = slope_rating(torque_at, i_a, fixed_point)
        return i, np.where(i_a > 0, off + t, 0.0)
    # T(0) = 0 and T is concave past the knee: the fixed point on the chord through the
    # curve at I_k lies at or above the true one, and the next chord goes through it; each
    # solve starts from the last flux scaled to the new current (the flux is near linear)
    # Warm starts: Φ(I) is concave (F(Φ) convex), so its tangent at a solved point and the
    # linear circuit's flux both lie above the root: Newton from their minimum converges
    # monotonically ([numerical-recipes] §9.4).
    i_old = phi = dfdphi = None
    kern = _kernels(path)  # the circuit's chords: its warm starts
    turns = path.turns[:, None]
    lin = turns / _mmf(path, mats, np.zeros((turns.shape[0], 1)), kern)["dtotal"]  # Φ/I
    if hint is not None:
        i_old = np.asarray(hint[0], dtype=float)[:, None]
        phi = np.asarray(hint[1], dtype=float)
        dfdphi = _mmf(path, mats, np.abs(phi), kern)["dtotal"]
    i, c1 = i_a, np.zeros_like(i_a)
    for k in range(passes):
        start = None
        if phi is not None:
            tangent = np.abs(phi) + turns * (i[:, None] - i_old) / dfdphi
            start = np.maximum(np.minimum(tangent, lin * i[:, None]), 1e-30)
        t, phi, dfdphi = _solved_point(path, i, mats, fluid, 1e-3, start, convention)
        i_old = i[:, None]
        c1 = np.where(i > 0, t / np.where(i > 0, i, 1.0), 0.0)
        i = fixed_point(lambda x, c1=c1: c1 * x, 1e-9 if k == passes - 1 else 1e-4)
    return i, np.where(i_a > 0, off + c1 * i, 0.0)
