"""The hot corner of ``[uncertainty]`` from the thermal model (issue 41, item 3).

A design file may ask for its fluid temperature range from its duty instead of typing it::

    [uncertainty]
    fluid_temperature_C = "duty"   # [operating T, the fluid's T at the end of the duty hold]

The range's hot end is then the fluid node's temperature at the end of the design's duty
hold (``mrclutch.duty``: the thermal network marched with R(T), η(T) and τy(T) fed back,
``magnetics.hot``): the duty torque held for ``time_s`` where ``[duty] torque_N_m`` > 0,
else the current limit held for ``peak_time_s`` (the hot peak). The cold end is the
operating temperature (where the nominal verdict is computed); the hot end is capped at
the fluid's upper limit, as the default range is. A typed range stays possible (and is
what every design without ``"duty"`` uses); ``evaluate`` says which one it used
(``mrclutch.uncertainty.range_from``).

What it assumes (docs/hot.md): the clutch starts the duty at ambient temperature and the
hold's end is its hottest point (a repeated duty that never cools between holds is hotter:
type the range then). A sweep's or an optimiser's hand box (``mrclutch.hand_box``) takes
each row's own hot end, the end of that design's duty hold (``mrclutch.hot_rows.
duty_hot_ends``: every row marched at once, the same figure as ``duty_end_temperature`` of
the row's design); the base design's resolved range is what :func:`resolved_ranges` reports.
"""

from __future__ import annotations

import functools
from dataclasses import replace
from typing import Any

import numpy as np

from geometry.section import build_section
from magnetics.hot import march
from magnetics.materials import FLUIDS
from magnetics.torque import torque_curve
from mrclutch.duty import GRID, STEPS, context, design_duty, duty_load, peak_load
from mrclutch.uncertainty import Uncertainty, default_uncertainty


def duty_end_temperature(design: Any) -> tuple[float, str]:
    """(°C, which hold) of ``design`` (a ``ClutchDesign``): the fluid node's temperature at
    the end of its duty hold (the duty torque for ``time_s``; without one, the current
    limit for ``peak_time_s``), the same march as ``mrclutch.duty.evaluation_duty``'s."""
    op = design.operating
    duty = design_duty(design)
    section = build_section(design.clutch, design.materials)
    limit = float(design.current_limit)
    currents = np.linspace(0.0, limit, GRID)
    curve = torque_curve(section, currents, method="network", speed_rpm=op.input_speed_rpm,
                         support=design.support)  # fmt: skip
    fluid_limit = FLUIDS[design.materials.fluid].temperature_range[1]
    ctx = context(section.table, currents, curve.yield_torque, limit, op.input_speed,
                  design.support, design.amplifier, op.ambient_temperature, fluid_limit,
                  op.wire_temperature_limit, op.fluid_temperature)  # fmt: skip
    if duty.torque > 0:
        load, seconds, which = duty_load(ctx, duty.torque), duty.time, "duty"
    else:
        load, seconds, which = peak_load(ctx), duty.peak_time, "peak"
    return float(march(ctx.net, load, seconds, STEPS).final[1]), which


def duty_range(operating_temperature: float, end_temperature: float,
               fluid_range: tuple[float, float]) -> tuple[float, float]:  # fmt: skip
    """(low, high) °C: the operating temperature to the duty's end temperature, the hot
    end capped at the fluid's limit and never below the cold one (a duty that cools the
    fluid below its operating temperature leaves the range a point)."""
    hi = min(max(end_temperature, operating_temperature), fluid_range[1])
    return operating_temperature, max(hi, operating_temperature)


@functools.lru_cache(maxsize=64)
def resolved_ranges(design: Any) -> Uncertainty:
    """``design``'s ranges with the fluid temperature range resolved: its ``[uncertainty]``
    (or the defaults), and where that says ``"duty"``, :func:`duty_range` of the duty's end
    temperature (cached per design: ``ClutchDesign`` is frozen and hashable)."""
    unc = design.uncertainty
    if unc is None:
        return default_uncertainty(design)
    if unc.fluid_temperature_from != "duty":
        return unc
    t_end, _ = duty_end_temperature(design)
    t_op = float(design.operating.fluid_temperature)
    fl = FLUIDS[design.materials.fluid]
    return replace(unc, fluid_temperature=duty_range(t_op, t_end, fl.temperature_range))
