"""From the drums to the hand: a ClutchDesign → clutch figures → Actuator → haptic metrics.

Two fidelities (README "Speed against accuracy"):

* ``fast`` — analytic inertia from the section, torque from the saturating magnetic
  circuit, drag from the closed-form films. Milliseconds; the default for sweeps.
* ``reference`` — inertia from the exact B-rep (build123d/OpenCascade), torque from the
  axisymmetric FEM. Seconds; for the final check of a design.

The MR actuator is the paper's antagonistic pair of clutches on the design's
transmission. The motor it is compared with is the Maxon 136206 on the paper's EM bench
with the same lever, geared (G = F_max,MR / F_max,EM) so both render the same force
— the *equal-force* comparison of the paper's Fig. 7c made exact — at the same virtual
stiffness K = K_max of the MR system.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.mass import analytic_mass, brep_mass, region_mass
from geometry.materials import MRF
from geometry.params import broadcast_fields, valid
from geometry.section import build_section
from geometry.validation import check_choice
from magnetics.circuit import path_from_regions
from magnetics.error_map import error_bound
from magnetics.materials import FLUIDS
from magnetics.torque import (
    coil_properties,
    film_damping_total,
    torque_curve,
    viscous_drag,
    yield_torque_at,
)
from mrclutch.design import ClutchDesign, current_limit
from mrclutch.haptics.actuator import (
    EM_170,
    Actuator,
    HapticParams,
    Transmission,
    actuator,
    reflect,
)
from mrclutch.haptics.model import max_passive_stiffness, metrics_batch, metrics_of
from mrclutch.outputs import SWEEP_COLUMNS
from mrclutch.trust import choose, circuit_trust

FIDELITIES: tuple[str, ...] = ("fast", "reference")
#: Stated relative error of the fast path's rendering bandwidth against the reference
#: fidelity. Bandwidth ∝ √(K_max/(m1+m2)) with K_max ∝ torque, so its error is about
#: half the torque error plus half the reflected-mass error (analytic inertia is exact
#: for the axisymmetric section). Holds where the circuit is within 10 % of the FEM —
#: near the paper preset and its 2-drum variants (docs/magnetics.md); elsewhere the
#: circuit's measured error map bounds the torque error per design (circuit_error_bound in
#: sweep rows; a note on evaluate). Checked on the paper preset, variants and the
#: optimiser's optimum in tests/mrclutch/test_pipeline.py.
FAST_BANDWIDTH_ERROR = 0.05

#: The motor of the paper's equal-force comparison (Fig. 7c).
MOTOR = "maxon-136206"


@dataclass(frozen=True)
class ClutchFigures:
    """What one clutch is (SI), and which method gave each figure."""

    max_current: float  # A: the current limit of the design
    max_torque: float  # N·m: yield + viscous torque at max_current and input speed
    yield_torque: float  # N·m: field-dependent part at max_current
    rotor_inertia: float  # kg·m²: output rotor + shaft
    rotor_mass: float  # kg
    clutch_mass: float  # kg: with fluid and coil
    viscous_damping: float  # N·m·s: dT/dω of the off-state drag
    off_state_torque: float  # N·m at the input speed, 0 A
    coil_resistance: float  # Ω at the coil temperature
    coil_power: float  # W at max_current
    diameter: float  # m, envelope
    length: float  # m, envelope
    methods: Mapping[str, str]
    notes: tuple[str, ...] = ()

    @property
    def torque_per_inertia(self) -> float:
        return self.max_torque / self.rotor_inertia

    def as_json(self) -> dict[str, Any]:
        return {
            "max_current_A": self.max_current,
            "max_torque_N_m": self.max_torque,
            "yield_torque_N_m": self.yield_torque,
            "rotor_inertia_kg_m2": self.rotor_inertia,
            "rotor_mass_kg": self.rotor_mass,
            "clutch_mass_kg": self.clutch_mass,
            "viscous_damping_N_m_s": self.viscous_damping,
            "off_state_torque_N_m": self.off_state_torque,
            "torque_per_inertia_N_m_per_kg_m2": self.torque_per_inertia,
            "coil_resistance_ohm": self.coil_resistance,
            "coil_power_W": self.coil_power,
            "envelope_m": [self.diameter, self.length],
            "methods": dict(self.methods),
            "notes": list(self.notes),
        }


def clutch_figures(
    design: ClutchDesign, fidelity: str = "fast", accuracy: float | None = None
) -> ClutchFigures:
    """Inertia, mass, torque at the current limit and drag of one design.

    With ``accuracy`` (relative, e.g. 0.01) the methods are the cheapest that meet it
    (mrclutch.trust.choose) and ``fidelity`` is ignored; the choice's notes (e.g. which
    quantity needs an FEM) are added to the figures' notes."""
    check_choice("fidelity", fidelity, FIDELITIES)
    c, op = design.clutch, design.operating
    section = build_section(c)
    fem_size = None
    extra: tuple[str, ...] = ()
    if accuracy is not None:
        ch = choose(design, accuracy)
        inertia_method, torque_method, fem_size, extra = (
            ch.inertia,
            ch.torque,
            ch.fem_size,
            ch.notes,
        )
    else:
        inertia_method = "analytic" if fidelity == "fast" else "brep"
        torque_method = "circuit" if fidelity == "fast" else "fem"
        if torque_method == "circuit":  # never a silent wrong number (issue 6)
            extra = circuit_trust(c)
    if inertia_method == "analytic":
        mass = analytic_mass(section)
    else:
        mass = brep_mass(c)
    i_max = design.current_limit
    curve = torque_curve(
        section, [i_max], method=torque_method, speed_rpm=op.input_speed_rpm, fem_size=fem_size
    )
    drag = viscous_drag(section, op.input_speed)
    coil = coil_properties(c, i_max, op.coil_temperature)
    d, length = section.envelope
    return ClutchFigures(
        max_current=i_max,
        max_torque=float(curve.torque[0]),
        yield_torque=float(curve.yield_torque[0]),
        rotor_inertia=mass.rotor_inertia,
        rotor_mass=mass.rotor_mass,
        clutch_mass=mass.clutch_mass,
        viscous_damping=drag.damping,
        off_state_torque=drag.torque,
        coil_resistance=coil.resistance,
        coil_power=coil.power,
        diameter=d,
        length=length,
        methods={
            "inertia": mass.method,
            "torque": torque_method if fem_size is None else f"fem@{fem_size * 1e3:g}mm",
            "drag": "couette",
        },
        notes=tuple(mass.notes) + extra,
    )


def mr_actuator(design: ClutchDesign, figures: ClutchFigures) -> Actuator:
    """The paper's antagonistic pair of this clutch (both rotors move with the lever)."""
    return Actuator.mr_pair(
        clutch_inertia=figures.rotor_inertia,
        clutch_damping=figures.viscous_damping,
        clutch_max_torque=figures.max_torque,
        clutch_mass=figures.clutch_mass,
        delay=design.operating.delay,
        name=design.name,
    )


def mr_at_hand(design: ClutchDesign, inertia: Any, damping: Any, torque: Any, mass: Any
               ) -> HapticParams:  # fmt: skip
    """The antagonistic pair of clutches with these figures (floats or arrays of designs),
    seen at the hand through the design's transmission (Eq. 3–4): what ``evaluate`` and
    ``evaluate_batch`` both feed the haptic model."""
    pair = Actuator.mr_pair(inertia, damping, torque, mass, design.operating.delay, design.name)
    return reflect(pair, design.transmission)


def motor_transmission(mr: HapticParams, mr_tr: Transmission, motor: Actuator) -> Transmission:
    """The paper's EM bench on the MR design's lever and workspace, geared to equal force."""
    em = EM_170.with_lever(mr_tr.lever) if mr_tr.lever != EM_170.lever else EM_170
    em = replace(em, workspace=mr_tr.workspace)
    base_force = motor.max_torque * em.reduction  # F = T nG/l (Eq. 4)
    return replace(em, gearing=float(mr.f_max) / base_force)


@dataclass(frozen=True)
class Evaluation:
    """A design evaluated: the clutch, the MR pair at the hand and the equal-force motor."""

    design: ClutchDesign
    fidelity: str
    clutch: ClutchFigures
    mr: HapticParams
    motor: HapticParams
    motor_gearing: float
    haptic: Mapping[str, Any]  # metrics of the MR pair at K_max
    motor_metrics: Mapping[str, Any]  # metrics of the motor at the same K

    def as_json(self) -> dict[str, Any]:
        mr_m, em_m = dict(self.haptic), dict(self.motor_metrics)
        return {
            "design": self.design.name,
            "fidelity": self.fidelity,
            "clutch": self.clutch.as_json(),
            "haptic": mr_m,
            "motor": {**em_m, "actuator": MOTOR, "gearing": self.motor_gearing},
            "bandwidth_gain": _gain(mr_m["bandwidth_hz"], em_m["bandwidth_hz"]),
            "bandwidth_gain_lumped": _gain(
                mr_m["bandwidth_lumped_hz"], em_m["bandwidth_lumped_hz"]
            ),
        }


def _gain(a: float | None, b: float | None) -> float | None:
    if a is None or b is None or not np.isfinite(a) or not np.isfinite(b):
        return None
    return a / b - 1.0


def evaluate(
    design: ClutchDesign, fidelity: str = "fast", accuracy: float | None = None
) -> Evaluation:
    """The clutch figures and their haptic consequences, beside the equal-force motor.
    ``accuracy`` (relative): pick per quantity the cheapest method that meets it
    (mrclutch.trust.choose); the Evaluation's fidelity then reads "accuracy=…"."""
    fig = clutch_figures(design, fidelity, accuracy)
    if accuracy is not None:
        fidelity = f"accuracy={accuracy:g}"
    mr = mr_at_hand(design, fig.rotor_inertia, fig.viscous_damping, fig.max_torque,
                    fig.clutch_mass)  # fmt: skip
    motor = actuator(MOTOR)
    em_tr = motor_transmission(mr, design.transmission, motor)
    em = reflect(motor, em_tr)
    k = float(mr.k_max)
    mr_m, em_m = metrics_of([mr, em], [k, k])  # the motor at the MR system's K_max
    return Evaluation(design, fidelity, fig, mr, em, em_tr.gearing, mr_m, em_m)


# ---- the vectorised fast path for sweeps -----------------------------------------------


@dataclass(frozen=True)
class BatchEvaluator:
    """Picklable fast-path evaluator of arrays of designs around a base ClutchDesign.

    Fields a sweep does not vary come from ``base.clutch``; operating point and
    transmission are the base design's. Invalid designs (DrumClutch validation fails) get
    ``valid = 0`` and NaN outputs; they are computed on the base geometry meanwhile so no
    invalid number ever reaches the solvers.
    """

    base: ClutchDesign

    def __call__(self, fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        return evaluate_batch(fields, self.base)


def evaluate_batch(
    fields: Mapping[str, ArrayLike], base: ClutchDesign | None = None, *, passivity: bool = False
) -> dict[str, np.ndarray]:
    """The fast path for S designs at once; returns arrays under ``SWEEP_COLUMNS``
    (and ``max_passive_K_N_per_m`` with ``passivity=True``).

    The same physics as ``evaluate(design, "fast")``, on arrays: per drum count, the region
    table gives the analytic mass (``region_mass``), the circuit (``path_from_regions``)
    and the film drag (``film_damping_total``); the pair at the hand is ``mr_at_hand``.
    Designs that fail DrumClutch's validation get ``valid = 0`` and NaN outputs; no invalid
    number reaches a solver."""
    base = base if base is not None else ClutchDesign()
    p = broadcast_fields(fields, base.clutch)
    ok = valid(p)
    op = base.operating
    current = current_limit(op, p["wire_diameter"])
    eta = FLUIDS[MRF].viscosity

    def clutch(rg: regions.Regions, rows: np.ndarray) -> dict[str, Any]:
        out = region_mass(rg)
        out["damping"] = film_damping_total(rg, eta)
        out["yield_torque"] = yield_torque_at(path_from_regions(rg), current[rows])
        return out

    fig = regions.per_topology(p, ok, clutch)
    off_torque = fig["damping"] * op.input_speed
    torque = fig["yield_torque"] + off_torque
    hand = {}
    if ok.any():
        hp = mr_at_hand(base, fig["rotor_inertia"][ok], fig["damping"][ok], torque[ok],
                        fig["clutch_mass"][ok])  # fmt: skip
        hand = dict(metrics_batch(hp, limits=False))
        if passivity:
            hand["max_passive_K_N_per_m"] = max_passive_stiffness(hp)
    out = {
        "valid": ok.astype(float),
        "rotor_inertia_kg_m2": fig["rotor_inertia"],
        "rotor_mass_kg": fig["rotor_mass"],
        "clutch_mass_kg": fig["clutch_mass"],
        "diameter_m": fig["diameter"],
        "length_m": fig["length"],
        "max_torque_N_m": torque,
        "circuit_error_bound": np.where(ok, error_bound(p)[1], np.nan),
        "viscous_damping_N_m_s": fig["damping"],
        "off_state_torque_N_m": off_torque,
    }
    extra = ("max_passive_K_N_per_m",) if passivity else ()
    columns = (*SWEEP_COLUMNS, *extra)
    for key in columns:
        if key not in out:  # a metric at the hand
            col = np.full(ok.shape, np.nan)
            if ok.any():
                col[ok] = np.broadcast_to(np.asarray(hand[key], dtype=float), (int(ok.sum()),))
            out[key] = col
    return {key: out[key] for key in columns}
