"""The operating point of a design: the current limit and what caps it, the input speed,
the delay and its source, the temperatures (``Operating``, the ``[operating]`` table of a
design file, mrclutch.design), and ``current_limit``: max_current capped by the current
density in the copper and by the amplifier's supply, on floats or arrays of designs."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry.materials import MRF
from geometry.validation import check_choice, check_positive, check_range
from magnetics.drag import ROOM_TEMPERATURE
from magnetics.materials import FLUIDS
from magnetics.thermal import adiabatic_current_density
from mrclutch.haptics.actuator import MR_DELAY

#: Largest actuator delay accepted (s): beyond it no haptic loop renders anything.
MAX_DELAY = 1.0
#: rad/s: the slowest input speed accepted (``Operating.__post_init__``).
MIN_INPUT_SPEED = 1e-6
#: Where the haptic model's actuator delay comes from (``Operating.delay_source``).
DELAY_SOURCES: tuple[str, ...] = ("fixed", "geometry")


@dataclass(frozen=True)
class Operating:
    """Operating limits and conditions (SI; temperature in °C)."""

    max_current: float = 7.0  # A: Fig. 2b's range
    #: A/m² in the copper; None = the IEC 60949 adiabatic limit for ``peak_duration``
    #: from ``coil_temperature`` to ``wire_temperature_limit``; inf = no limit
    max_current_density: float | None = None
    input_speed: float = 530 * 2 * math.pi / 60  # rad/s: Fig. 2b's 530 rpm
    delay: float = MR_DELAY  # s: paper §IV-B, 1 ms for MR actuators
    coil_temperature: float = 20.0  # °C, for the coil's resistance at the peak current
    fluid_temperature: float = ROOM_TEMPERATURE  # °C, sets the fluid's viscosity
    ambient_temperature: float = 20.0  # °C, air around the clutch
    wire_temperature_limit: float = 155.0  # °C: magnet wire of thermal class 155 [iec60085]
    peak_duration: float = 1.0  # s the peak current is held (sets the default J limit)
    #: "fixed": the haptic model uses ``delay``; "geometry": the torque response's
    #: equivalent delay from the design (magnetics.dynamics; docs/dynamics.md)
    delay_source: str = "fixed"

    def __post_init__(self) -> None:
        check_choice("delay_source", self.delay_source, DELAY_SOURCES)
        check_range("max_current", self.max_current, 0.0, 1e4, " A", lo_open=True)
        j = self.max_current_density
        if j is not None and not (math.isinf(j) and j > 0):
            check_positive("max_current_density", j, " A/m²")
        # 1e-6 rad/s (1e-5 rpm, a turn in 12 days) is the slowest input: nearer 0 the drag
        # figures underflow and the stability search finds no scale (1e-300 rpm, issue 32)
        check_range("input_speed", self.input_speed, MIN_INPUT_SPEED, 1e5, " rad/s")
        check_range("delay", self.delay, 0.0, MAX_DELAY, " s")
        check_range("coil_temperature", self.coil_temperature, -60.0, 250.0, " °C")
        lo, hi = FLUIDS[MRF].temperature_range
        check_range("fluid_temperature", self.fluid_temperature, lo, hi, " °C")
        check_range("ambient_temperature", self.ambient_temperature, -40.0, 100.0, " °C")
        check_range("wire_temperature_limit", self.wire_temperature_limit,
                    max(self.ambient_temperature, self.coil_temperature), 300.0, " °C",
                    lo_open=True)  # fmt: skip
        check_range("peak_duration", self.peak_duration, 0.0, 1e4, " s", lo_open=True)

    @property
    def current_density_limit(self) -> float:
        """A/m²: ``max_current_density``, or by default the IEC 60949 adiabatic limit."""
        if self.max_current_density is not None:
            return self.max_current_density
        return float(adiabatic_current_density(self.peak_duration, self.coil_temperature,
                                               self.wire_temperature_limit))  # fmt: skip

    @property
    def input_speed_rpm(self) -> float:
        return self.input_speed * 60 / (2 * math.pi)


def current_limit(operating: Operating, wire_diameter: Any, supply: Any = math.inf) -> Any:
    """max_current capped by the current-density limit in the copper and by ``supply``
    (A, the amplifier's V/R: ``magnetics.amplifier.supply_current``) (floats or arrays)."""
    # batches hold rows that valid() refused (a 1e150 m wire): their area may overflow to
    # inf, which caps nothing; those rows' currents are never used
    with np.errstate(over="ignore"):
        wire_area = math.pi * np.asarray(wire_diameter, dtype=float) ** 2 / 4
        cap = np.minimum(operating.current_density_limit * wire_area, supply)
        return np.minimum(operating.max_current, cap)
