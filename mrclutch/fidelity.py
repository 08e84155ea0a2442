"""Speed against accuracy, measured: every method of every quantity, what it costs and how
wrong it is against the quantity's reference.

* :func:`registry` — per quantity, plain functions design → value (SI), each with its
  setting; the last of each quantity is its reference.
* :func:`measure` — times each method (median of repeats) and its relative error against
  the quantity's reference: rows (quantity, method, setting, time_s, value, error_rel).

Which method is trusted where, and the accuracy-target choice, are ``mrclutch.trust``.
"""

from __future__ import annotations

import functools
import math
import statistics
import time
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from geometry.mass import analytic_mass, brep_mass, mesh_mass
from geometry.materials import MRF, STEEL
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.dynamics import torque_response
from magnetics.fem.eddy import bias_current, eddy_response
from magnetics.materials import MATERIALS, MU0, linear_materials
from magnetics.torque import torque_curve
from mrclutch.design import ClutchDesign
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.delay import pade_stable_stiffness, step_stable_stiffness
from mrclutch.haptics.model import bandwidth, bandwidth_lumped, max_stable_stiffness
from mrclutch.pipeline import evaluate
from mrclutch.trust import (
    FidelityWarning,
    circuit_trust,
    linear_circuit_trust,
    lumped_trust,
    mesh_trust,
    pade_trust,
    warn,
)

QUANTITIES: tuple[str, ...] = ("inertia", "torque", "stability", "bandwidth", "eddy_delay")
UNITS = {"inertia": "kg·m²", "torque": "N·m", "stability": "N/m", "bandwidth": "Hz",
         "eddy_delay": "s"}  # fmt: skip
MESH_TOLERANCES_MM: tuple[float, ...] = (0.1, 0.03, 0.01, 0.003)
FEM_SIZES_MM: tuple[float, ...] = (1.0, 0.5, 0.35, 0.25)  # the last is the reference
PADE_ORDERS: tuple[int, ...] = (1, 2, 4)
STEPS_PER_DELAY: tuple[int, ...] = (2, 5, 20)
EDDY_FEM_SIZES_MM: tuple[float, ...] = (1.0, 0.5, 0.25)  # the last is the reference


# ---- methods: design → value ------------------------------------------------------------


@dataclass(frozen=True)
class Method:
    """One way of computing one quantity of a design."""

    quantity: str
    name: str
    setting: str
    fn: Callable[[ClutchDesign], float]
    repeats: int = 5
    reference: bool = False


@functools.lru_cache(maxsize=16)
def haptic_params(design: ClutchDesign) -> tuple[HapticParams, float]:
    """The MR pair at the hand (fast clutch figures) and its K_max [N/m]; cached per
    design so the delay and bandwidth methods are timed without the clutch figures."""
    mr = evaluate(design, "fast").mr
    return mr, float(mr.k_max)


def linear_torque(design: ClutchDesign) -> float:
    """Torque at the current limit by the circuit with linear steel and fluid at their
    initial permeabilities; warns past the steel knee."""
    mats = linear_materials(MATERIALS[STEEL].mu_initial / MU0, MATERIALS[MRF].mu_initial / MU0)
    c, i = design.clutch, design.current_limit
    warn(linear_circuit_trust(c, i))
    curve = torque_curve(c, [i], method="circuit", materials=mats,
                         speed_rpm=design.operating.input_speed_rpm)  # fmt: skip
    return float(curve.torque[0])


def circuit_torque(design: ClutchDesign) -> float:
    """Torque at the current limit by the saturating circuit; warns outside its trusted
    region (circuit_trust)."""
    warn(circuit_trust(design.clutch))
    curve = torque_curve(design.clutch, [design.current_limit], method="circuit",
                         speed_rpm=design.operating.input_speed_rpm)  # fmt: skip
    return float(curve.torque[0])


def network_torque(design: ClutchDesign) -> float:
    """Torque at the current limit by the reluctance network (magnetics.network); warns
    outside its trusted region (its own measured error map, circuit_trust)."""
    warn(circuit_trust(design.clutch, "network", design.current_limit))
    curve = torque_curve(design.clutch, [design.current_limit], method="network",
                         speed_rpm=design.operating.input_speed_rpm)  # fmt: skip
    return float(curve.torque[0])


def fem_torque(design: ClutchDesign, size: float) -> float:
    """Torque at the current limit by the axisymmetric FEM at element size [m]."""
    curve = torque_curve(
        design.clutch,
        [design.current_limit],
        method="fem",
        fem_size=size,
        speed_rpm=design.operating.input_speed_rpm,
    )
    return float(curve.torque[0])


def _analytic_inertia(design: ClutchDesign) -> float:
    return analytic_mass(build_section(design.clutch)).rotor_inertia


def _mesh_inertia(design: ClutchDesign, tol: float) -> float:
    warn(mesh_trust(design.clutch, tol))
    return mesh_mass(design.clutch, tolerance=tol, guard=False).rotor_inertia


def _brep_inertia(design: ClutchDesign) -> float:
    return brep_mass(design.clutch).rotor_inertia


def pade_stability(design: ClutchDesign, order: int) -> float:
    """Largest stable K with an order-n Padé delay; warns where its phase is off."""
    p, _ = haptic_params(design)
    k = pade_stable_stiffness(p, order)
    warn(pade_trust(p, k, order))
    return k


def _step_stability(design: ClutchDesign, n: int) -> float:
    return step_stable_stiffness(haptic_params(design)[0], n)


def _exact_stability(design: ClutchDesign) -> float:
    return float(max_stable_stiffness(haptic_params(design)[0]))


def lumped_bandwidth(design: ClutchDesign) -> float:
    """Eq. 1 bandwidth [Hz] at K_max; warns near the transmission mode."""
    p, k = haptic_params(design)
    warn(lumped_trust(p, k))
    return float(bandwidth_lumped(p, k))


def _full_bandwidth(design: ClutchDesign) -> float:
    p, k = haptic_params(design)
    return float(bandwidth(p, k))


def diffusion_eddy_delay(design: ClutchDesign) -> float:
    """τ_eddy [s] of the 1-D diffusion model, as the torque response computes it (at half
    the peak gap flux at the current limit; ``magnetics.dynamics``)."""
    rg = build_section(design.clutch).table
    resp = torque_response(rg, design.current_limit, design.amplifier, design.laminations)
    return float(resp.tau_eddy[0])


def fem_eddy_delay(design: ClutchDesign, size: float) -> float:
    """The eddy lag's low-frequency group delay [s] by the time-harmonic FEM at element
    ``size`` [m] (``magnetics.fem.eddy``), at the same operating point."""
    sec = build_section(design.clutch)
    i_b = bias_current(sec, design.current_limit)
    return eddy_response(sec, i_b, (), size=size, laminations=design.laminations).delay


def registry() -> tuple[Method, ...]:
    """Every method of every quantity, cheapest family first; the reference of each
    quantity last within it (``reference=True``)."""
    ms: list[Method] = [Method("inertia", "analytic", "section integrals", _analytic_inertia)]
    for t in MESH_TOLERANCES_MM:
        ms.append(Method("inertia", "mesh", f"tolerance {t:g} mm",
                         lambda d, t=t: _mesh_inertia(d, t * 1e-3), repeats=3))  # fmt: skip
    ms.append(Method("inertia", "brep", "OpenCascade", _brep_inertia, 1, True))
    ms.append(Method("torque", "linear circuit", "initial μr", linear_torque))
    ms.append(Method("torque", "saturating circuit", "B-H curves", circuit_torque))
    ms.append(Method("torque", "reluctance network", "ladder from the section", network_torque))
    for s in FEM_SIZES_MM:
        ms.append(Method("torque", "fem", f"size {s:g} mm",
                         lambda d, s=s: fem_torque(d, s * 1e-3), 1 if s < 0.5 else 2,
                         s == FEM_SIZES_MM[-1]))  # fmt: skip
    for n in PADE_ORDERS:
        ms.append(Method("stability", "padé", f"order {n}", lambda d, n=n: pade_stability(d, n)))
    for n in STEPS_PER_DELAY:
        ms.append(Method("stability", "time stepping", f"h = τ/{n}",
                         lambda d, n=n: _step_stability(d, n), repeats=3))  # fmt: skip
    ms.append(Method("stability", "exact delay", "D-subdivision", _exact_stability, 3, True))
    ms.append(Method("bandwidth", "lumped", "√(K/(m1+m2))", lumped_bandwidth))
    ms.append(Method("bandwidth", "full response", "k_eff zero", _full_bandwidth, 5, True))
    ms.append(Method("eddy_delay", "diffusion 1-D", "1-D cuts per part", diffusion_eddy_delay))
    for s in EDDY_FEM_SIZES_MM:
        ms.append(Method("eddy_delay", "harmonic fem", f"size {s:g} mm",
                         lambda d, s=s: fem_eddy_delay(d, s * 1e-3), 1 if s < 0.5 else 2,
                         s == EDDY_FEM_SIZES_MM[-1]))  # fmt: skip
    return tuple(ms)


@dataclass(frozen=True)
class Row:
    quantity: str
    method: str
    setting: str
    time_s: float  # median over repeats [s]
    value: float  # SI (UNITS[quantity])
    error_rel: float  # |value / reference − 1|; 0 for the reference
    reference: bool
    warnings: tuple[str, ...] = ()

    def as_json(self) -> dict[str, Any]:
        return {
            "quantity": self.quantity,
            "method": self.method,
            "setting": self.setting,
            "time_s": self.time_s,
            "value": self.value,
            "unit": UNITS[self.quantity],
            "error_rel": self.error_rel,
            "reference": self.reference,
            "warnings": list(self.warnings),
        }


def _time(m: Method, design: ClutchDesign, repeats: int | None) -> tuple[float, float, tuple]:
    n = m.repeats if repeats is None else max(1, min(repeats, m.repeats))
    times, value, caught = [], math.nan, ()
    for k in range(n):
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always", FidelityWarning)
            t0 = time.perf_counter()
            value = m.fn(design)
            times.append(time.perf_counter() - t0)
        if k == 0:
            caught = tuple(str(x.message) for x in w if issubclass(x.category, FidelityWarning))
    return statistics.median(times), float(value), caught


def measure(
    design: ClutchDesign,
    quantities: Iterable[str] = QUANTITIES,
    *,
    repeats: int | None = None,
    methods: Iterable[Method] | None = None,
    progress: Callable[[str], None] | None = None,
    finished: Callable[[int, int], None] | None = None,
) -> tuple[Row, ...]:
    """Time every method (median of its repeats, capped by ``repeats``) and its relative
    error against its quantity's reference. FidelityWarnings are recorded on the rows.
    ``progress(what)`` is told each method as it starts and each one skipped;
    ``finished(n, total)`` the count of methods done (run or skipped) after each."""
    qs = tuple(quantities)
    for q in qs:
        if q not in QUANTITIES:
            raise ParameterError(f"quantity = {q!r}: known: {', '.join(QUANTITIES)}")
    ms = [m for m in (registry() if methods is None else methods) if m.quantity in qs]
    raw = []
    for k, m in enumerate(ms, 1):
        if progress is not None:
            progress(f"{m.quantity}: {m.name} ({m.setting})")
        try:
            raw.append((m, *_time(m, design, repeats)))
        except ParameterError as e:
            if m.reference:  # a quantity without its reference has no errors to show
                raise
            # a setting this design refuses (a mesh finer than 1e-4 of a larger clutch):
            # the method is left out of the table, and the progress says why
            if progress is not None:
                progress(f"{m.quantity}: {m.name} ({m.setting}) skipped: {e}")
        if finished is not None:
            finished(k, len(ms))
    ref = {m.quantity: v for m, _, v, _ in raw if m.reference}
    return tuple(
        Row(m.quantity, m.name, m.setting, t, v, abs(v / ref[m.quantity] - 1.0), m.reference, w)
        for m, t, v, w in raw
    )
