"""The coil's current amplifier (supply voltage, current-loop bandwidth) and the most current
its supply holds through the coil: a design's input, apart from the torque response that
reads it (``magnetics.dynamics``), so that a design loads without the circuit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.validation import check_range
from magnetics.thermal import coil_resistance


@dataclass(frozen=True)
class Amplifier:
    """The coil's current amplifier (SI). Defaults: a typical 24 V linear/PWM current
    amplifier for small actuators, its current loop closed at 2 kHz; its current limit is
    the design's ``Operating.max_current``."""

    supply_voltage: float = 24.0  # V
    current_bandwidth_hz: float = 2000.0  # Hz, −3 dB of the current loop (first order)

    def __post_init__(self) -> None:
        check_range("supply_voltage", self.supply_voltage, 0.0, 1e4, " V", lo_open=True)
        # a current loop slower than 10 Hz is no haptic amplifier (its lag alone would be
        # 16 ms); 10 MHz stands for an ideal (instant) loop
        check_range("current_bandwidth_hz", self.current_bandwidth_hz, 10.0, 1e7, " Hz")

    @property
    def time_constant(self) -> float:
        """s: τ_a = 1/(2π f_c), the small-signal current loop."""
        return 1.0 / (2 * math.pi * self.current_bandwidth_hz)


def supply_current(
    fields: Mapping[str, Any],
    stations: Mapping[str, Any],
    amplifier: Amplifier,
    coil_temperature: ArrayLike = 20.0,
) -> NDArray[np.float64]:
    """A: the largest current the amplifier holds through the coil, V/R (Ohm's law; R at
    ``coil_temperature`` °C, ``thermal.coil_resistance``) from the design's fields and
    stations (``geometry.regions.stations``; floats or arrays). Above it the voltage-limited
    current tends to V/R and never reaches the command: a design's current limit is capped
    here (``mrclutch.design.current_limit``)."""
    res = coil_resistance(fields, stations["coil_in"], stations["coil_out"], coil_temperature)
    return np.asarray(amplifier.supply_voltage / np.asarray(res, float))
