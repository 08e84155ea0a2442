"""What one clutch is: its figures at the current limit (torque, inertia and mass, drag,
coil, thermal rating) by the fast or the reference method (``clutch_figures``), and the
notes that say why a figure is not what the user typed (the current limit, a thermal
limit). The first stage of ``mrclutch.pipeline.evaluate``; the batch path computes the
same figures on arrays (``mrclutch.fast_batch``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry import regions
from geometry.mass import MassReport, analytic_mass, brep_mass
from geometry.materials import MRF, MaterialChoice
from geometry.validation import check_choice
from magnetics import thermal
from magnetics.circuit import MagneticPath, path_from_section
from magnetics.drag import Drag, coupled_fluid_inertia
from magnetics.materials import FLUIDS
from magnetics.network import Network, network_from_regions
from magnetics.torque import (
    coil_properties,
    continuous_torque,
    network_yield_at,
    torque_curve,
)
from mrclutch.design import ClutchDesign, current_notes
from mrclutch.design_network import network_curve, section_network, solved_at
from mrclutch.trust import choose, circuit_trust

FIDELITIES: tuple[str, ...] = ("fast", "reference")

#: °C: the fluid's upper temperature limit, the maker's operating range [lord-mrf132dg].
FLUID_LIMIT = FLUIDS[MRF].temperature_range[1]


def fluid_limit(materials: MaterialChoice) -> float:
    """°C, the hottest the chosen fluid may run (its maker's range)."""
    return FLUIDS[materials.fluid].temperature_range[1]


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
    design: ClutchDesign,
    fidelity: str = "fast",
    accuracy: float | None = None,
    path: MagneticPath | None = None,
) -> ClutchFigures:
    """Inertia, mass, torque at the current limit and drag of one design.

    With ``accuracy`` (relative, e.g. 0.01) the methods are the cheapest that meet it
    (mrclutch.trust.choose) and ``fidelity`` is ignored; the choice's notes (e.g. which
    quantity needs an FEM) are added to the figures' notes. ``path``: the design's circuit
    (``path_from_section``) where the caller built it already (the thermal rating's)."""
    check_choice("fidelity", fidelity, FIDELITIES)
    c, op = design.clutch, design.operating
    section, net = section_network(c, design.materials)  # shared with the feel and the duty
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
    i_max = design.current_limit
    # one network solve at N·I_max: the trust check's features and the torque read it
    flux = solved_at(net, i_max) if torque_method == "network" else None
    if accuracy is None and torque_method == "network":  # never a silent wrong number (#6)
        extra = circuit_trust(c, "network", i_max, design.materials, flux)
    temp = op.fluid_temperature
    if torque_method == "network":  # torque_curve's network branch on the shared network
        curve = network_curve(section, net, [i_max], op.input_speed_rpm, temp, design.support,
                              flux)  # fmt: skip
    else:
        curve = torque_curve(
            section, [i_max], method=torque_method, speed_rpm=op.input_speed_rpm,
            fem_size=fem_size, temperature=temp, support=design.support,
        )  # fmt: skip
    drag = curve.drag
    coil = coil_properties(c, i_max, op.coil_temperature)
    path = path_from_section(section) if path is None else path
    thermal = thermal_figures(design, section.table, path, drag.torque, float(curve.torque[0]),
                              net)  # fmt: skip
    # the mass last: a B-rep mass may come from another process (geometry.mass.brep_mass_from:
    # the report's CAD process), and the torque's FEM above runs here meanwhile (issue 40)
    if inertia_method == "analytic":
        mass = analytic_mass(section)
    else:
        mass = brep_mass(c, materials=design.materials)
    d, length = section.envelope
    notes = (tuple(mass.notes) + extra + drag.notes + _thermal_notes(design, thermal)
             + current_notes(design))  # fmt: skip
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
                    peak_torque: float, ladder: Network | None = None
                    ) -> dict[str, float]:  # fmt: skip
    """Continuous rating and peak endurance of one design (``magnetics.thermal``): the same
    closed forms as the sweeps' continuous torque, plus the transient at the peak current
    holding the peak torque while slipping at the input speed. ``ladder``: ``rg``'s
    reluctance network if already built (None: built here)."""
    op = design.operating
    limit = fluid_limit(rg.materials)
    net = thermal.network(rg, op.ambient_temperature, limit)
    # the chords through the default torque model's curve (the network), as the sweeps
    ladder = network_from_regions(rg) if ladder is None else ladder
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


def dynamic_range_db(max_torque: Any, off_torque: Any) -> Any:
    """Largest over smallest torque, in dB: 20 log10(T_max / T_off)."""
    return 20 * np.log10(np.asarray(max_torque) / np.asarray(off_torque))


def _output_parts(mass: MassReport) -> dict[str, float]:
    return {p: float(mass.parts[p].inertia) for p in regions.OUTPUT_PARTS if p in mass.parts}
