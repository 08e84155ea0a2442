"""What the hand feels after a duty and how long the fluid lasts (issue 41, items 3–5).

A design's ``[duty]`` (or ``--duty NM:S`` on the command line) states how it is used:

* ``torque_N_m`` held slipping at the input speed (yield + drag) for ``time_s`` — the duty
  of docs/optimize.md (0: none);
* ``peak_time_s``: how long the current limit is held for the hot peak figures (30 s);
* ``on_fraction``: the share of its life the clutch holds that torque (the rest off, its
  drag at the input speed), for the fluid's life; 0.25 by default, the paper's 25 % duty
  rule for rated torque [lebel].

From the thermal network (``magnetics.thermal``) marched with the temperatures fed back
(``magnetics.hot``): the coil's R(T) in its Joule heat and in the amplifier's V/R cap, the
fluid's η(T) in the drag and its τy(T) in the yield torque. At the end of the hold: the
current, the node temperatures, the torque, b1 at the hand (the films' damping at η(T))
and the verdict at the rendered K (passive or not with that b1). The fluid: its volume and
its life at the stated duty (``magnetics.life``).

The yield torque against current is the network's (the default torque model) at 20 °C on
a grid of currents, scaled by τy(T)/τy(20 °C): the field in the gap is taken as the cold
one (the fluid's B–H is not made temperature-dependent).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from geometry import regions
from geometry.params import INT_RANGES, valid
from geometry.regions import Regions
from geometry.validation import ParameterError
from magnetics import thermal
from magnetics.amplifier import Amplifier, supply_current
from magnetics.drag import Support, drag_terms, totals
from magnetics.hot import Load, march, tau_y_coefficient, tau_y_factor
from magnetics.life import fluid_volume, life_hours, mean_power
from magnetics.materials import FLUIDS
from mrclutch.batch import batch_fields
from mrclutch.design_network import network_yield, section_network
from mrclutch.duty_spec import Duty
from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.model import passivity_batch
from mrclutch.uncertainty import Uncertainty, range_from

#: Steps of the thermal march over a hold (the feedback lags one step).
STEPS = 300
#: Currents of the cold yield-torque grid (0 to the current limit).
GRID = 17


def parse_duty(text: str, base: Duty | None = None) -> Duty:
    """``--duty NM:S`` (N·m held for S seconds) on top of ``base``; ParameterError names it."""
    torque, sep, seconds = text.partition(":")
    try:
        t, s = float(torque), float(seconds)
    except ValueError:
        raise ParameterError(f"--duty {text!r}: give NM:S, e.g. 0.2:60") from None
    if not sep:
        raise ParameterError(f"--duty {text!r}: give NM:S, e.g. 0.2:60")
    try:
        return replace(base if base is not None else Duty(), torque=t, time=s)
    except ParameterError as e:
        raise ParameterError(f"--duty {text!r}: {e}") from None


@dataclass(frozen=True)
class Context:
    """What a hold needs of one design (SI): its region table, thermal network, fluid, the
    cold yield torque on a grid of currents, the current limit and the operating point."""

    rg: Regions
    net: thermal.Network
    fluid_name: str
    currents: np.ndarray
    yield_cold: np.ndarray
    current_limit: float
    slip_speed: float
    amplifier: Amplifier
    film_per_viscosity: float  # N·m·s per Pa·s: the films' damping is η × this
    rest_torque: float  # N·m: bearings and seal (no fluid viscosity in them)
    rest_damping: float  # N·m·s: the bearings' rolling slope
    wire_limit: float  # °C, the magnet wire's
    #: °C: the operating fluid temperature, at which the pair's b1 (``hold``'s ``mr``) was
    #: taken; a hold's b1 moves by the films' damping from there to its own temperature
    fluid_temperature: float = 20.0


def drag_at(ctx: Context, temperature: float) -> tuple[float, float, float]:
    """(off-state torque N·m, damping N·m·s, η Pa·s) at fluid ``temperature`` (°C),
    clipped to the fluid's range: the films' terms are linear in η(T)
    (``magnetics.drag.film_coefficients``), the bearings' and the seal's do not see it."""
    fl = FLUIDS[ctx.fluid_name]
    lo, hi = fl.temperature_range
    eta = float(fl.viscosity_at(float(np.clip(temperature, lo, hi))))
    films = ctx.film_per_viscosity * eta
    return ctx.rest_torque + films * ctx.slip_speed, ctx.rest_damping + films, eta


def supply_at(ctx: Context, coil_temperature: float) -> float:
    """A: the most the amplifier holds through the coil at ``coil_temperature`` (V/R(T))."""
    return float(supply_current(ctx.rg.fields, ctx.rg.at, ctx.amplifier, coil_temperature))


def torque_at(ctx: Context, current: float, temps: np.ndarray) -> float:
    """N·m at ``current`` and node temperatures (coil, fluid, housing): τy(T)/τy0 × the
    cold yield torque + the drag at η(T)."""
    f = float(tau_y_factor(FLUIDS[ctx.fluid_name], temps[1]))
    return f * float(np.interp(current, ctx.currents, ctx.yield_cold)) + drag_at(ctx, temps[1])[0]


def peak_load(ctx: Context) -> Any:
    """The load of a held current limit: I = min(limit, V/R(T_coil)), slip power T·ω."""

    def load(temps: np.ndarray) -> Load:
        i = min(ctx.current_limit, supply_at(ctx, temps[0]))
        return Load(i, torque_at(ctx, i, temps) * ctx.slip_speed)

    return load


def duty_current(ctx: Context, torque: float, temps: np.ndarray) -> float:
    """A: the current that holds ``torque`` at these temperatures (the cold yield curve
    inverted at (T − drag)/factor), capped at the current limit and the supply."""
    f = float(tau_y_factor(FLUIDS[ctx.fluid_name], temps[1]))
    need = max(torque - drag_at(ctx, temps[1])[0], 0.0) / f
    i = float(np.interp(need, ctx.yield_cold, ctx.currents))  # the yield is increasing in I
    return min(i, ctx.current_limit, supply_at(ctx, temps[0]))


def duty_load(ctx: Context, torque: float) -> Any:
    """The load of a held torque (the current follows τy(T) and the drag)."""

    def load(temps: np.ndarray) -> Load:
        i = duty_current(ctx, torque, temps)
        return Load(i, torque_at(ctx, i, temps) * ctx.slip_speed)

    return load


def hold(ctx: Context, load: Any, seconds: float, mr: HapticParams, reduction: float,
         k: float) -> dict[str, Any]:  # fmt: skip
    """The state after ``seconds`` of ``load``: current, temperatures, torque, η, the τy
    factor, b1 at the hand (the cold pair's b1 + the films' change of damping, both
    clutches: 2 r² Δc, Eq. 3) and the verdict at ``k`` with that b1."""
    m = march(ctx.net, load, seconds, STEPS)
    temps = m.final
    i = float(load(temps).current)
    fl = FLUIDS[ctx.fluid_name]
    lo, hi = fl.temperature_range
    _, damp_cold, _ = drag_at(ctx, ctx.fluid_temperature)  # where mr.b1 was taken
    off, damp, eta = drag_at(ctx, temps[1])
    b1 = float(mr.b1) + 2 * reduction**2 * (damp - damp_cold)
    # the verdict's passivity at k with that b1 (metrics_of's, without its other metrics)
    verdict = passivity_batch(HapticParams.stack([replace(mr, b1=b1)]), np.array([float(k)]))
    return {
        "time_s": seconds,
        "current_A": i,
        "coil_temperature_C": float(temps[0]),
        "fluid_temperature_C": float(temps[1]),
        "housing_temperature_C": float(temps[2]),
        "beyond_fluid_range": bool(not lo <= temps[1] <= hi),
        "beyond_wire_limit": bool(temps[0] > ctx.wire_limit),
        "tau_y_factor": float(tau_y_factor(fl, temps[1])),
        "viscosity_Pa_s": eta,
        "torque_N_m": torque_at(ctx, i, temps),
        "off_state_torque_N_m": off,
        "b1_N_s_per_m": b1,
        "passive": bool(verdict["passive"][0]),
        "max_passive_K_N_per_m": float(verdict["max_passive_K_N_per_m"][0]),
    }


def context(rg: Regions, currents: np.ndarray, yield_cold: np.ndarray, current_limit: float,
            slip_speed: float, support: Support, amplifier: Amplifier, ambient: float,
            fluid_limit: float, wire_limit: float, fluid_temperature: float = 20.0
            ) -> Context:  # fmt: skip
    """A hold's context for one design (``rg`` on floats)."""
    fl = FLUIDS[rg.materials.fluid]
    terms = drag_terms(rg, slip_speed, fl.viscosity_temperature, support, fl)
    films = ("drum gaps", "end faces")
    per_eta = sum(float(terms[n].damping) for n in films) / fl.viscosity  # at its own T_ref
    rest = {k: v for k, v in terms.items() if k not in films}
    rest_torque, rest_damping = totals(rest)
    return Context(rg, thermal.network(rg, ambient, fluid_limit), fl.name,
                   np.asarray(currents, float),
                   np.maximum.accumulate(np.asarray(yield_cold, float)), current_limit,
                   slip_speed, amplifier, per_eta, float(rest_torque),
                   float(rest_damping), wire_limit, fluid_temperature)  # fmt: skip


def duty_figures(ctx: Context, duty: Duty, mr: HapticParams, reduction: float, k: float,
                 peak_torque: float) -> dict[str, Any]:  # fmt: skip
    """The hot peak hold, the duty hold (None without a duty torque) and the fluid's life
    (module docstring)."""
    fl = FLUIDS[ctx.fluid_name]
    peak = hold(ctx, peak_load(ctx), duty.peak_time, mr, reduction, k)
    at_duty = None
    if duty.torque > 0:
        at_duty = hold(ctx, duty_load(ctx, duty.torque), duty.time, mr, reduction, k)
        at_duty["torque_asked_N_m"] = duty.torque
        at_duty["held"] = bool(at_duty["torque_N_m"] >= duty.torque * (1 - 1e-3))
    off, _, _ = drag_at(ctx, 20.0)
    on = duty.torque if duty.torque > 0 else peak_torque
    volume = float(fluid_volume(ctx.rg))
    power = float(mean_power(on, off, ctx.slip_speed, duty.on_fraction))
    coef = tau_y_coefficient(fl)
    return {
        "peak": peak,
        "duty": at_duty,
        "tau_y_coefficient_per_K": coef,
        "fluid": {
            "volume_m3": volume,
            "lifetime_energy_J_per_m3": fl.lifetime_energy,
            "on_torque_N_m": on,
            "on_fraction": duty.on_fraction,
            "mean_power_W": power,
            "life_h": life_hours(volume, power, fl.lifetime_energy),
            "life_off_h": life_hours(volume, off * ctx.slip_speed, fl.lifetime_energy),
        },
    }


def duty_json(fig: Mapping[str, Any]) -> dict[str, Any]:
    """``duty_figures`` as JSON (the volume also in mL, the unit a builder fills with)."""
    out = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in fig.items()}
    out["fluid"]["volume_mL"] = out["fluid"]["volume_m3"] * 1e6
    return out


def design_context(design: Any, current_limit: float) -> Context:
    """A hold's ``Context`` of one ``ClutchDesign`` at its current limit (A): its section,
    the network's cold yield torque on ``GRID`` currents from 0 to the limit, its
    operating point; what ``evaluation_duty`` and the sweep's hot columns both hold."""
    op = design.operating
    section, net = section_network(design.clutch, design.materials)  # evaluate's network
    currents = np.linspace(0.0, current_limit, GRID)
    limit = FLUIDS[design.materials.fluid].temperature_range[1]  # as clutch.fluid_limit
    return context(section.table, currents, network_yield(section, net, currents), current_limit,
                   op.input_speed, design.support, design.amplifier, op.ambient_temperature,
                   limit, op.wire_temperature_limit, op.fluid_temperature)  # fmt: skip


def evaluation_duty(ev: Any, ranges: Uncertainty) -> dict[str, Any]:
    """``duty_figures`` of an evaluation (``mrclutch.pipeline.Evaluation``: its design,
    clutch figures and MR pair, at its rendered K), as JSON (``duty_json``), with the
    duty it was computed for; ``ranges``: the design's resolved ranges
    (``mrclutch.hot_range.resolved_ranges``), for its hot corner."""
    design, fig, mr = ev.design, ev.clutch, ev.mr
    duty = design_duty(design)
    ctx = design_context(design, fig.max_current)
    k = float(ev.haptic["K_N_per_m"])
    out = duty_json(duty_figures(ctx, duty, mr, design.transmission.reduction, k,
                                 fig.max_torque))  # fmt: skip
    out["asked"] = {"torque_N_m": duty.torque, "time_s": duty.time,
                    "peak_time_s": duty.peak_time, "on_fraction": duty.on_fraction}  # fmt: skip
    out["hot_corner"] = hot_corner(design, out["duty"], ranges)
    r2 = 2 * design.transmission.reduction**2  # both clutches of the pair, Eq. 3
    terms = fig.drag.terms
    warm = None if out["duty"] is None else out["duty"]["b1_N_s_per_m"] - float(mr.b1)
    out["b1_budget"] = b1_budget(
        r2 * sum(float(t.damping) for n, t in terms.items() if n != "seal"),
        r2 * float(terms["seal"].damping),
        float(design.support.seal_torque),
        warm,
    )
    return out


def hot_corner(design: Any, at_duty: Mapping[str, Any] | None, ranges: Uncertainty
               ) -> dict[str, Any]:  # fmt: skip
    """The ``[uncertainty]`` fluid-temperature range (of ``ranges``, the design's resolved
    ranges: ``mrclutch.hot_range.resolved_ranges``) beside what the thermal model gives at
    the end of the duty hold: ``covered`` False where the duty warms the fluid past the
    range's hot end (the range's verdicts then miss the duty's; widen it to the duty's
    temperature, or declare it ``"duty"``). None where no duty torque was asked.
    ``range_from``: "default", "typed" or "duty" (``mrclutch.uncertainty.range_from``)."""
    lo, hi = ranges.fluid_temperature
    src = range_from(design)
    if at_duty is None:
        return {"range_C": [lo, hi], "range_from": src, "duty_fluid_temperature_C": None,
                "covered": None}  # fmt: skip
    t = float(at_duty["fluid_temperature_C"])
    covered = bool(t <= hi + 1e-9)  # a "duty" range ends at this very temperature
    return {"range_C": [lo, hi], "range_from": src, "duty_fluid_temperature_C": t,
            "covered": covered}  # fmt: skip


def b1_budget(films: float, seal: float, seal_torque: float, warm: float | None) -> dict[str, Any]:
    """b1 at the hand [N·s/m] as the model's terms beside Table 2's identified 1.0, each
    with the share of Table 2 it explains (item 5 of issue 41; nothing fitted to Table 2):
    the drag model's films and bearings at 20 °C, the seal (Coulomb: a bias the pair
    cancels, so no damping whatever its torque), the post-yield plastic viscosity at the
    bias current (no source gives it against field: the Bingham model with the off-state η,
    so none beyond the films), and, with a duty (``warm``), the fluid warmed by its hold
    (η(T) falls: negative)."""
    paper = float(TABLE2_MR.b1)
    seal_src = (f"Coulomb, seal_torque = {seal_torque * 1e3:g} mN·m (no contact seal unless "
                "the design states one): no damping")  # fmt: skip
    plastic_src = "no source read gives it against field: the off-state η (Bingham); unverified"
    rows = [
        ("films, end faces and bearings at 20 °C", films, "magnetics.drag [white-viscous]"),
        ("seal", seal, seal_src),
        ("post-yield plastic viscosity at the bias current", 0.0, plastic_src),
    ]
    if warm is not None:
        rows.append(("fluid warmed by the duty", warm, "η(T) at the hold's end (magnetics.hot)"))
    total = sum(v for _, v, _ in rows)
    terms = [{"name": n, "value": v, "share_of_table2": v / paper, "source": s}
             for n, v, s in rows]  # fmt: skip
    return {"terms": terms, "total": total, "paper_table2": paper, "unexplained": paper - total}


def design_duty(design: Any) -> Duty:
    """The design's ``[duty]`` (``ClutchDesign.duty``), or the defaults."""
    d = getattr(design, "duty", None)
    return d if isinstance(d, Duty) else Duty()


#: The sweep's and the optimiser's columns of this module (``outputs.SWEEP_OPTIONAL``).
DUTY_COLUMNS = ("fluid_volume_m3", "fluid_life_h")


def duty_batch(fields: Mapping[str, Any], base: Any, r: Mapping[str, np.ndarray]
               ) -> dict[str, np.ndarray]:  # fmt: skip
    """``DUTY_COLUMNS`` for S designs (a sweep's fields around ``base``, a ``ClutchDesign``)
    beside ``evaluate_batch``'s ``r`` (its off-state and peak torques): the fluid's volume
    and its life at ``base``'s duty (``duty_figures``' figures on arrays). Rows that fail
    validation are NaN."""
    p, mats = batch_fields(fields, base)
    ok = valid(p) & (np.asarray(r["valid"]) == 1)
    duty = design_duty(base)
    off = np.asarray(r["off_state_torque_N_m"], float)
    on = np.full(off.shape, duty.torque) if duty.torque > 0 else np.asarray(r["max_torque_N_m"])
    power = mean_power(on, off, base.operating.input_speed, duty.on_fraction)

    def fn(rg: Regions, rows: np.ndarray) -> dict[str, np.ndarray]:
        vol = np.asarray(fluid_volume(rg), float)
        lde = FLUIDS[rg.materials.fluid].lifetime_energy
        return {"vol": vol, "life": np.asarray(life_hours(vol, power[rows], lde), float)}

    out = regions.per_topology(p, ok, fn, mats)
    return {"fluid_volume_m3": out["vol"], "fluid_life_h": out["life"]}


#: The sweep's hot columns (``outputs.SWEEP_OPTIONAL``, issue 41 item 3): the torque and
#: b1 at the end of the hot peak hold and of the duty hold (``duty_figures``' ``peak`` and
#: ``duty``).
HOT_COLUMNS = (
    "hot_peak_torque_N_m",
    "hot_peak_b1_N_s_per_m",
    "duty_end_torque_N_m",
    "duty_end_b1_N_s_per_m",
)


def hot_batch(fields: Mapping[str, Any], base: Any, r: Mapping[str, np.ndarray],
              mr: HapticParams) -> dict[str, np.ndarray]:  # fmt: skip
    """``HOT_COLUMNS`` for S designs (a sweep's fields around ``base``, a ``ClutchDesign``):
    each valid row's hold at the current limit for ``peak_time`` and, with a duty torque,
    its duty hold (NaN without one), as ``evaluation_duty`` gives them. ``r``:
    ``evaluate_batch``'s rows; ``mr``: the pair at the hand of its valid rows
    (``at_hand.mr_at_hand``). Design by design: the thermal march feeds each design's
    temperatures back into its own load at every step (``magnetics.hot.march``). The
    reference of ``mrclutch.hot_rows.hot_batch``, which the sweep runs (the same figures,
    every design of a fluid marched at once)."""
    p, mats = batch_fields(fields, base)
    ok = np.nonzero(valid(p) & (np.asarray(r["valid"]) == 1))[0]
    out = {k: np.full(np.shape(r["valid"]), np.nan) for k in HOT_COLUMNS}
    duty = design_duty(base)
    red = base.transmission.reduction
    ints = {name for name, _, _ in INT_RANGES}
    for j, i in enumerate(ok):
        clutch = replace(base.clutch, **{k: int(v[i]) if k in ints else float(v[i])
                                         for k, v in p.items()})  # fmt: skip
        m = mats if not isinstance(mats, np.ndarray) else mats[i]
        design = replace(base, clutch=clutch, materials=m)
        ctx = design_context(design, design.current_limit)
        pair = mr.item(j) if mr.shape else mr
        k = float(pair.k_max)  # the holds' torque and b1 do not depend on K
        peak = hold(ctx, peak_load(ctx), duty.peak_time, pair, red, k)
        out["hot_peak_torque_N_m"][i] = peak["torque_N_m"]
        out["hot_peak_b1_N_s_per_m"][i] = peak["b1_N_s_per_m"]
        if duty.torque > 0:
            end = hold(ctx, duty_load(ctx, duty.torque), duty.time, pair, red, k)
            out["duty_end_torque_N_m"][i] = end["torque_N_m"]
            out["duty_end_b1_N_s_per_m"][i] = end["b1_N_s_per_m"]
    return out
