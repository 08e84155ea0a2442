"""Every number the tool outputs, named once: key (SI unit in the name), unit, meaning, and
how a person reads it (label, display unit and scale).

The evaluate JSON, the sweep CSV (its columns and the ``.meta.json`` beside it), the
``mrclutch evaluate`` table and the HTML report all take their names from here, so the
same quantity has the same name everywhere. The haptic model (a lower layer) writes its
metrics under its own ``METRIC_KEYS``; each of them has its entry here
(tests/mrclutch/test_outputs.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Output:
    """One output quantity."""

    key: str  # JSON key and CSV column, SI unit in the name
    unit: str  # SI unit ("1" for a pure number, "" for a flag)
    description: str
    label: str  # what a person reads in a table
    display_unit: str = ""  # unit shown beside the label ("" = the SI unit)
    scale: float = 1.0  # SI value × scale = displayed value

    @property
    def shown_unit(self) -> str:
        return self.display_unit or self.unit

    def display(self, value: Any, digits: int = 4) -> str:
        """The value as a person reads it: scaled, ``digits`` significant; yes/no for a
        flag, — for none (None, NaN), ∞ for unbounded."""
        if isinstance(value, str):
            return value
        if value is None:
            return "—"
        if isinstance(value, bool | np.bool_):
            return "yes" if value else "no"
        v = float(value)
        if math.isnan(v):
            return "—"
        if math.isinf(v):
            return "∞" if v > 0 else "−∞"
        return f"{v * self.scale:.{digits}g}"


_ALL = (
    # ---- the clutch (one of the pair) ----------------------------------------------
    Output("valid", "", "1 if the design passes DrumClutch's validation, else 0 (row NaN)",
           "valid"),
    Output("max_current_A", "A", "coil current limit: wire current density or amplifier",
           "max current"),
    Output("max_torque_N_m", "N·m", "yield + viscous torque at the current limit and the "
           "input speed", "max torque"),
    Output("yield_torque_N_m", "N·m", "field-dependent (yield-stress) torque at the current "
           "limit", "yield torque"),
    Output("rotor_inertia_kg_m2", "kg·m²", "output rotor + shaft inertia about the axis",
           "rotor inertia", "g·cm²", 1e7),
    Output("rotor_mass_kg", "kg", "output rotor + shaft mass", "rotor mass", "g", 1e3),
    Output("clutch_mass_kg", "kg", "whole clutch with fluid and coil", "clutch mass", "g",
           1e3),
    Output("diameter_m", "m", "envelope diameter", "diameter", "mm", 1e3),
    Output("length_m", "m", "envelope axial length", "length", "mm", 1e3),
    Output("drag_damping_N_m_s", "N·m·s", "dT/dω of every drag term (films at the fluid "
           "temperature, bearings) at the input speed", "drag damping"),
    Output("off_state_torque_N_m", "N·m", "drag torque at the input speed, 0 A: every term",
           "off-state torque", "mN·m", 1e3),
    Output("fluid_inertia_kg_m2", "kg·m²", "fluid the output carries (linear Couette "
           "profiles)", "carried-fluid inertia", "g·cm²", 1e7),
    Output("dynamic_range_dB", "dB", "20 log10(max torque / off-state torque)",
           "dynamic range"),
    Output("continuous_current_A", "A", "largest current held forever while slipping at "
           "the input speed, within the wire's and the fluid's temperature limits",
           "continuous current"),
    Output("continuous_torque_N_m", "N·m", "torque at the continuous current (slip heat "
           "included)", "continuous torque"),
    Output("time_to_wire_limit_s", "s", "from ambient, at the peak current holding the "
           "peak torque: time until the coil reaches the wire's limit", "time to wire limit"),
    Output("time_to_fluid_limit_s", "s", "same, until the fluid reaches its limit",
           "time to fluid limit"),
    Output("thermal_time_constant_s", "s", "longest time constant of the thermal network",
           "thermal time constant"),
    Output("idle_coil_temperature_C", "°C", "steady coil temperature slipping unenergised at "
           "the input speed (the drag's heat alone): why a continuous rating is 0",
           "idle coil temperature"),
    Output("idle_fluid_temperature_C", "°C", "steady fluid temperature slipping "
           "unenergised at the input speed (the drag's heat alone)", "idle fluid temperature"),
    Output("torque_per_inertia_N_m_per_kg_m2", "N·m/(kg·m²)", "max torque / rotor "
           "inertia", "torque / inertia"),
    Output("coil_resistance_ohm", "Ω", "coil resistance at the coil temperature",
           "coil resistance"),
    Output("coil_power_W", "W", "coil Joule power at the current limit",
           "coil power at max current"),
    Output("torque_error_bound", "1", "bound on the |relative error| of the max torque (the "
           "reluctance network's) against the FEM at this design and current limit, 95 % "
           "coverage over every section dimension (inf: outside the measured ranges or "
           "materials; magnetics/data/network_bound.json)",
           "torque error bound"),
    Output("torque_delay_s", "s", "equivalent pure delay of the torque's response to a "
           "current step: Σ of the electrical, eddy-current and fluid lags "
           "(magnetics.dynamics, docs/dynamics.md)", "torque delay", "ms", 1e3),
    Output("current_A", "A", "coil current of a torque-curve point", "current"),
    Output("torque_N_m", "N·m", "clutch torque (yield + viscous) at a torque-curve point",
           "torque"),
    Output("speed_rpm", "rpm", "slip speed of the torque curve (input speed)", "speed"),
    # ---- at the hand (the haptic model's metrics) ----------------------------------
    Output("m1_kg", "kg", "actuator-side mass at the hand (Eq. 3)", "m1", "g", 1e3),
    Output("m2_kg", "kg", "end-effector mass at the hand", "m2", "g", 1e3),
    Output("b1_N_s_per_m", "N·s/m", "actuator-side damping at the hand (Eq. 3)", "b1"),
    Output("k_N_per_m", "N/m", "transmission stiffness", "k"),
    Output("b_N_s_per_m", "N·s/m", "transmission damping", "b"),
    Output("K_N_per_m", "N/m", "rendered virtual stiffness (by the design's [render] rule: "
           "by default the MR pair's K_max; mrclutch.verdict)", "K rendered"),
    Output("K_max_N_per_m", "N/m", "the MR pair's K_max = F_max / workspace (Eq. 4-5), "
           "whatever K is rendered", "K_max"),
    Output("delay_s", "s", "actuator delay in the loop", "delay", "ms", 1e3),
    Output("bandwidth_lumped_hz", "Hz", "rendering bandwidth √(K/(m1+m2))/2π (Eq. 1)",
           "bandwidth, lumped √(K/m)"),
    Output("bandwidth_hz", "Hz", "rendering bandwidth: first frequency where the "
           "effective stiffness turns negative (full 2-DOF response)",
           "bandwidth, full response"),
    Output("resonance_hz", "Hz", "system (transmission) resonance (empty/NaN: none, the "
           "free lever is overdamped: every zero of Eq. 2 is real)", "system resonance"),
    Output("rendering_area_dB_decade", "dB·decade", "area between the rendered and the "
           "ideal impedance over 1–1000 Hz (Fig. 7)", "rendering area"),
    Output("passive", "", "passive at the rendered K (delay included)", "passive at K"),
    Output("max_passive_K_N_per_m", "N/m", "largest K rendered passively",
           "largest passive K"),
    Output("max_stable_K_N_per_m", "N/m", "largest K rendered stably (delay included)",
           "largest stable K"),
    Output("backdrive_force_N", "N", "peak force felt moving the lever with nothing "
           "rendered (K = 0), ±10 mm at 2 Hz: |Z_p(jω)|·ω·X (mrclutch.haptics.hand)",
           "backdrive force", "mN", 1e3),
    Output("max_stable_K_worst_N_per_m", "N/m", "worst case of the largest stable K over "
           "the design's uncertain inputs (mrclutch.robust, docs/verdicts.md)",
           "largest stable K, worst case"),
    Output("max_passive_K_worst_N_per_m", "N/m", "worst case of the largest passive K over "
           "the design's uncertain inputs (mrclutch.robust, docs/verdicts.md)",
           "largest passive K, worst case"),
    Output("bandwidth_worst_hz", "Hz", "worst case of the full-response bandwidth at K_max "
           "over the design's uncertain inputs (mrclutch.robust, docs/verdicts.md)",
           "bandwidth, worst case"),
    Output("zwidth_area_N2_s_per_m2", "N²·s/m²", "area of the Z-width: virtual (K, B) "
           "rendered passively (mrclutch.haptics.zwidth)", "Z-width area"),
    # ---- issue 41: what the hand feels of the steel's memory and of the runout --------
    Output("residual_torque_N_m", "N·m", "yield torque left at 0 A after the current limit: "
           "the steel's coercive current through the network (mrclutch.feel, "
           "docs/hysteresis.md)", "residual torque", "mN·m", 1e3),
    Output("hysteresis_width_pct", "%", "widest gap between the falling and the rising "
           "torque–current branches, % of the yield torque at the current limit "
           "(mrclutch.feel)", "hysteresis loop width"),
    Output("ripple_torque_N_m", "N·m", "half peak-to-peak torque ripple at the slip "
           "frequency from the [process] runout (mrclutch.feel, magnetics.ripple)",
           "runout ripple", "mN·m", 1e3),
    Output("ripple_force_N", "N", "the runout ripple at the hand, T·nG/l (mrclutch.feel)",
           "runout ripple at the hand", "mN", 1e3),
    # ---- issue 41: how long the fluid lasts (mrclutch.duty, magnetics.life) -------------
    Output("fluid_volume_m3", "m³", "MR fluid the clutch holds: films, face films and cavity "
           "(magnetics.life)", "fluid volume", "mL", 1e6),
    Output("fluid_life_h", "h", "hours until the fluid has dissipated its lifetime energy "
           "(LDE, unverified per fluid) at the design's [duty] (mrclutch.duty)", "fluid life"),
    # ---- issue 41 item 3: hot torque and b1 (mrclutch.duty, magnetics.hot) ------------
    Output("hot_peak_torque_N_m", "N·m", "torque at the end of the hot peak hold: the "
           "current limit held slipping for the [duty] peak_time_s, the temperatures fed "
           "back into R(T), η(T) and τy(T) (mrclutch.duty, docs/hot.md)", "hot peak torque"),
    Output("hot_peak_b1_N_s_per_m", "N·s/m", "b1 at the hand at the end of the hot peak "
           "hold (the films at η(T); mrclutch.duty)", "hot peak b1"),
    Output("duty_end_torque_N_m", "N·m", "torque at the end of the [duty] hold "
           "(torque_N_m for time_s); NaN without a duty torque (mrclutch.duty)",
           "torque after the duty"),
    Output("duty_end_b1_N_s_per_m", "N·s/m", "b1 at the hand at the end of the [duty] "
           "hold; NaN without a duty torque (mrclutch.duty)", "b1 after the duty"),
)  # fmt: skip

#: Every output, by key.
OUTPUTS: Mapping[str, Output] = MappingProxyType({o.key: o for o in _ALL})

#: The clutch figures a person reads first (evaluate's table and the report).
CLUTCH_ROWS: tuple[str, ...] = (
    "max_torque_N_m",
    "max_current_A",
    "rotor_inertia_kg_m2",
    "rotor_mass_kg",
    "clutch_mass_kg",
    "fluid_inertia_kg_m2",
    "drag_damping_N_m_s",
    "off_state_torque_N_m",
    "dynamic_range_dB",
    "torque_per_inertia_N_m_per_kg_m2",
    "coil_resistance_ohm",
    "coil_power_W",
    "continuous_current_A",
    "continuous_torque_N_m",
    "time_to_wire_limit_s",
    "time_to_fluid_limit_s",
    "thermal_time_constant_s",
)
#: The haptic metrics compared side by side, MR pair against the motor.
HAND_ROWS: tuple[str, ...] = (
    "m1_kg",
    "b1_N_s_per_m",
    "m2_kg",
    "k_N_per_m",
    "K_N_per_m",
    "bandwidth_lumped_hz",
    "bandwidth_hz",
    "resonance_hz",
    "rendering_area_dB_decade",
    "passive",
    "max_passive_K_N_per_m",
    "max_stable_K_N_per_m",
)
#: Columns of a sweep row, in order (fast path; the ``SWEEP_OPTIONAL`` ones follow where
#: asked for).
SWEEP_COLUMNS: tuple[str, ...] = (
    "valid",
    "rotor_inertia_kg_m2",
    "rotor_mass_kg",
    "clutch_mass_kg",
    "diameter_m",
    "length_m",
    "max_torque_N_m",
    "torque_error_bound",
    "fluid_inertia_kg_m2",
    "drag_damping_N_m_s",
    "off_state_torque_N_m",
    "dynamic_range_dB",
    "continuous_torque_N_m",
    "torque_delay_s",
    "m1_kg",
    "b1_N_s_per_m",
    "K_N_per_m",
    "bandwidth_lumped_hz",
    "bandwidth_hz",
    "resonance_hz",
    "rendering_area_dB_decade",
    "backdrive_force_N",
)

#: Sweep columns computed only when asked for (``evaluate_batch`` flags, ``sweep --with``),
#: each with its cost relative to the default row (docs/sweeps.md).
SWEEP_OPTIONAL: tuple[str, ...] = (
    "max_passive_K_N_per_m",  # about ×1.7
    "max_stable_K_N_per_m",  # the batch D-subdivision (mrclutch.robust_search)
    "zwidth_area_N2_s_per_m2",  # about ×7
    # over the uncertain inputs (mrclutch.robust.RobustBatchEvaluator; benchmarks/bench_robust.py)
    "max_stable_K_worst_N_per_m",
    "max_passive_K_worst_N_per_m",
    "bandwidth_worst_hz",
    # issue 41 (mrclutch.feel.feel_batch): the residual torque and loop about ×1.3, the
    # ripple's gap curvature two more network solves
    "residual_torque_N_m",
    "hysteresis_width_pct",
    "ripple_torque_N_m",
    "ripple_force_N",
    # issue 41 (mrclutch.duty.duty_batch): the fluid's volume and life, no solve
    "fluid_volume_m3",
    "fluid_life_h",
    # issue 41 item 3 (mrclutch.hot_rows.hot_batch): the hot peak and duty holds (two
    # thermal marches of 300 steps, every design of a fluid at once)
    "hot_peak_torque_N_m",
    "hot_peak_b1_N_s_per_m",
    "duty_end_torque_N_m",
    "duty_end_b1_N_s_per_m",
)


def output(key: str) -> Output:
    """The output named ``key``; KeyError names the known keys."""
    try:
        return OUTPUTS[key]
    except KeyError:
        raise KeyError(f"no output named {key!r}; known: {', '.join(OUTPUTS)}") from None


def format_kmax(value: float, source: str) -> str:
    """K_max as every command prints it: the value and, in brackets, where it comes from
    (Table 2 / Table 1 catalogue / fast model / reference model / measured), so two
    commands that differ say why."""
    return f"K_max {value:.4g} N/m [{source}]"


def row_label(key: str) -> str:
    """``label (display unit)`` for a table row."""
    o = output(key)
    return f"{o.label} ({o.shown_unit})" if o.shown_unit else o.label


def describe(keys: tuple[str, ...] | list[str]) -> dict[str, dict[str, str]]:
    """Unit and meaning of each key (the sweep's ``.meta.json`` ``columns`` entry)."""
    return {k: {"unit": output(k).unit, "description": output(k).description} for k in keys}
