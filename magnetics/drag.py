"""Off-state drag of a drum clutch as named terms, and the fluid the output carries along.

The clutch's torque against slip speed ω with no field is a sum of terms, each from its
own source, each evaluated on the region table (one design as floats, or S designs as
arrays — one code path):

============  ==========================================================  ================
term          model                                                       source
============  ==========================================================  ================
drum gaps     Couette film per cylindrical gap, T = 2π η ω r³ L / h        [white-viscous]
end faces     disc film per face film, T = π η ω (r1⁴ − r0⁴) / (2h)        [white-viscous]
bearings      rolling M_rr = G_rr (ν n)^0.6 + sliding M_sl = μ_sl G_sl      [skf-friction]
seal          a Coulomb torque stated by the design (its maker's value)    design input
============  ==========================================================  ================

η = η(T) at the fluid temperature (``MRFluid.viscosity_at``). The *damping* of a term is
its slope dT/dω at the operating slip: η·(geometry) for the films (linear in ω),
0.6·M_rr/ω for the bearings' rolling moment (∝ n^0.6), and 0 for Coulomb terms (the
bearings' sliding moment, the seal): a constant torque at a constant slip speed is a bias
that the antagonistic pair cancels, not damping.

Checks reported beside the numbers (``Drag.notes``):

* laminar Couette flow while every cylindrical film's Taylor number
  Ta = (ω r h / ν)² h / r is below 1708, the onset of Taylor vortices for a narrow gap
  [taylor1923]; above it the Couette torque underestimates the drag;
* Newtonian off-state flow while the films shear faster than a few hundred 1/s, where the
  fluid's apparent viscosity has levelled off [lord-faq]; slower, the datasheet η (the
  800–1200 1/s slope) underestimates the drag.

**Co-rotating fluid.** In a film between an output wall and an input wall the velocity is
linear across the film (quasi-steady Couette), so the fluid adds ∫ρ r² s² dV to the
output's inertia, s the fraction of the way from the input wall to the output wall
[white-viscous]: 1/3 of a disc film's own inertia, and the exact integral for a
cylindrical film. The rest of the cavity's fluid also lies between output and input
surfaces and is given the same 1/3 (an assumption: its flow is not a plain Couette
profile). Quasi-steady holds while the film is thinner than the viscous penetration depth
√(2ν/ω) at the motion's frequency (Stokes' second problem [white-viscous]): below
``quasi_steady_hz``, reported with the drag.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.materials import DENSITY, MRF
from geometry.regions import Regions
from geometry.validation import ParameterError, check_choice, check_nonnegative, check_range
from magnetics.fluid import MRFluid
from magnetics.materials import FLUIDS

#: °C: the default fluid temperature, a room — not the datasheet's 40 °C.
ROOM_TEMPERATURE = 20.0
#: Narrow-gap critical Taylor number (inner cylinder rotating) [taylor1923].
TAYLOR_CRITICAL = 1708.0
#: 1/s: below this film shear rate the off-state fluid shear-thins noticeably [lord-faq].
NEWTONIAN_SHEAR_RATE = 300.0

# SKF deep groove ball bearings, series 618: geometry constants of the rolling and sliding
# frictional moments R1, S1 [skf-friction] and the catalogue's bores d → outside
# diameters D (mm) of the small sizes.
_618 = ((3, 6), (4, 7), (5, 8), (6, 10), (7, 11), (8, 12), (9, 14), (10, 19), (12, 21),
        (15, 24), (17, 26), (20, 32), (25, 37), (30, 42))  # fmt: skip
_SERIES: Mapping[str, tuple[float, float, tuple[tuple[float, float], ...]]] = MappingProxyType(
    {
        "618": (4.7e-7, 6.50e-3, _618),
    }
)
BEARINGS: tuple[str, ...] = ("none", *_SERIES)
MU_SLIDING = 0.05  # SKF: sliding friction coefficient, full-film grease lubrication [skf-friction]


@dataclass(frozen=True)
class Support:
    """The bearings and the seal between the output rotor and the input housing (both see
    the slip speed), SI. Defaults: two SKF 618-series bearings on the shaft (bore = shaft
    diameter, the nearest catalogue bore at or above it), 10 N radial load each (the
    cable's pretension shared by the pair: the paper gives none, so this is a stated
    guess), grease base oil 110 mm²/s (SKF LGMT 2 at 40 °C), no contact seal."""

    bearing: str = "618"  # SKF series, or "none"
    bearings: int = 2  # how many
    bearing_load: float = 10.0  # N, radial, per bearing
    grease_viscosity: float = 110e-6  # m²/s, base oil at the operating temperature
    seal_torque: float = 0.0  # N·m, Coulomb torque of a contact seal at the slip speed

    def __post_init__(self) -> None:
        check_choice("bearing", self.bearing, BEARINGS)
        check_range("bearings", self.bearings, 0, 16)
        if int(self.bearings) != self.bearings:
            raise ParameterError(f"bearings = {self.bearings!r}: must be a whole number")
        check_range("bearing_load", self.bearing_load, 0.0, 1e4, " N")
        check_range("grease_viscosity", self.grease_viscosity, 1e-7, 1e-2, " m²/s")
        check_nonnegative("seal_torque", self.seal_torque, " N·m")


@dataclass(frozen=True)
class Term:
    """One drag source at the operating slip: torque [N·m] and slope dT/dω [N·m·s]
    (floats for one design, arrays for S designs)."""

    torque: Any
    damping: Any
    source: str


def fluid_of(fluid: MRFluid | None, rg: Regions | None = None) -> MRFluid:
    """``fluid``, or else the fluid ``rg``'s materials choose (MRF-132DG without ``rg``)."""
    if fluid is not None:
        return fluid
    return FLUIDS[MRF if rg is None else rg.materials.fluid]


def _density(fl: MRFluid) -> float:
    """kg/m³ of a fluid (the registry's)."""
    return DENSITY[fl.name]


def film_coefficients(rg: Regions, viscosity: Any) -> tuple[list[Any], list[Any]]:
    """dT/dω (N·m·s) of every cylindrical gap and every face film of a region table at
    viscosity η (Pa·s): the viscous drag, written once."""
    gaps = []
    for sp in rg.films("cylinder"):
        r0, r1, z0, z1 = rg.bounds(sp)
        # Couette: T = 2π η ω r³ L / h (thin cylindrical gap at mid-radius) [white-viscous]
        gaps.append(2 * np.pi * viscosity * ((r0 + r1) / 2) ** 3 * (z1 - z0) / (r1 - r0))
    faces = []
    for sp in rg.films("face"):
        r0, r1, z0, z1 = rg.bounds(sp)
        # Disc film: T = π η ω (r1⁴ − r0⁴) / (2h) [white-viscous]
        faces.append(np.pi * viscosity * (r1**4 - r0**4) / (2 * (z1 - z0)))
    return gaps, faces


def bearing_moment(support: Support, shaft_radius: Any, slip_speed: Any) -> tuple[Any, Any]:
    """(rolling, sliding) frictional moments [N·m] of all the support's bearings at the
    slip speed (SKF model with φ_ish = φ_rs = 1, light load, low speed) [skf-friction]."""
    if support.bearing == "none" or support.bearings == 0:
        zero = 0.0 * np.asarray(shaft_radius, dtype=float)
        return zero, zero
    r1, s1, sizes = _SERIES[support.bearing]
    bores = np.array([d for d, _ in sizes])
    outs = np.array([o for _, o in sizes])
    d = 2e3 * np.asarray(shaft_radius, dtype=float)  # mm
    j = np.minimum(np.searchsorted(bores, d - 1e-9), bores.size - 1)
    dm = (np.maximum(bores[j], d) + np.maximum(outs[j], d + 3.0)) / 2  # mm, pitch diameter
    fr = support.bearing_load
    n = np.abs(np.asarray(slip_speed, dtype=float)) * 60 / (2 * math.pi)  # r/min
    nu = support.grease_viscosity * 1e6  # mm²/s
    g_rr = r1 * dm**1.96 * fr**0.54  # SKF G_rr, deep groove, F_a = 0 [skf-friction]
    m_rr = g_rr * (nu * n) ** 0.6  # N·mm [skf-friction]
    g_sl = s1 * dm**-0.26 * fr ** (5 / 3)  # SKF G_sl, deep groove, F_a = 0 [skf-friction]
    m_sl = MU_SLIDING * g_sl  # N·mm
    k = support.bearings * 1e-3
    return _like(k * m_rr, shaft_radius), _like(k * m_sl, shaft_radius)


def _like(x: Any, ref: Any) -> Any:
    return float(x) if np.ndim(ref) == 0 else np.asarray(x, dtype=float)


def drag_terms(
    rg: Regions,
    slip_speed: Any,
    temperature: Any = ROOM_TEMPERATURE,
    support: Support | None = None,
    fluid: MRFluid | None = None,
) -> dict[str, Term]:
    """Every off-state drag term of the designs of ``rg`` at ``slip_speed`` (rad/s) and
    fluid ``temperature`` (°C) (module docstring)."""
    sup = Support() if support is None else support
    w = np.asarray(slip_speed, dtype=float)
    eta = fluid_of(fluid, rg).viscosity_at(temperature)
    c_gap, c_face = film_coefficients(rg, eta)
    c_g, c_f = sum(c_gap), sum(c_face)
    m_rr, m_sl = bearing_moment(sup, rg.fields["shaft_radius"], w)
    w_safe = np.where(w > 0, w, np.inf)
    # d(M_rr)/dω = 0.6 M_rr/ω (M_rr ∝ n^0.6) [skf-friction]; M_sl and the seal: Coulomb
    bearing_slope = _like(0.6 * m_rr / w_safe, c_g)
    seal = _like(sup.seal_torque + 0.0 * c_g, c_g)
    return {
        "drum gaps": Term(c_g * w, c_g, "Couette films, η(T) [white-viscous]"),
        "end faces": Term(c_f * w, c_f, "disc films, η(T) [white-viscous]"),
        "bearings": Term(m_rr + m_sl, bearing_slope,
                         f"SKF model, {sup.bearings}× {sup.bearing} [skf-friction]"),
        "seal": Term(seal, 0.0 * seal, "Coulomb torque, design input"),
    }  # fmt: skip


def totals(terms: Mapping[str, Term]) -> tuple[Any, Any]:
    """(off-state torque N·m, damping N·m·s): the sums over the terms."""
    return sum(t.torque for t in terms.values()), sum(t.damping for t in terms.values())


def taylor_ratio(rg: Regions, slip_speed: Any, temperature: Any, fluid: MRFluid | None = None
                 ) -> Any:  # fmt: skip
    """Largest Ta / 1708 over the cylindrical films: < 1 laminar Couette [taylor1923]."""
    fl = fluid_of(fluid, rg)
    nu = fl.viscosity_at(temperature) / _density(fl)
    worst = 0.0
    for sp in rg.films("cylinder"):
        r0, r1, _, _ = rg.bounds(sp)
        h = r1 - r0
        ta = (np.asarray(slip_speed) * r0 * h / nu) ** 2 * h / r0  # narrow-gap Taylor number
        worst = np.maximum(worst, ta)
    return worst / TAYLOR_CRITICAL


def min_shear_rate(rg: Regions, slip_speed: Any) -> Any:
    """Slowest film shear rate ω r / h (1/s) over the cylindrical films (the face films'
    inner edges shear slower, but carry little of the torque)."""
    lowest = np.inf
    for sp in rg.films("cylinder"):
        r0, r1, _, _ = rg.bounds(sp)
        lowest = np.minimum(lowest, np.abs(slip_speed) * r0 / (r1 - r0))
    return lowest


# 3-point Gauss–Legendre on [0, 1]: exact for the degree-5 integrand r³ s(r)²
_GL_X = (0.5 - math.sqrt(15) / 10, 0.5, 0.5 + math.sqrt(15) / 10)
_GL_W = (5 / 18, 8 / 18, 5 / 18)


def coupled_fluid_inertia(rg: Regions) -> Any:
    """Inertia [kg·m²] the fluid adds to the output rotor (module docstring): for a
    cylindrical film 2πρL ∫ r³ s² dr with s linear from the input wall (0) to the output
    wall (1); 1/3 of every other fluid region's own inertia ρπ(r1⁴ − r0⁴)Δz/2."""
    rho = DENSITY[rg.materials.fluid]
    total: Any = 0.0
    for sp in rg:
        if sp.part != "fluid":
            continue
        r0, r1, z0, z1 = rg.bounds(sp)
        if sp.film == "cylinder":
            out_inner = sp.walls[0].startswith("out")
            acc: Any = 0.0
            for x, wgt in zip(_GL_X, _GL_W, strict=True):
                r = r0 + x * (r1 - r0)
                s = 1 - x if out_inner else x
                acc = acc + wgt * r**3 * s**2
            total = total + 2 * np.pi * rho * (z1 - z0) * (r1 - r0) * acc
        else:
            total = total + rho * np.pi * (r1**4 - r0**4) * (z1 - z0) / 2 / 3
    return total


def quasi_steady_hz(rg: Regions, temperature: Any, fluid: MRFluid | None = None) -> Any:
    """Frequency [Hz] below which every cylindrical film is thinner than the viscous
    penetration depth √(2ν/ω) (Stokes' second problem [white-viscous]): f = ν/(π h²) of the
    widest film. Below it the carried fluid's linear profile (``coupled_fluid_inertia``)
    holds; above it less fluid follows the output."""
    fl = fluid_of(fluid, rg)
    nu = fl.viscosity_at(temperature) / _density(fl)
    widest = 0.0
    for sp in rg.films("cylinder"):
        r0, r1, _, _ = rg.bounds(sp)
        widest = np.maximum(widest, r1 - r0)
    return nu / (np.pi * widest**2)


@dataclass(frozen=True)
class Drag:
    """The off-state drag of one design at one slip speed and fluid temperature."""

    slip_speed: float  # rad/s
    temperature: float  # °C, fluid
    viscosity: float  # Pa·s at that temperature
    terms: Mapping[str, Term]
    gap_torque: tuple[float, ...]  # per cylindrical gap, N·m
    face_torque: tuple[float, ...]  # per face film, N·m
    taylor_ratio: float  # largest Ta/1708
    min_shear_rate: float  # 1/s
    quasi_steady_hz: float  # the carried fluid's inertia holds below this frequency
    notes: tuple[str, ...]

    @property
    def torque(self) -> float:
        return float(totals(self.terms)[0])

    @property
    def damping(self) -> float:
        return float(totals(self.terms)[1])

    def as_json(self) -> dict[str, Any]:
        return {
            "slip_speed_rad_s": self.slip_speed,
            "fluid_temperature_C": self.temperature,
            "viscosity_Pa_s": self.viscosity,
            "terms": {k: _term_json(t) for k, t in self.terms.items()},
            "taylor_number_over_critical": self.taylor_ratio,
            "min_film_shear_rate_per_s": self.min_shear_rate,
            "carried_fluid_quasi_steady_below_hz": self.quasi_steady_hz,
            "notes": list(self.notes),
        }


def _term_json(t: Term) -> dict[str, Any]:
    return {"torque_N_m": float(t.torque), "damping_N_m_s": float(t.damping), "source": t.source}


def clutch_drag(
    rg: Regions,
    slip_speed: float,
    temperature: float = ROOM_TEMPERATURE,
    support: Support | None = None,
    fluid: MRFluid | None = None,
) -> Drag:
    """Every drag term of one design (``rg`` evaluated on floats), with its checks."""
    fl = fluid_of(fluid, rg)
    eta = fl.viscosity_at(temperature)
    w = float(slip_speed)
    terms = drag_terms(rg, w, temperature, support, fl)
    c_gap, c_face = film_coefficients(rg, eta)
    ta = float(taylor_ratio(rg, w, temperature, fl))
    gmin = float(min_shear_rate(rg, w))
    notes = []
    if ta >= 1.0:
        notes.append(
            f"Taylor vortices: Ta = {ta:.3g}× critical in the widest film; the Couette "
            "drag is a lower bound"
        )
    if w > 0 and gmin < NEWTONIAN_SHEAR_RATE:
        notes.append(
            f"film shear rate {gmin:.0f} 1/s < {NEWTONIAN_SHEAR_RATE:.0f} 1/s: the fluid "
            "shear-thins there; the datasheet η underestimates the drag"
        )
    return Drag(w, float(temperature), float(eta), MappingProxyType(terms),
                tuple(float(c * w) for c in c_gap), tuple(float(c * w) for c in c_face),
                ta, gmin, float(quasi_steady_hz(rg, temperature, fl)), tuple(notes))  # fmt: skip
