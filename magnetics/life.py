"""Fluid life: the fluid's volume and the hours until it has dissipated its lifetime energy.

MR fluids wear with the energy dissipated in them per unit volume: past the *lifetime
dissipated energy* (LDE, J/m³) the fluid thickens in use until it is an unworkable paste
[durability2022]. A clutch slipping at ω with torque T dissipates T·ω in its fluid, so at a
mean power P̄ a fluid of volume V lasts

    life = LDE · V / P̄  (s),

with P̄ = f T_on ω + (1 − f) T_off ω for a duty that holds T_on a fraction f of the time and
leaves the clutch off (its drag T_off, the motor still running) otherwise. The volume is
every fluid region of the section (the films, the end-face films and the cavity), the
fluid the clutch is filled with. The LDE is the fluid's (``MRFluid.lifetime_energy``, its
data file, with its source; unverified where it was not read for that fluid). Assumes the
wear depends on the energy alone, not on how fast it is dissipated nor on the field (the
LDE literature's own assumption [durability2022]; the Mason number changes it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from geometry.regions import Regions
from geometry.validation import check_nonnegative, check_range

SECONDS_PER_HOUR = 3600.0


def fluid_volume(rg: Regions) -> Any:
    """m³ of fluid in the designs of ``rg`` (floats or arrays): Σ π (r1² − r0²)(z1 − z0)
    over its fluid regions."""
    total: Any = 0.0
    for sp in rg:
        if sp.part != "fluid":
            continue
        r0, r1, z0, z1 = rg.bounds(sp)
        total = total + np.pi * (r1**2 - r0**2) * (z1 - z0)
    return total


def mean_power(on_torque: Any, off_torque: Any, slip_speed: float, on_fraction: float) -> Any:
    """W: f T_on ω + (1 − f) T_off ω (module docstring)."""
    check_range("on_fraction", on_fraction, 0.0, 1.0)
    check_nonnegative("slip_speed", slip_speed, " rad/s")
    return (on_fraction * np.asarray(on_torque) + (1 - on_fraction) * np.asarray(off_torque)
            ) * slip_speed  # fmt: skip


def life_hours(volume: Any, power: Any, lifetime_energy: float | None) -> Any:
    """Hours until ``volume`` m³ of fluid has dissipated ``lifetime_energy`` J/m³ at
    ``power`` W: LDE·V/P/3600 (inf at no power; NaN with no LDE)."""
    if lifetime_energy is None:
        return math.nan if np.ndim(volume) == 0 else np.full(np.shape(volume), np.nan)
    p = np.asarray(power, dtype=float)
    with np.errstate(divide="ignore"):
        out = lifetime_energy * np.asarray(volume) / p / SECONDS_PER_HOUR
    return float(out) if np.ndim(out) == 0 else out
