"""Speed against accuracy: every method of every quantity, what it costs, how wrong it is,
where it stops being trustworthy, and the cheapest one that meets an accuracy target.

* :func:`registry` — per quantity, plain functions design → value (SI), each with its
  setting; the last of each quantity is its reference.
* :func:`measure` — times each method (median of repeats) and its relative error against
  the quantity's reference: rows (quantity, method, setting, time_s, value, error_rel).
* Trust functions (the failure map, docs/fidelity.md) — pure, return a tuple of messages
  (empty: trusted); :func:`warn` turns them into :class:`FidelityWarning`.
* :func:`choose` — per quantity, the cheapest method whose error bound meets a target.

No heavy import at module level (``mrclutch fidelity --help`` imports this lazily anyway).
"""

from __future__ import annotations

import functools
import math
import statistics
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry.validation import ParameterError
from mrclutch.design import ClutchDesign
from mrclutch.haptics.actuator import HapticParams

QUANTITIES: tuple[str, ...] = ("inertia", "torque", "stability", "bandwidth")
UNITS = {"inertia": "kg·m²", "torque": "N·m", "stability": "N/m", "bandwidth": "Hz"}
MESH_TOLERANCES_MM: tuple[float, ...] = (0.1, 0.03, 0.01, 0.003)
FEM_SIZES_MM: tuple[float, ...] = (1.0, 0.5, 0.35, 0.25)  # the last is the reference
PADE_ORDERS: tuple[int, ...] = (1, 2, 4)
STEPS_PER_DELAY: tuple[int, ...] = (2, 5, 20)


class FidelityWarning(UserWarning):
    """A value was computed by a method outside the region where it is trusted."""


# ---- the failure map: trust functions ---------------------------------------------------

#: The saturating circuit is trusted while its torque error against the FEM, as bounded by
#: the measured error map (mrclutch.circuit_map), stays within this.
CIRCUIT_TORQUE_TRUST = 0.10
#: Largest Padé phase error [rad] at the stability crossing frequency trusted: the K_c
#: error is about |d ln K_c/dφ| Δφ with |d ln K_c/dφ| = O(1) (magnitude and phase of
#: ω Num/(k + jbω) move together near the crossing), so 0.01 rad keeps it near 1 %.
PADE_PHASE_BOUND = 0.01
#: The lumped bandwidth √(K/(m1+m2)) is trusted while it is below this fraction of the
#: transmission resonance (the rigid-lever assumption of Eq. 1): measured on TABLE2_MR with
#: the transmission stiffness swept (tests/mrclutch/test_failure_map.py), the lumped error
#: stays below 5 % up to a ratio of ~0.3.
LUMPED_RATIO = 0.3


def steel_knee(steel: Any = None) -> float:
    """B [T] of the knee of the steel's B–H curve: beyond the peak of the differential
    permeability, the first B where it falls below half the initial μr (the linear circuit
    assumes the initial μr everywhere)."""
    from magnetics.materials import MATERIALS, MU0

    steel = MATERIALS["steel_1018"] if steel is None else steel
    b = np.linspace(1e-3, 3.0, 30001)
    mu = steel.mu_r_differential(b)
    peak = int(np.argmax(mu))
    below = np.nonzero(mu[peak:] < 0.5 * steel.mu_initial / MU0)[0]
    return float(b[peak + below[0]]) if below.size else math.inf


def linear_circuit_trust(clutch: Any, current: float) -> tuple[str, ...]:
    """Messages if the linear circuit is used past the steel knee at ``current`` [A]:
    the saturating circuit's largest steel B is compared with :func:`steel_knee`."""
    from magnetics.circuit import solve

    res = solve(clutch, [current])
    knee = steel_knee()
    worst = max(res.steel_b, key=lambda k: float(np.max(res.steel_b[k])))
    b = float(np.max(res.steel_b[worst]))
    if b > knee:
        return (
            f"linear circuit: steel B = {b:.2f} T in {worst} at {current:g} A is past the "
            f"knee of the B-H curve ({knee:.2f} T); use the saturating circuit or the FEM",
        )
    return ()


def circuit_trust(clutch: Any) -> tuple[str, ...]:
    """Messages if the saturating circuit's torque may be more than CIRCUIT_TORQUE_TRUST off
    the FEM on ``clutch``: the measured error map's bound (mrclutch.circuit_map), or the
    design lies outside the map (error unknown)."""
    from mrclutch.circuit_map import circuit_error

    e = circuit_error(clutch)
    if not math.isfinite(e.bound):
        return e.notes
    if e.bound > CIRCUIT_TORQUE_TRUST:
        return (
            f"saturating circuit: torque {e.estimate:+.1%} off the FEM by the measured error "
            f"map (bound {e.bound:.1%} > {CIRCUIT_TORQUE_TRUST:.0%}) at {clutch.n_drums} "
            f"drums, gap {clutch.gap * 1e3:g} mm, zone {clutch.zone_length * 1e3:g} mm; "
            f"use the FEM",
        )
    return ()


def mesh_trust(clutch: Any, tolerance: float) -> tuple[str, ...]:
    """Messages if an unguarded mesh at ``tolerance`` [m] cannot resolve the thinnest wall
    (chord height above half of it: facets of one wall can cross the other)."""
    from geometry.mass import thinnest_feature

    t = thinnest_feature(clutch)
    if tolerance > t / 2:
        return (
            f"mesh: tolerance {tolerance * 1e3:.3g} mm > half the thinnest feature "
            f"({t * 1e3:.3g} mm); the guarded mesh_mass refines it, an unguarded one is wrong",
        )
    return ()


def pade_trust(p: HapticParams, K: float, order: int) -> tuple[str, ...]:
    """Messages if the order-n Padé delay is off by more than PADE_PHASE_BOUND in phase at
    the crossing frequency of K (high K·τ: the crossing moves up to where Padé fails)."""
    from mrclutch.haptics.delay import pade_phase_error
    from mrclutch.haptics.model import crossing_frequency

    w = crossing_frequency(p, K)
    tau = float(p.delay) + 0.5 * float(p.sample_period)
    err = float(pade_phase_error(tau, order, w))
    if err > PADE_PHASE_BOUND:
        return (
            f"Padé order {order}: phase error {err:.3g} rad at the crossing "
            f"{w / (2 * math.pi):.4g} Hz (ωτ = {w * tau:.3g}, K·τ = {K * tau:.3g} N·s/m) "
            f"> {PADE_PHASE_BOUND}; use the exact delay",
        )
    return ()


def lumped_trust(p: HapticParams, K: float) -> tuple[str, ...]:
    """Messages if √(K/(m1+m2)) approaches the transmission resonance √(k(m1+m2)/(m1 m2))
    (the two-mass spring mode, undamped; paper Eq. 1 assumes a rigid transmission)."""
    ws = math.sqrt(K / (p.m1 + p.m2))  # Eq. 1
    wt = math.sqrt(p.k * (p.m1 + p.m2) / (p.m1 * p.m2))  # two masses on a spring
    if ws > LUMPED_RATIO * wt:
        return (
            f"lumped bandwidth: √(K/(m1+m2)) = {ws / (2 * math.pi):.4g} Hz is "
            f"{ws / wt:.2f} of the transmission mode ({wt / (2 * math.pi):.4g} Hz) > "
            f"{LUMPED_RATIO}; use the full response",
        )
    return ()


def warn(messages: Iterable[str], stacklevel: int = 2) -> tuple[str, ...]:
    """Emit each message as a FidelityWarning; return them (for notes)."""
    msgs = tuple(messages)
    for m in msgs:
        warnings.warn(m, FidelityWarning, stacklevel=stacklevel + 1)
    return msgs


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
    from mrclutch.pipeline import evaluate

    mr = evaluate(design, "fast").mr
    return mr, float(mr.k_max)


def linear_torque(design: ClutchDesign) -> float:
    """Torque at the current limit by the circuit with linear steel and fluid at their
    initial permeabilities; warns past the steel knee."""
    from magnetics.materials import MATERIALS, MU0, linear_materials
    from magnetics.torque import torque_curve

    mats = linear_materials(
        MATERIALS["steel_1018"].mu_initial / MU0, MATERIALS["mrf_132dg"].mu_initial / MU0
    )
    c, i = design.clutch, design.current_limit
    warn(linear_circuit_trust(c, i))
    curve = torque_curve(c, [i], materials=mats, speed_rpm=design.operating.input_speed_rpm)
    return float(curve.torque[0])


def circuit_torque(design: ClutchDesign) -> float:
    """Torque at the current limit by the saturating circuit; warns outside its trusted
    region (circuit_trust)."""
    from magnetics.torque import torque_curve

    warn(circuit_trust(design.clutch))
    curve = torque_curve(
        design.clutch, [design.current_limit], speed_rpm=design.operating.input_speed_rpm
    )
    return float(curve.torque[0])


def fem_torque(design: ClutchDesign, size: float) -> float:
    """Torque at the current limit by the axisymmetric FEM at element size [m]."""
    from magnetics.torque import torque_curve

    curve = torque_curve(
        design.clutch,
        [design.current_limit],
        method="fem",
        fem_size=size,
        speed_rpm=design.operating.input_speed_rpm,
    )
    return float(curve.torque[0])


def _analytic_inertia(design: ClutchDesign) -> float:
    from geometry.mass import analytic_mass
    from geometry.section import build_section

    return analytic_mass(build_section(design.clutch)).rotor_inertia


def _mesh_inertia(design: ClutchDesign, tol: float) -> float:
    from geometry.mass import mesh_mass

    warn(mesh_trust(design.clutch, tol))
    return mesh_mass(design.clutch, tolerance=tol, guard=False).rotor_inertia


def _brep_inertia(design: ClutchDesign) -> float:
    from geometry.mass import brep_mass

    return brep_mass(design.clutch).rotor_inertia


def pade_stability(design: ClutchDesign, order: int) -> float:
    """Largest stable K with an order-n Padé delay; warns where its phase is off."""
    from mrclutch.haptics.delay import pade_stable_stiffness

    p, _ = haptic_params(design)
    k = pade_stable_stiffness(p, order)
    warn(pade_trust(p, k, order))
    return k


def _step_stability(design: ClutchDesign, n: int) -> float:
    from mrclutch.haptics.delay import step_stable_stiffness

    return step_stable_stiffness(haptic_params(design)[0], n)


def _exact_stability(design: ClutchDesign) -> float:
    from mrclutch.haptics.model import max_stable_stiffness

    return float(max_stable_stiffness(haptic_params(design)[0]))


def lumped_bandwidth(design: ClutchDesign) -> float:
    """Eq. 1 bandwidth [Hz] at K_max; warns near the transmission mode."""
    from mrclutch.haptics.model import bandwidth_lumped

    p, k = haptic_params(design)
    warn(lumped_trust(p, k))
    return float(bandwidth_lumped(p, k))


def _full_bandwidth(design: ClutchDesign) -> float:
    from mrclutch.haptics.model import bandwidth

    p, k = haptic_params(design)
    return float(bandwidth(p, k))


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
) -> tuple[Row, ...]:
    """Time every method (median of its repeats, capped by ``repeats``) and its relative
    error against its quantity's reference. FidelityWarnings are recorded on the rows."""
    qs = tuple(quantities)
    for q in qs:
        if q not in QUANTITIES:
            raise ParameterError(f"quantity = {q!r}: known: {', '.join(QUANTITIES)}")
    ms = [m for m in (registry() if methods is None else methods) if m.quantity in qs]
    raw = []
    for m in ms:
        if progress is not None:
            progress(f"{m.quantity}: {m.name} ({m.setting})")
        raw.append((m, *_time(m, design, repeats)))
    ref = {m.quantity: v for m, _, v, _ in raw if m.reference}
    return tuple(
        Row(m.quantity, m.name, m.setting, t, v, abs(v / ref[m.quantity] - 1.0), m.reference, w)
        for m, t, v, w in raw
    )


def stderr_progress(msg: str) -> None:
    print(f"fidelity: {msg}", file=sys.stderr, flush=True)


# ---- automatic fidelity -----------------------------------------------------------------

#: Torque methods, cheapest first: (method, FEM size [m] or None, typical time [s] at the
#: paper preset's current limit on the 2-core development machine, `mrclutch fidelity`).
#: Their error bounds come from the measured map (torque_error_bound).
TORQUE_METHODS: tuple[tuple[str, float | None, float], ...] = (
    ("circuit", None, 0.0024),
    ("fem", 1.0e-3, 0.11),
    ("fem", 0.5e-3, 0.21),
    ("fem", 0.35e-3, 0.41),
    ("fem", 0.25e-3, 0.70),
)


def torque_error_bound(clutch: Any, method: str, size: float | None) -> float:
    """Bound on the relative torque error of a method against the reference FEM: the
    circuit's from the measured error map at this design (mrclutch.circuit_map); a coarse
    FEM's is the largest error measured over the map's slice (FEM_ERROR_BOUND); 0 for the
    reference mesh size itself."""
    from mrclutch import circuit_map_data as m
    from mrclutch.circuit_map import circuit_error

    if method == "circuit":
        return circuit_error(clutch).bound
    if size == m.REFERENCE_FEM_SIZE:
        return 0.0
    return m.FEM_ERROR_BOUND.get(size, math.inf)


def inertia_bound(design: ClutchDesign) -> float:
    """A-priori relative error of the analytic rotor inertia: the hub holes it does not
    see, each a cylinder of inertia m(d²/8 + R²) about the axis (parallel axis, Meriam &
    Kraige App. B), over the analytic inertia. 0 without holes (exact for the section)."""
    c = design.clutch
    if not c.hub_holes:
        return 0.0
    from geometry.section import build_section

    s = build_section(c)
    rho = max(s.densities.values())
    d, R = c.hub_hole_diameter, c.hub_hole_pitch_radius
    m = rho * math.pi * d * d / 4 * c.hub_thickness
    return c.hub_holes * m * (d * d / 8 + R * R) / _analytic_inertia(design)


@dataclass(frozen=True)
class Choice:
    """Methods picked for an accuracy target and the expected errors (bounds)."""

    accuracy: float
    inertia: str  # "analytic" | "brep"
    torque: str  # "circuit" | "fem"
    fem_size: float | None
    errors: Mapping[str, float]
    notes: tuple[str, ...]


def choose(design: ClutchDesign, accuracy: float) -> Choice:
    """Per quantity, the cheapest method whose error bound meets ``accuracy``.

    Inertia: analytic if its a-priori bound (hub holes) meets it, else the B-rep.
    Torque: the first of TORQUE_METHODS whose bound (torque_error_bound: the measured map)
    meets the target. Bandwidth ∝ √(K_max/(m1+m2)) with K_max ∝ torque, by the full
    response (exact for the model, a fraction of a millisecond): its error is
    ≤ ½(torque error + inertia error). The stability and passivity limits are always exact
    (the exact D-subdivision measured cheaper than its Padé and time-stepping stand-ins).
    """
    if not (isinstance(accuracy, (int, float)) and 0 < accuracy < 1):
        raise ParameterError(f"accuracy = {accuracy!r}: need 0 < accuracy < 1 (relative)")
    from mrclutch.circuit_map import circuit_error

    notes: list[str] = []
    ei = inertia_bound(design)
    inertia = "analytic" if ei <= accuracy else "brep"
    if inertia == "brep":
        ei = 0.0
        notes.append("inertia: the analytic method misses the hub holes; B-rep used")
    t_target = min(accuracy, 2 * accuracy - ei)
    circ = circuit_error(design.clutch)
    bounds = [
        (n, s, circ.bound if n == "circuit" else torque_error_bound(design.clutch, n, s), t)
        for n, s, t in TORQUE_METHODS
    ]
    name, size, et, t = next(b for b in bounds if b[2] <= t_target)  # the reference: 0
    if name == "fem":
        est = "unknown" if not math.isfinite(circ.estimate) else f"{circ.estimate:+.1%}"
        notes.append(
            f"torque within {accuracy:.3g} needs the FEM at {size * 1e3:g} mm (~{t:.2g} s): "
            f"the saturating circuit's error on this design is {est} by the measured map "
            f"(bound {circ.bound:.1%}), so this target cannot be had at circuit speed "
            f"({bounds[0][3] * 1e3:.0f} ms)"
        )
    return Choice(
        accuracy,
        inertia,
        name,
        size,
        {"inertia": ei, "torque": et, "bandwidth": 0.5 * (et + ei)},
        tuple(notes) + circ.notes,
    )
