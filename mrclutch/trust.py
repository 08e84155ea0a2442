"""Which method to trust, and how far off it can be: the failure map of every fast method,
and the cheapest method that meets an accuracy target.

* Trust functions (the failure map, docs/fidelity.md) — pure, return a tuple of messages
  (empty: trusted); :func:`warn` turns them into :class:`FidelityWarning`.
* :func:`choose` — per quantity, the cheapest method whose error bound meets a target.

The pipeline asks these before it answers; ``mrclutch.fidelity`` measures the methods
whose bounds are stated here. No heavy import at module level.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from geometry.mass import analytic_mass, thinnest_feature
from geometry.materials import DEFAULT_CHOICE, LABEL, STEEL, MaterialChoice
from geometry.params import DrumClutch
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.circuit import solve
from magnetics.error_map import LABELS, circuit_error, load
from magnetics.materials import MATERIALS, MU0
from magnetics.network_bound import DEFAULT_MATERIALS, material_key, solved_features
from magnetics.network_bound import load as load_bound
from mrclutch.design import ClutchDesign
from mrclutch.design_network import section_network
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.delay import pade_phase_error
from mrclutch.haptics.model import crossing_frequency


class FidelityWarning(UserWarning):
    """A value was computed by a method outside the region where it is trusted."""


# ---- the failure map: trust functions ---------------------------------------------------

#: The saturating circuit is trusted while its torque error against the FEM, as bounded by
#: the measured error map (magnetics.error_map), stays within this.
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
    steel = MATERIALS[STEEL] if steel is None else steel
    b = np.linspace(1e-3, 3.0, 30001)
    mu = steel.mu_r_differential(b)
    peak = int(np.argmax(mu))
    below = np.nonzero(mu[peak:] < 0.5 * steel.mu_initial / MU0)[0]
    return float(b[peak + below[0]]) if below.size else math.inf


def linear_circuit_trust(clutch: Any, current: float) -> tuple[str, ...]:
    """Messages if the linear circuit is used past the steel knee at ``current`` [A]:
    the saturating circuit's largest steel B is compared with :func:`steel_knee`."""
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


def circuit_trust(
    clutch: Any, model: str = "circuit", current: float | None = None,
    materials: MaterialChoice = DEFAULT_CHOICE, flux: np.ndarray | None = None,
) -> tuple[str, ...]:  # fmt: skip
    """Messages if the saturating circuit's torque (``model`` "network": the reluctance
    network's at ``current`` [A]) may be more than CIRCUIT_TORQUE_TRUST off the FEM on
    ``clutch``: the measured error map's bound (magnetics.error_map; the network's covers
    every dimension, magnetics.network_bound), or the design lies outside what was
    measured (error unknown; the network's for a material set never measured, ``materials``:
    ``material_set``). ``flux``: the network's loop fluxes (1, 1, ·) at ``current`` on the
    process's shared network (``section_network``) if already solved (the torque's solve,
    ``mrclutch.clutch``), read instead of solving it again."""
    key = material_set(materials)
    features = None
    if model == "network" and current is not None:
        features = _shared_features(clutch, current, materials, key, flux)
    e = circuit_error(clutch, model, current, key, features)
    if not math.isfinite(e.bound):
        return e.notes
    if e.bound > CIRCUIT_TORQUE_TRUST:
        return (
            f"{LABELS[model]}: torque {e.estimate:+.1%} off the FEM by the measured error "
            f"map (bound {e.bound:.1%} > {CIRCUIT_TORQUE_TRUST:.0%}) at {clutch.n_drums} "
            f"drums, gap {clutch.gap * 1e3:g} mm, zone {clutch.zone_length * 1e3:g} mm; "
            f"use the FEM",
        )
    return ()


def _shared_features(
    clutch: Any, current: float, materials: MaterialChoice, key: str,
    flux: np.ndarray | None = None,
) -> Mapping[str, np.ndarray] | None:  # fmt: skip
    """The network bound's solution features of ``clutch`` at ``current`` [A] solved on the
    process's shared network (``section_network``, which evaluate has built already)
    rather than on one ``network_bound`` would build again (issue 40). None (the bound
    does what it did) unless every material is the default one (the set the bound builds
    its network with) and the design lies inside the bound's ranges (the only designs it
    solves). The same bits: tests/mrclutch/test_trust_materials.py."""
    if key != DEFAULT_MATERIALS or materials != DEFAULT_CHOICE:
        return None
    bound = load_bound(key)
    if bound is None or not bound.features or not isinstance(clutch, DrumClutch):
        return None
    p = {f.name: getattr(clutch, f.name) for f in fields(clutch)}
    ni = np.asarray(float(clutch.coil_turns) * float(current))  # N·I as network_bound forms it
    if not bound.scaled(p, ni)[1].all():
        return None
    _, net = section_network(clutch, materials)
    return solved_features(net, ni.reshape(1), flux)


def material_set(materials: MaterialChoice) -> str:
    """The network bound's key of a design's magnetic materials (magnetics.network_bound):
    "steel+fluid" when one steel makes the core, the drums and the shell; a mixed set
    names its three steels (never measured: its bound is unmeasured)."""
    steels = {materials.core, materials.drums, materials.shell}
    steel = materials.core if len(steels) == 1 else "/".join((materials.core, materials.drums,
                                                              materials.shell))  # fmt: skip
    return material_key(steel, materials.fluid)


def material_trust(materials: MaterialChoice) -> tuple[str, ...]:
    """A note when the magnetic materials differ from the ones every error map and bound
    was measured with (AISI 1018, MRF-132DG): the fast torque's bound is then unmeasured
    for this material set (the torque itself is still given)."""
    if materials.magnetic == DEFAULT_CHOICE.magnetic:
        return ()
    slots = ("fluid", "core", "drums", "shell")
    chosen = ", ".join(f"{k} {LABEL[v]}" for k, v in zip(slots, materials.magnetic, strict=True))
    return (
        f"torque error bound: unmeasured for this material ({chosen}); the maps were "
        "measured on steel 1018 and MRF-132DG (docs/magnetics.md: the network against the "
        "FEM per fluid)",
    )


def mesh_trust(clutch: Any, tolerance: float) -> tuple[str, ...]:
    """Messages if an unguarded mesh at ``tolerance`` [m] cannot resolve the thinnest wall
    (chord height above half of it: facets of one wall can cross the other)."""
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


# ---- automatic fidelity -----------------------------------------------------------------

#: Torque methods, cheapest first: (method, FEM size [m] or None, typical time [s] at the
#: paper preset's current limit on the 2-core development machine, `mrclutch fidelity`).
#: Their error bounds come from the measured map (torque_error_bound).
TORQUE_METHODS: tuple[tuple[str, float | None, float], ...] = (
    ("circuit", None, 0.0024),
    ("network", None, 0.0054),  # the reluctance network, one design (docs/magnetics.md)
    ("fem", 1.0e-3, 0.11),
    ("fem", 0.5e-3, 0.21),
    ("fem", 0.35e-3, 0.41),
    ("fem", 0.25e-3, 0.70),
)


#: The reference FEM's own discretisation error: 0.3781 N·m at 0.25 mm against 0.3814 at
#: 0.0625 mm, the paper preset at 7 A (docs/magnetics.md, "Mesh-converged").
REFERENCE_MESH_ERROR = 1.0 - 0.3781 / 0.3814


def torque_error_bound(
    clutch: Any, method: str, size: float | None, current: float | None = None,
    materials: MaterialChoice = DEFAULT_CHOICE,
) -> float:  # fmt: skip
    """Bound on the relative torque error of a method against the reference FEM: the
    circuit's from its measured error map at this design (magnetics.error_map), the
    network's from its bound over every dimension at ``current`` [A]
    (magnetics.network_bound); a coarse FEM's is the largest error measured over the map's
    slice (FEM_ERROR_BOUND); 0 for the reference mesh size itself."""
    if method == "network":
        return circuit_error(clutch, method, current, material_set(materials)).bound
    if method == "circuit":  # its map was measured on 1018 / MRF-132DG only
        if materials.magnetic != DEFAULT_CHOICE.magnetic:
            return math.inf
        return circuit_error(clutch, method, current).bound
    m = load()
    if size == m.reference_fem_size:
        return 0.0
    return m.fem_error_bound.get(size, math.inf)


def inertia_bound(design: ClutchDesign) -> float:
    """A-priori relative error of the analytic rotor inertia: the hub holes it does not
    see, each a cylinder of inertia m(d²/8 + R²) about the axis (parallel axis, Meriam &
    Kraige App. B), over the analytic inertia. 0 without holes (exact for the section)."""
    c = design.clutch
    if not c.hub_holes:
        return 0.0
    s = build_section(c)
    rho = max(s.densities.values())
    d, R = c.hub_hole_diameter, c.hub_hole_pitch_radius
    m = rho * math.pi * d * d / 4 * c.hub_thickness
    return c.hub_holes * m * (d * d / 8 + R * R) / analytic_mass(s).rotor_inertia


@dataclass(frozen=True)
class Choice:
    """Methods picked for an accuracy target and the expected errors (bounds)."""

    accuracy: float
    inertia: str  # "analytic" | "brep"
    torque: str  # "circuit" | "network" | "fem"
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
    notes: list[str] = []
    ei = inertia_bound(design)
    inertia = "analytic" if ei <= accuracy else "brep"
    if inertia == "brep":
        ei = 0.0
        notes.append("inertia: the analytic method misses the hub holes; B-rep used")
    t_target = min(accuracy, 2 * accuracy - ei)
    i_max = design.current_limit
    measured = design.materials.magnetic == DEFAULT_CHOICE.magnetic
    mset = material_set(design.materials)
    # the circuit's map holds 1018 / MRF-132DG only (torque_error_bound): elsewhere unmeasured
    circ = circuit_error(design.clutch) if measured else None
    unmeasured = material_trust(design.materials)
    bounds = [(n, s, torque_error_bound(design.clutch, n, s, i_max, design.materials), t)
              for n, s, t in TORQUE_METHODS]  # fmt: skip
    name, size, et, t = next(b for b in bounds if b[2] <= t_target)  # the reference: 0

    def said(model: str, err: Any) -> str:
        if err is None or (not math.isfinite(err.bound) and not measured):
            return (f"the {model}'s error was never measured with the materials {mset} "
                    "(its bound is unmeasured, not small)")  # fmt: skip
        est = "unknown" if not math.isfinite(err.estimate) else f"{err.estimate:+.1%}"
        return (f"the {model}'s error on this design is {est} by its measured map "
                f"(bound {err.bound:.1%})")  # fmt: skip

    if name == "network":
        notes.append(
            f"torque within {accuracy:.3g} by the reluctance network (~{t * 1e3:.0f} ms): "
            f"{said('saturating circuit', circ)}; the network's bound is {et:.1%}"
        )
    if name == "fem":
        net = circuit_error(design.clutch, "network", i_max, mset)
        why = (
            f"so this target cannot be had at their speed ({bounds[1][3] * 1e3:.0f} ms)"
            if measured
            else "so no bound says their speed meets it; the FEM's mesh-error bound "
            "was itself measured on steel 1018 and MRF-132DG (unverified for this set)"
        )
        notes.append(
            f"torque within {accuracy:.3g} needs the FEM at {size * 1e3:g} mm (~{t:.2g} s): "
            f"{said('saturating circuit', circ)} and {said('reluctance network', net)}, "
            f"{why}"
        )
    if accuracy < REFERENCE_MESH_ERROR:
        notes.append(
            f"accuracy {accuracy:.3g} is met against the reference fidelity (the FEM at "
            f"{load().reference_fem_size * 1e3:g} mm), not against the true field: the "
            f"reference itself is {REFERENCE_MESH_ERROR:.2%} below its mesh-converged torque "
            "on the paper preset at 7 A, and the material data are less certain still"
        )
    return Choice(
        accuracy,
        inertia,
        name,
        size,
        {"inertia": ei, "torque": et, "bandwidth": 0.5 * (et + ei)},
        tuple(notes) + (circ.notes if circ else ()) + unmeasured,
    )
