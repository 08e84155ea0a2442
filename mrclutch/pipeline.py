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

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.mass import MassReport, analytic_mass, brep_mass, region_mass
from geometry.materials import MRF, MaterialChoice
from geometry.params import preset, valid
from geometry.section import build_section
from geometry.validation import ParameterError, check_choice
from magnetics import thermal
from magnetics.circuit import path_from_regions, path_from_section, solve_flux
from magnetics.drag import Drag, coupled_fluid_inertia, drag_terms, totals
from magnetics.dynamics import supply_current, torque_response
from magnetics.error_map import error_bound
from magnetics.materials import FLUIDS
from magnetics.network import network_from_regions
from magnetics.network_bound import FEATURES, solution_features
from magnetics.torque import (
    coil_properties,
    continuous_torque,
    network_torque_and_flux,
    network_yield_at,
    torque_curve,
)
from mrclutch.batch import batch_fields
from mrclutch.design import ClutchDesign, current_limit
from mrclutch.duty import DUTY_COLUMNS, DUTY_INFS, DUTY_NULLS, duty_batch, evaluation_duty
from mrclutch.feel import FEEL_COLUMNS, feel_batch, feel_figures
from mrclutch.haptics.actuator import (
    EM_170,
    TABLE2_MR,
    Actuator,
    HapticParams,
    Transmission,
    actuator,
    reflect,
)
from mrclutch.haptics.delay import lag_stable_stiffness
from mrclutch.haptics.hand import backdrive_force, hand_figures
from mrclutch.haptics.model import (
    StabilitySearchError,
    max_passive_stiffness,
    max_stable_stiffness,
    metrics_batch,
    metrics_of,
)
from mrclutch.haptics.zwidth import ZWIDTH_KEYS
from mrclutch.haptics.zwidth import zwidth as zwidth_of
from mrclutch.outputs import SWEEP_COLUMNS, SWEEP_OPTIONAL
from mrclutch.trust import choose, circuit_trust, material_set

FIDELITIES: tuple[str, ...] = ("fast", "reference")
#: Stated relative error of the fast path's rendering bandwidth against the reference
#: fidelity. Bandwidth ∝ √(K_max/(m1+m2)) with K_max ∝ torque, so its error is about
#: half the torque error plus half the reflected-mass error (analytic inertia is exact
#: for the axisymmetric section). Holds where the network is within 10 % of the FEM —
#: on all of its measured map (docs/magnetics.md); its map bounds the torque error per
#: design (torque_error_bound in sweep rows; a note on evaluate where it exceeds 10 %).
#: Checked on the paper preset, variants and the optimiser's optimum in
#: tests/mrclutch/test_pipeline.py.
FAST_BANDWIDTH_ERROR = 0.05

#: °C: the fluid's upper temperature limit, the maker's operating range [lord-mrf132dg].
FLUID_LIMIT = FLUIDS[MRF].temperature_range[1]


def fluid_limit(materials: MaterialChoice) -> float:
    """°C, the hottest the chosen fluid may run (its maker's range)."""
    return FLUIDS[materials.fluid].temperature_range[1]


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
    fluid_inertia: float  # kg·m²: fluid carried by the output (linear Couette profiles)
    drag: Drag  # every off-state drag term at the input speed and fluid temperature
    coil_resistance: float  # Ω at the coil temperature
    coil_power: float  # W at max_current
    diameter: float  # m, envelope
    length: float  # m, envelope
    thermal: Mapping[str, float]  # thermal_figures: continuous rating, times to the limits
    methods: Mapping[str, str]
    notes: tuple[str, ...] = ()
    inertia_parts: Mapping[str, float] = field(default_factory=dict)  # kg·m², output parts

    @property
    def drag_damping(self) -> float:
        """N·m·s: dT/dω of all the drag terms at the operating slip."""
        return self.drag.damping

    @property
    def off_state_torque(self) -> float:
        return self.drag.torque

    @property
    def moving_inertia(self) -> float:
        """kg·m²: what the output's motion accelerates — rotor, shaft and carried fluid."""
        return self.rotor_inertia + self.fluid_inertia

    @property
    def torque_per_inertia(self) -> float:
        return self.max_torque / self.rotor_inertia

    @property
    def dynamic_range_db(self) -> float:
        return float(dynamic_range_db(self.max_torque, self.off_state_torque))

    def as_json(self) -> dict[str, Any]:
        return {
            "max_current_A": self.max_current,
            "max_torque_N_m": self.max_torque,
            "yield_torque_N_m": self.yield_torque,
            "rotor_inertia_kg_m2": self.rotor_inertia,
            "rotor_mass_kg": self.rotor_mass,
            "clutch_mass_kg": self.clutch_mass,
            "fluid_inertia_kg_m2": self.fluid_inertia,
            "drag_damping_N_m_s": self.drag_damping,
            "off_state_torque_N_m": self.off_state_torque,
            "dynamic_range_dB": self.dynamic_range_db,
            "torque_per_inertia_N_m_per_kg_m2": self.torque_per_inertia,
            "coil_resistance_ohm": self.coil_resistance,
            "coil_power_W": self.coil_power,
            **dict(self.thermal),
            "drag": self.drag.as_json(),
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
    section = build_section(c, design.materials)
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
        torque_method = "network" if fidelity == "fast" else "fem"
        if torque_method == "network":  # never a silent wrong number (issue 6)
            extra = circuit_trust(c, "network", design.current_limit, design.materials)
    if inertia_method == "analytic":
        mass = analytic_mass(section)
    else:
        mass = brep_mass(c, materials=design.materials)
    i_max = design.current_limit
    temp = op.fluid_temperature
    curve = torque_curve(
        section, [i_max], method=torque_method, speed_rpm=op.input_speed_rpm, fem_size=fem_size,
        temperature=temp, support=design.support,
    )  # fmt: skip
    drag = curve.drag
    coil = coil_properties(c, i_max, op.coil_temperature)
    thermal = thermal_figures(design, section.table, path_from_section(section), drag.torque,
                              float(curve.torque[0]))  # fmt: skip
    d, length = section.envelope
    notes = (tuple(mass.notes) + extra + drag.notes + _thermal_notes(design, thermal)
             + _density_notes(design) + _supply_notes(design))  # fmt: skip
    return ClutchFigures(
        max_current=i_max,
        max_torque=float(curve.torque[0]),
        yield_torque=float(curve.yield_torque[0]),
        rotor_inertia=mass.rotor_inertia,
        rotor_mass=mass.rotor_mass,
        clutch_mass=mass.clutch_mass,
        fluid_inertia=float(coupled_fluid_inertia(section.table)),
        drag=drag,
        coil_resistance=coil.resistance,
        coil_power=coil.power,
        diameter=d,
        length=length,
        thermal=MappingProxyType(thermal),
        methods={
            "inertia": mass.method,
            "torque": torque_method if fem_size is None else f"fem@{fem_size * 1e3:g}mm",
            "drag": "terms (magnetics.drag)",
            "thermal": "3-node network (magnetics.thermal)",
        },
        notes=notes,
        inertia_parts=MappingProxyType(_output_parts(mass)),
    )


def thermal_figures(design: ClutchDesign, rg: regions.Regions, path: Any, off_torque: float,
                    peak_torque: float) -> dict[str, float]:  # fmt: skip
    """Continuous rating and peak endurance of one design (``magnetics.thermal``): the same
    closed forms as the sweeps' continuous torque, plus the transient at the peak current
    holding the peak torque while slipping at the input speed."""
    op = design.operating
    limit = fluid_limit(rg.materials)
    net = thermal.network(rg, op.ambient_temperature, limit)
    # the chords through the default torque model's curve (the network), as the sweeps
    ladder = network_from_regions(rg)
    i_c, t_c = continuous_torque(net, path, op.input_speed, off_torque,
                                 op.wire_temperature_limit, limit,
                                 torque_at=network_yield_at(ladder))  # fmt: skip
    t_wire, t_fluid = thermal.time_to_limits(
        net,
        design.current_limit,
        peak_torque * op.input_speed,
        op.wire_temperature_limit,
        limit,
    )
    # the steady temperatures with no current, slipping unenergised (why a rating is 0)
    idle = np.ravel(thermal.steady(net, 0.0, off_torque * op.input_speed))
    return {
        "continuous_current_A": float(np.ravel(i_c)[0]),
        "continuous_torque_N_m": float(np.ravel(t_c)[0]),
        "idle_coil_temperature_C": float(idle[0]),
        "idle_fluid_temperature_C": float(idle[1]),
        "time_to_wire_limit_s": t_wire,
        "time_to_fluid_limit_s": t_fluid,
        "thermal_time_constant_s": float(thermal.time_constants(net)[0]),
    }


def _thermal_notes(design: ClutchDesign, th: Mapping[str, float]) -> tuple[str, ...]:
    """Say when the peak cannot be held for its duration, and why a continuous rating is
    0 (which limit the unenergised clutch already reaches by its slip heat alone)."""
    op = design.operating
    out = []
    if th["time_to_wire_limit_s"] < op.peak_duration:
        out.append(f"the coil reaches {op.wire_temperature_limit:g} °C after "
                   f"{th['time_to_wire_limit_s']:.2g} s at the peak current, before the "
                   f"{op.peak_duration:g} s peak duration")  # fmt: skip
    if th["continuous_current_A"] <= 0.0:
        limit = fluid_limit(design.materials)
        fluid, coil = th["idle_fluid_temperature_C"], th["idle_coil_temperature_C"]
        which = (f"the fluid would settle at {fluid:.4g} °C, above its {limit:g} °C limit"
                 if fluid > limit else f"the coil would settle at {coil:.4g} °C, above its "
                 f"{op.wire_temperature_limit:g} °C limit")  # fmt: skip
        out.append(f"continuous rating 0: slipping unenergised at {op.input_speed_rpm:g} rpm, "
                   f"the drag's heat alone (off-state torque × speed) exceeds a thermal limit "
                   f"({which}, ambient {op.ambient_temperature:g} °C); no current can be held "
                   "continuously — slower input speed, wider gaps or more cooling")  # fmt: skip
    return tuple(out)


def _density_notes(design: ClutchDesign) -> tuple[str, ...]:
    """Say when the current-density limit, not max_current, sets the current limit (the
    design is evaluated at a current the user did not type)."""
    op = design.operating
    area = math.pi * design.clutch.wire_diameter**2 / 4
    cap = op.current_density_limit * area  # A = (A/m²)·m²
    if cap >= op.max_current or design.supply_current < cap:  # not the binding limit
        return ()
    source = ("max_current_density_A_per_mm2" if op.max_current_density is not None
              else f"IEC 60949 adiabatic limit for {op.peak_duration:g} s")  # fmt: skip
    return (f"the current-density limit caps the current at {cap:.4g} A, below "
            f"max_current_A = {op.max_current:g}: {op.current_density_limit * 1e-6:.4g} A/mm² "
            f"({source}) in the {design.clutch.wire_diameter * 1e3:.3g} mm wire; every "
            f"figure is at {cap:.4g} A",)  # fmt: skip


def _supply_notes(design: ClutchDesign) -> tuple[str, ...]:
    """Say when the amplifier's supply, not max_current, sets the current limit."""
    op, supply = design.operating, design.supply_current
    if supply >= current_limit(op, design.clutch.wire_diameter):  # capped without the supply
        return ()
    volts = design.amplifier.supply_voltage
    return (f"the amplifier's {volts:g} V supply holds at most {supply:.3g} A through the "
            f"coil ({volts / supply:.3g} Ω at {op.coil_temperature:g} °C): the current "
            f"limit is {supply:.3g} A, below max_current_A = {op.max_current:g}; raise "
            "[amplifier] supply_voltage_V to reach it",)  # fmt: skip


def current_notes(design: ClutchDesign) -> tuple[str, ...]:
    """Why the design's current limit is below its typed max_current_A (the current
    density in the wire, the amplifier's supply), as ``evaluate`` prints it; () if it is
    not."""
    return _density_notes(design) + _supply_notes(design)


def dynamic_range_db(max_torque: Any, off_torque: Any) -> Any:
    """Largest over smallest torque, in dB: 20 log10(T_max / T_off)."""
    return 20 * np.log10(np.asarray(max_torque) / np.asarray(off_torque))


def _output_parts(mass: MassReport) -> dict[str, float]:
    return {p: float(mass.parts[p].inertia) for p in regions.OUTPUT_PARTS if p in mass.parts}


def mr_at_hand(design: ClutchDesign, inertia: Any, damping: Any, torque: Any, mass: Any,
               delay: Any = None) -> HapticParams:  # fmt: skip
    """The antagonistic pair of clutches with these figures (floats or arrays of designs),
    seen at the hand through the design's transmission (Eq. 3–4): what ``evaluate`` and
    ``evaluate_batch`` both feed the haptic model. ``delay``: the torque response's
    equivalent delay, used where ``operating.delay_source`` is "geometry"."""
    op = design.operating
    pair = Actuator.mr_pair(inertia, damping, torque, mass, op.delay, design.name)
    hp = reflect(pair, design.transmission)
    if op.delay_source == "geometry" and delay is not None:
        hp = replace(hp, delay=delay)  # one delay per design (arrays in a sweep)
    return hp


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
    motor: HapticParams | None  # None: unavailable (``unavailable["motor"]`` says why)
    motor_gearing: float | None
    haptic: Mapping[str, Any]  # metrics of the MR pair at K_max
    motor_metrics: Mapping[str, Any]  # metrics of the motor at the same K
    budget: Mapping[str, Any]  # b1 and m1 as named terms beside the paper's Table 2
    zwidth: Mapping[str, Any]  # side → the Z-width (``zwidth.zwidth``) of MR pair and motor
    hand: Mapping[str, Any]  # side → ``hand.hand_figures``: coupled stability, transparency
    response: Mapping[str, Any] = field(default_factory=dict)  # ``response_figures``
    torque_response: Any = None  # its ``magnetics.dynamics.TorqueResponse`` (step, lags)
    #: secondary figures that could not be computed → why (the motor comparison, the
    #: torque response's delay); the rest of the evaluation stands
    unavailable: Mapping[str, str] = field(default_factory=dict)
    source: str = "fast model"  # where the pair's figures at the hand come from
    model_mr: HapticParams | None = None  # the model's pair where measured values replace it
    #: ``mrclutch.feel.feel_figures``: the residual torque and its loop, the runout ripple
    feel: Mapping[str, Any] = field(default_factory=dict)

    @functools.cached_property
    def duty(self) -> dict[str, Any]:
        """Issue 41: the hot peak and duty holds, the fluid's volume and life and the b1
        budget's new terms (``mrclutch.duty.evaluation_duty``), computed when first read."""
        return evaluation_duty(self)

    def as_json(self) -> dict[str, Any]:
        mr_m, em_m = dict(self.haptic), dict(self.motor_metrics)
        zw = {k: dict(v) for k, v in self.zwidth.items()}
        hand = {k: dict(v) for k, v in self.hand.items()}
        motor = {**em_m, "actuator": MOTOR, "gearing": self.motor_gearing}
        if self.motor is None:  # every figure of the motor's side None, and why
            why = self.unavailable["motor"]
            motor = {**dict.fromkeys(mr_m), "actuator": MOTOR, "gearing": None, "note": why}
            zw["motor"] = {**dict.fromkeys(zw["mr"]), "note": why}
            hand["motor"] = {**_nones(hand["mr"]), "note": why}
        out = {
            "design": self.design.name,
            "fidelity": self.fidelity,
            "clutch": self.clutch.as_json(),
            "haptic": mr_m,
            "budget": dict(self.budget),
            "motor": motor,
            "bandwidth_gain": _gain(mr_m["bandwidth_hz"], motor["bandwidth_hz"]),
            "bandwidth_gain_lumped": _gain(
                mr_m["bandwidth_lumped_hz"], motor["bandwidth_lumped_hz"]
            ),
            "zwidth": zw,
            "hand": hand,
            "response": dict(self.response),
            "unavailable": dict(self.unavailable),
            "source": self.source,
            "feel": {k: dict(v) for k, v in self.feel.items()},
            "duty": self.duty,
        }
        out["nulls"] = null_notes(out)
        return out


#: Why a figure is NaN (null in JSON) where that is its documented meaning, by key.
NAN_MEANS: dict[str, str] = {
    "resonance_hz": "no resonance: the free lever is overdamped (every zero of Eq. 2 is "
    "real; mrclutch.haptics.model.resonance)",
    "B_N_s_per_m": "no damping grid: B_top is unbounded (every damper renders passively at "
    "K = 0), so [0, B_top] cannot be sampled; the intercepts and the area say the rest",
    "K_max_N_per_m": "no passive K >= 0 at that damping (the Z-width is empty there), or no "
    "damping grid (B_N_s_per_m null)",
    "bandwidth_gain": "one side has no bandwidth (the motor unavailable, or no crossing)",
    "max_stable_K_N_per_m": "unknown: the stability scan cannot resolve this loop (it would "
    "need more than 2e6 frequencies a step: an extreme transmission or delay)",
    "max_stable_K_torque_delay_N_per_m": "unknown: the stability scan cannot resolve this "
    "loop with that delay, or the lags are not finite",
    "bandwidth_gain_lumped": "one side has no bandwidth (the motor unavailable)",
}
NAN_MEANS["K_min_N_per_m"] = NAN_MEANS["K_max_N_per_m"]
NAN_MEANS["robust"] = (
    "not asked: the verdict is at nominal values only (--no-uncertainty, "
    "or the design's [render] verdict = 'nominal')"
)
NAN_MEANS["K_max_at_B0_N_per_m"] = (
    "no passive K >= 0 even with no virtual damping (the Z-width is empty at B = 0)"
)
NAN_MEANS["delay"] = (
    "the delay's range is not given: it spans the typed delay and the torque "
    "response's equivalent delay at the corners (mrclutch.robust)"
)
NAN_MEANS["fluid_temperature"] = "the fluid's temperature range is not given: the operating one"
NAN_MEANS["max_stable_K_typed_delay_N_per_m"] = NAN_MEANS["max_stable_K_N_per_m"]
NAN_MEANS["max_stable_K_lags_N_per_m"] = NAN_MEANS["max_stable_K_torque_delay_N_per_m"]
#: What an infinite figure (null in JSON, which has no infinity) means, by key.
INF_MEANS: dict[str, str] = {
    "time_to_wire_limit_s": "never: the coil stays below its temperature limit at the peak current",
    "time_to_fluid_limit_s": "never: the fluid stays below its temperature limit at the "
    "peak current",
}
NAN_MEANS.update(DUTY_NULLS)  # issue 41's figures (mrclutch.duty)
INF_MEANS.update(DUTY_INFS)
_UNBOUNDED = "unbounded (inf): no finite limit exists; JSON has no infinity"


def null_notes(data: Mapping[str, Any]) -> dict[str, str]:
    """Every figure of an evaluation's JSON that would be null (None, NaN or ±inf), by its
    path ("zwidth/mr/K_max_N_per_m[3]" as "zwidth/mr/K_max_N_per_m"), with why: the
    documented meaning of a NaN or an inf, or the note of an unavailable side. Figures
    left without a reason would be a bug (tests/mrclutch/test_robust_inputs.py)."""
    out: dict[str, str] = {}

    def walk(v: Any, path: tuple[str, ...], note: str | None) -> None:
        if isinstance(v, Mapping):
            here = v.get("note") if isinstance(v.get("note"), str) else note
            for k, x in v.items():
                if k not in ("nulls", "note"):
                    walk(x, (*path, str(k)), here)
            return
        if isinstance(v, (list, tuple, np.ndarray)) and np.ndim(v) > 0:
            for x in v:
                walk(x, path, note)
            return
        if v is None:
            why = note or NAN_MEANS.get(path[-1])
        elif isinstance(v, (float, np.floating)) and math.isnan(v):
            why = note or NAN_MEANS.get(path[-1])
        elif isinstance(v, (float, np.floating)) and math.isinf(v):
            why = INF_MEANS.get(path[-1], _UNBOUNDED)
        else:
            return
        key = "/".join(path)
        if key not in out:
            out[key] = why or "not computed (no reason recorded)"

    walk(data, (), None)
    return out


def _nones(d: Mapping[str, Any]) -> dict[str, Any]:
    """The same keys (nested), every value None: a side whose figures are unavailable."""
    return {k: _nones(v) if isinstance(v, Mapping) else None for k, v in d.items()}


def _gain(a: float | None, b: float | None) -> float | None:
    if a is None or b is None or not np.isfinite(a) or not np.isfinite(b):
        return None
    return a / b - 1.0


def evaluate(
    design: ClutchDesign,
    fidelity: str = "fast",
    accuracy: float | None = None,
    K: float | None = None,
) -> Evaluation:
    """The clutch figures and their haptic consequences, beside the equal-force motor, at
    the virtual stiffness ``K`` (N/m; None: the MR pair's K_max, Eq. 4). ``accuracy``
    (relative): pick per quantity the cheapest method that meets it (mrclutch.trust.choose);
    the Evaluation's fidelity then reads "accuracy=…". The design's own ``[render]`` rule
    is applied by ``mrclutch.verdict.judge``, which calls this."""  # fmt: skip
    fig = clutch_figures(design, fidelity, accuracy)
    if accuracy is not None:
        fidelity = f"accuracy={accuracy:g}"
    resp = torque_response(
        build_section(design.clutch, design.materials).table,
        fig.max_current,
        design.amplifier,
        design.laminations,
        coil_temperature=design.operating.coil_temperature,
    )
    mr = mr_at_hand(design, fig.moving_inertia, fig.drag_damping, fig.max_torque,
                    fig.clutch_mass, float(resp.equivalent_delay[0]))  # fmt: skip
    model_mr = mr
    mr, source = with_measured(design, mr, fig.max_current, source_label(fidelity))
    motor = actuator(MOTOR)
    unavailable: dict[str, str] = {}
    try:  # a secondary figure: a motor that cannot be geared to the force is left out
        em_tr: Transmission | None = motor_transmission(mr, design.transmission, motor)
        em: HapticParams | None = reflect(motor, em_tr)
    except ParameterError as exc:
        em_tr = em = None
        unavailable["motor"] = (f"the equal-force {MOTOR} is left out: matching the MR pair's "
                                f"{float(mr.f_max):.4g} N would need {exc}")  # fmt: skip
    sides = [mr] if em is None else [mr, em]
    zw = zwidth_of(HapticParams.stack(sides))
    names = ZWIDTH_SIDES[: len(sides)]
    zws = {side: {key: zw[key][i] if np.ndim(zw[key]) > 1 else float(zw[key][i])
                  for key in ZWIDTH_KEYS} for i, side in enumerate(names)}  # fmt: skip
    gearing = em_tr.gearing if em_tr is not None else None
    ev = Evaluation(design, fidelity, fig, mr, em, gearing, {}, {}, {}, zws, {},
                    response_figures(design, resp, mr, unavailable), resp,
                    MappingProxyType(unavailable), source, model_mr,
                    feel_figures(design, fig.max_torque, fig.yield_torque, fig.off_state_torque,
                                 float(backdrive_force(mr))))  # fmt: skip
    return rendered(ev, float(mr.k_max) if K is None else K)


def rendered(ev: Evaluation, K: float) -> Evaluation:
    """``ev`` with the MR pair and the equal-force motor rendering the virtual spring ``K``
    (N/m): the metrics at the hand, the b1 budget's Table 2 check and the hand figures are
    taken at K; the clutch, the pair's parameters, K_max and the Z-width do not depend on
    it. ``haptic["K_max_N_per_m"]`` is the pair's F_max/d (Eq. 4) whatever K is."""
    mr, em = ev.mr, ev.motor
    unavailable = {k: v for k, v in ev.unavailable.items() if not k.startswith("hand_")}
    table2 = replace(mr, b1=TABLE2_MR.b1)  # the same pair with the paper's identified b1
    sides = [mr] if em is None else [mr, em]
    *side_m, t2_m = metrics_of([*sides, table2], [K] * (len(sides) + 1))
    mr_m, em_m = side_m[0], (side_m[1] if em is not None else {})
    mr_m = {**mr_m, "K_max_N_per_m": float(mr.k_max)}
    if em is not None:
        em_m = {**em_m, "K_max_N_per_m": float(em.k_max)}
    budget = hand_budget(ev.design, ev.clutch, mr, t2_m)
    names = ZWIDTH_SIDES[: len(sides)]
    hand = {side: _hand_or_why(p, K, unavailable, side)
            for side, p in zip(names, sides, strict=True)}  # fmt: skip
    return replace(ev, haptic=mr_m, motor_metrics=em_m, budget=budget, hand=hand,
                   unavailable=MappingProxyType(unavailable))  # fmt: skip


#: The label beside a figure at the hand: where its torque, mass and damping come from.
SOURCE_LABELS = {"fast": "fast model", "reference": "reference model"}


def source_label(fidelity: str) -> str:
    """ "fast model", "reference model", or the accuracy target's label."""
    return SOURCE_LABELS.get(fidelity, f"model, {fidelity}")


def with_measured(design: ClutchDesign, mr: HapticParams, current: float, source: str
                  ) -> tuple[HapticParams, str]:  # fmt: skip
    """The pair at the hand with what the bench measured put in (``[measured]`` with
    ``use_in_model``): m1, b1, the step delay and, measured at the current limit, the
    torque (F_max through Eq. 4's reduction); the label then names them as measured."""
    meas = design.measured
    if meas is None or not meas.use_in_model:
        return mr, source
    new: dict[str, float] = {}
    if meas.m1 is not None:
        new["m1"] = meas.m1
    if meas.b1 is not None:
        new["b1"] = meas.b1
    if meas.step_delay is not None:
        new["delay"] = meas.step_delay
    at_limit = [p.torque for p in meas.torque if math.isclose(p.current, current, rel_tol=1e-9)]
    if at_limit:
        new["f_max"] = at_limit[0] * design.transmission.reduction  # Eq. 4: F = T nG/l
    if not new:
        return mr, source
    names = {"m1": "m1", "b1": "b1", "delay": "delay", "f_max": "torque"}
    return replace(mr, **new), f"measured ({', '.join(names[k] for k in new)}) + {source}"


def _hand_or_why(p: HapticParams, k: float, unavailable: dict[str, str], side: str
                 ) -> dict[str, Any]:  # fmt: skip
    """``hand_figures``, or (where the stability scan cannot resolve the loop) the same keys
    None with a note, the reason also in ``unavailable``."""
    try:
        return hand_figures(p, k)
    except StabilitySearchError as exc:
        why = f"the hand figures are unknown: {exc}"
        unavailable[f"hand_{side}"] = why
        return {**_nones(HAND_KEYS), "notes": [], "note": why}


#: The keys of ``hand_figures`` (nested), for a side whose figures are unavailable.
HAND_KEYS: dict[str, Any] = {
    "K_N_per_m": 0, "coupled_stable": 0, "max_stable_K_all_hands_N_per_m": 0,
    "worst_hand": {"m_kg": 0, "b_N_s_per_m": 0, "k_N_per_m": 0}, "hands_checked": 0,
    "max_stable_K_hands_off_N_per_m": 0, "max_passive_K_N_per_m": 0, "backdrive_force_N": 0,
    "felt_damping_N_s_per_m": 0, "felt_mass_kg": 0,
    "motion": {"amplitude_m": 0, "frequency_hz": 0},
}  # fmt: skip


def response_figures(design: ClutchDesign, resp: Any, mr: HapticParams,
                     unavailable: dict[str, str] | None = None) -> dict[str, Any]:  # fmt: skip
    """The torque response of one design (``magnetics.dynamics.TorqueResponse``) and what it
    does to the haptic loop: the largest stable K with the typed delay, with the
    equivalent delay τ_eq, and with the lags themselves (the reference τ_eq approximates).
    Where the lags are not finite those two K are None and ``unavailable`` (filled in
    place) says why."""
    op = design.operating
    tau_eq = float(resp.equivalent_delay[0])
    k_typed = max_stable_stiffness(replace(mr, delay=op.delay))
    k_eq = k_lags = None
    if np.all(np.isfinite(resp.lags[0])):
        k_eq = max_stable_stiffness(replace(mr, delay=tau_eq))
        k_lags = lag_stable_stiffness(replace(mr, delay=0.0), resp.lags[0])
    elif unavailable is not None:
        unavailable["torque_response"] = (
            f"the current does not reach 90 % of {float(resp.current[0]):.3g} A on the "
            f"{design.amplifier.supply_voltage:g} V supply: no equivalent delay, and no "
            "stable K with it")  # fmt: skip
    return {
        **resp.item(0),
        "delay_source": op.delay_source,
        "typed_delay_s": op.delay,
        "supply_voltage_V": design.amplifier.supply_voltage,
        "current_bandwidth_hz": design.amplifier.current_bandwidth_hz,
        "max_stable_K_typed_delay_N_per_m": k_typed,
        "max_stable_K_torque_delay_N_per_m": k_eq,
        "max_stable_K_lags_N_per_m": k_lags,
    }


#: The sides of ``Evaluation.zwidth`` and ``.hand``: the MR pair and the equal-force motor.
ZWIDTH_SIDES = ("mr", "motor")


#: Why the budget of b1 may not reach the paper's identified value, least certain first.
B1_UNCERTAIN = (
    "the fluid's viscosity law: the carrier grade is not disclosed (a PAO 4 is assumed), "
    "and the datasheet η is ±18 % at 40 °C",
    "the gap: the paper's clutch gaps are not published (the preset's 0.7 mm was inferred); "
    "the film damping scales as 1/gap",
    "Table 2's b1 was fitted by eye to the bench's response (paper §III), lever and cable included",
)


def hand_budget(design: ClutchDesign, fig: ClutchFigures, mr: HapticParams,
                table2: Mapping[str, Any]) -> dict[str, Any]:  # fmt: skip
    """b1 and m1 at the hand as named terms (the pair's two clutches, Eq. 3), each with its
    value, share and source, beside the paper's Table 2; the terms sum to the values the
    haptic model uses. ``table2``: the pair's metrics with Table 2's b1 instead."""
    r2 = 2 * design.transmission.reduction**2  # both clutches of the pair, Eq. 3
    b_terms = [(k, t.damping * r2, t.source) for k, t in fig.drag.terms.items()]
    labels = {"rotor": "output rotor (hub + drums)", "shaft": "output shaft"}
    how = f"inertia by {fig.methods['inertia']}"
    m_terms = [(labels.get(k, k), v * r2, how) for k, v in fig.inertia_parts.items()]
    m_terms.append(("carried fluid", fig.fluid_inertia * r2, "linear Couette (magnetics.drag)"))

    def table(terms: list[tuple[str, float, str]], total: float, paper: float) -> dict[str, Any]:
        rows = [
            {"name": n, "value": v, "share": v / total if total else math.nan, "source": src}
            for n, v, src in terms
        ]
        return {
            "terms": rows,
            "total": total,
            "paper_table2": paper,
            "unexplained": paper - total,
            "ratio_to_paper": total / paper,
        }

    b1, m1 = float(mr.b1), float(mr.m1)
    return {
        # Table 2 identified the paper's own clutch: "unexplained" means something only there
        "paper_clutch": design.clutch == preset("paper"),
        "b1_N_s_per_m": {
            **table(b_terms, b1, float(TABLE2_MR.b1)),
            "least_certain": list(B1_UNCERTAIN),
        },
        "m1_kg": table(m_terms, m1, float(TABLE2_MR.m1)),
        "with_table2_b1": {
            "b1_N_s_per_m": float(TABLE2_MR.b1),
            "passive": bool(table2["passive"]),
            "max_passive_K_N_per_m": table2["max_passive_K_N_per_m"],
            "max_stable_K_N_per_m": table2["max_stable_K_N_per_m"],
        },
    }


# ---- the vectorised fast path for sweeps -----------------------------------------------


def _material_bounds(
    p: Mapping[str, np.ndarray], current: np.ndarray, mats: MaterialChoice | np.ndarray,
    features: Mapping[str, np.ndarray],
) -> np.ndarray:  # fmt: skip
    """The network's error bound of every row at its material set (``trust.material_set``;
    magnetics.network_bound: inf for a set never measured), from its network's solution
    ``features`` at that current (``solution_features``, each (S,))."""
    if isinstance(mats, MaterialChoice):
        return np.asarray(
            error_bound(p, "network", current, material_set(mats), features)[1], float
        )
    keys = np.array([material_set(m) for m in mats], dtype=object)
    out = np.full(keys.shape, np.inf)
    for key in dict.fromkeys(keys.tolist()):
        rows = keys == key
        sub = {k: np.asarray(v)[rows] for k, v in p.items()}
        feats = {k: np.asarray(v)[rows] for k, v in features.items()}
        out[rows] = error_bound(sub, "network", np.asarray(current)[rows], key, feats)[1]
    return out


@dataclass(frozen=True)
class BatchEvaluator:
    """Picklable fast-path evaluator of arrays of designs around a base ClutchDesign.

    Fields a sweep does not vary come from ``base.clutch``; operating point and
    transmission are the base design's. Invalid designs (DrumClutch validation fails) get
    ``valid = 0`` and NaN outputs; they are computed on the base geometry meanwhile so no
    invalid number ever reaches the solvers.
    """

    base: ClutchDesign
    optional: tuple[str, ...] = ()  # of ``SWEEP_OPTIONAL``: columns after SWEEP_COLUMNS

    def __post_init__(self) -> None:
        for key in self.optional:
            check_choice("optional column", key, SWEEP_OPTIONAL)

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns of its rows, in order."""
        return (*SWEEP_COLUMNS, *(k for k in SWEEP_OPTIONAL if k in self.optional))

    def __call__(self, fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        on = set(self.optional)
        feel = tuple(k for k in self.optional if k in FEEL_COLUMNS)  # mrclutch.feel
        robust = on - {"max_passive_K_N_per_m", "max_stable_K_N_per_m", "zwidth_area_N2_s_per_m2",
                       *FEEL_COLUMNS, *DUTY_COLUMNS}  # fmt: skip
        if robust:  # over the uncertain inputs: the application's robust layer computes them
            raise ParameterError(f"{sorted(robust)[0]}: a robust column; "
                                 "use mrclutch.robust.RobustBatchEvaluator")  # fmt: skip
        out = evaluate_batch(fields, self.base, passivity="max_passive_K_N_per_m" in on,
                             stability="max_stable_K_N_per_m" in on,
                             zwidth="zwidth_area_N2_s_per_m2" in on)  # fmt: skip
        if feel:
            out.update(feel_batch(fields, self.base, feel))
        if on & set(DUTY_COLUMNS):  # the fluid's volume and life (mrclutch.duty)
            out.update(duty_batch(fields, self.base, out))
        return {k: out[k] for k in self.columns}


def evaluate_batch(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign | None = None,
    *,
    passivity: bool = False,
    stability: bool = False,
    zwidth: bool = False,
) -> dict[str, np.ndarray]:
    """The fast path for S designs at once; returns arrays under ``SWEEP_COLUMNS``, and
    opt-in columns after them: ``max_passive_K_N_per_m`` (``passivity``, about ×1.7 the
    cost), ``max_stable_K_N_per_m`` (``stability``: design by design, about ×8),
    ``zwidth_area_N2_s_per_m2`` (``zwidth``, about ×7) (``outputs.SWEEP_OPTIONAL``).

    The same physics as ``evaluate(design, "fast")``, on arrays: per drum count, the region
    table gives the analytic mass (``region_mass``), the max torque by the reluctance
    network (``network_from_regions``), the circuit (``path_from_regions``: the flux the
    torque response starts from), the drag terms (``drag_terms``), the carried fluid
    (``coupled_fluid_inertia``) and the continuous rating (``continuous_torque``, its chords
    through the network's curve from the peak's loop fluxes, ``network_yield_at``); the
    pair at the hand is ``mr_at_hand``.
    Designs that fail DrumClutch's validation get ``valid = 0`` and NaN outputs; no invalid
    number reaches a solver."""
    base = base if base is not None else ClutchDesign()
    p, mats = batch_fields(fields, base)
    ok = valid(p)
    op = base.operating
    current = np.array(np.broadcast_to(current_limit(op, p["wire_diameter"]), ok.shape), float)

    def clutch(rg: regions.Regions, rows: np.ndarray) -> dict[str, Any]:
        # the amplifier's V/R caps the current as in ClutchDesign.current_limit
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            supply = supply_current(rg.fields, rg.at, base.amplifier, op.coil_temperature)
        current[rows] = np.minimum(current[rows], np.nan_to_num(supply, nan=np.inf))
        out = region_mass(rg)
        terms = drag_terms(rg, op.input_speed, op.fluid_temperature, base.support)
        out["off_torque"], out["damping"] = totals(terms)
        out["fluid_inertia"] = coupled_fluid_inertia(rg)
        path = path_from_regions(rg)
        # the loop's flux at the peak: the torque response's start (its torque is not used)
        flux = np.abs(solve_flux(path, (path.turns * current[rows])[:, None], rtol=1e-7))
        ladder = network_from_regions(rg)
        t_peak, x_peak = network_torque_and_flux(ladder, current[rows][:, None])
        out["yield_torque"] = t_peak.sum(-1)[:, 0]
        # the network's error bound reads its solution at the peak (no second solve)
        for k, v in solution_features(ladder, x_peak).items():
            out[f"bound_{k}"] = v[:, 0]
        resp = torque_response(rg, current[rows], base.amplifier, base.laminations, path=path,
                               coil_temperature=op.coil_temperature,
                               flux_peak=flux[:, 0])  # fmt: skip
        out["torque_delay"] = resp.equivalent_delay
        limit = fluid_limit(rg.materials)
        net = thermal.network(rg, op.ambient_temperature, limit)
        out["continuous_torque"] = continuous_torque(
            net, path, op.input_speed, out["off_torque"], op.wire_temperature_limit,
            limit, torque_at=network_yield_at(ladder, seed=(current[rows], x_peak)),
        )[1]  # fmt: skip
        return out

    fig = regions.per_topology(p, ok, clutch, mats)
    off_torque = fig["off_torque"]
    torque = fig["yield_torque"] + off_torque
    hand = {}
    if ok.any():
        inertia = fig["rotor_inertia"] + fig["fluid_inertia"]
        hp = mr_at_hand(base, inertia[ok], fig["damping"][ok], torque[ok],
                        fig["clutch_mass"][ok], fig["torque_delay"][ok])  # fmt: skip
        hand = dict(metrics_batch(hp, limits=False))
        hand["backdrive_force_N"] = backdrive_force(hp)
        if passivity:
            hand["max_passive_K_N_per_m"] = max_passive_stiffness(hp)
        if stability:
            hand["max_stable_K_N_per_m"] = max_stable_stiffness(hp)
        if zwidth:
            hand["zwidth_area_N2_s_per_m2"] = zwidth_of(hp)["zwidth_area_N2_s_per_m2"]
    out = {
        "valid": ok.astype(float),
        "rotor_inertia_kg_m2": fig["rotor_inertia"],
        "rotor_mass_kg": fig["rotor_mass"],
        "clutch_mass_kg": fig["clutch_mass"],
        "diameter_m": fig["diameter"],
        "length_m": fig["length"],
        "max_torque_N_m": torque,
        # each row's material set's bound (inf where that set was never measured)
        "torque_error_bound": np.where(
            ok,
            _material_bounds(p, current, mats, {k: fig[f"bound_{k}"] for k in FEATURES}),
            np.nan,
        ),
        "fluid_inertia_kg_m2": fig["fluid_inertia"],
        "drag_damping_N_m_s": fig["damping"],
        "off_state_torque_N_m": off_torque,
        "dynamic_range_dB": dynamic_range_db(torque, off_torque),
        "continuous_torque_N_m": fig["continuous_torque"],
        "torque_delay_s": fig["torque_delay"],
    }
    opt_in = {
        "max_passive_K_N_per_m": passivity,
        "max_stable_K_N_per_m": stability,
        "zwidth_area_N2_s_per_m2": zwidth,
    }
    extra = tuple(k for k, on in opt_in.items() if on)
    columns = (*SWEEP_COLUMNS, *extra)
    for key in columns:
        if key not in out:  # a metric at the hand
            col = np.full(ok.shape, np.nan)
            if ok.any():
                col[ok] = np.broadcast_to(np.asarray(hand[key], dtype=float), (int(ok.sum()),))
            out[key] = col
    return {key: out[key] for key in columns}
