"""The sweep's hot columns on arrays of designs (issue 41, item 3): the torque and b1 at the
end of the hot peak hold and of the duty hold (``mrclutch.duty.HOT_COLUMNS``), every design
of one fluid marched at once.

The same figures as ``mrclutch.duty.hot_batch`` (design by design, ``duty.hold``, the
reference): per drum count and material choice, the cold yield torque on ``duty.GRID``
currents from 0 to each design's current limit by one batched network solve
(``network_gap_torque`` on the group's region table), the drag split into the films
(∝ η(T)) and the rest, the thermal network (``group``); the groups of one fluid joined
(``merged``) and the thermal march with the R(T)/η(T)/τy(T) feedback run over all their
designs at each step (``magnetics.hot.march_batch``), the loads of ``duty.peak_load`` and
``duty.duty_load`` with the tables read row by row (``interp_rows``: ``np.interp`` per row).
``benchmarks/bench_hot_columns.py`` times the two on the same rows.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry import regions
from geometry.params import valid
from geometry.regions import Regions
from magnetics import thermal
from magnetics.amplifier import supply_current
from magnetics.drag import drag_terms, totals
from magnetics.fluid import MRFluid
from magnetics.hot import march_batch, tau_y_factor
from magnetics.materials import FLUIDS
from magnetics.network import network_from_regions
from magnetics.network.torque import network_gap_torque
from mrclutch.batch import batch_fields
from mrclutch.duty import GRID, HOT_COLUMNS, STEPS, design_duty
from mrclutch.haptics.actuator import HapticParams
from mrclutch.operating import current_limit

FloatArray = np.ndarray


def interp_rows(x: FloatArray, xp: FloatArray, fp: FloatArray) -> FloatArray:
    """``np.interp(x[k], xp[k], fp[k])`` for every row k (xp (S, G) non-decreasing rows,
    x (S,)): the last knot j with xp[j] ≤ x, linear to j + 1; the end values outside."""
    n, m = xp.shape
    j = np.clip(np.sum(xp <= x[:, None], axis=1) - 1, 0, m - 2)
    rows = np.arange(n)
    x0, x1 = xp[rows, j], xp[rows, j + 1]
    f0, f1 = fp[rows, j], fp[rows, j + 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        mid = f0 + (x - x0) * (f1 - f0) / (x1 - x0)  # linear between the knots
    out = np.where(x1 > x0, mid, f0)
    out = np.where(x <= xp[:, 0], fp[:, 0], out)
    return np.where(x >= xp[:, -1], fp[:, -1], out)


@dataclass(frozen=True)
class Group:
    """``duty.Context`` of S designs of one drum count and material choice (arrays (S,) or
    (S, G))."""

    coil: dict[str, FloatArray]  # coil_turns, wire_diameter, coil_in, coil_out (S,)
    net: thermal.Network
    fluid: MRFluid
    currents: FloatArray  # (S, G) A
    yield_cold: FloatArray  # (S, G) N·m, non-decreasing
    current_limit: FloatArray  # (S,) A
    slip_speed: float  # rad/s
    amplifier: Any
    film_per_viscosity: FloatArray  # (S,) N·m·s per Pa·s
    rest_torque: FloatArray  # (S,) N·m
    rest_damping: FloatArray  # (S,) N·m·s
    fluid_temperature: float  # °C where the pair's b1 was taken


def group(rg: Regions, base: Any) -> Group:
    """The group's ``Group`` around ``base`` (a ``ClutchDesign``: its operating point,
    support and amplifier), as ``duty.design_context`` builds each design's."""
    op, fl = base.operating, FLUIDS[rg.materials.fluid]
    supply = supply_current(rg.fields, rg.at, base.amplifier, op.coil_temperature)
    limit = np.asarray(current_limit(op, rg.fields["wire_diameter"], supply), float)
    currents = np.linspace(0.0, limit, GRID, axis=-1)
    per = network_gap_torque(network_from_regions(rg), currents, None, fl)
    terms = drag_terms(rg, op.input_speed, fl.viscosity_temperature, base.support, fl)
    films = ("drum gaps", "end faces")
    per_eta = sum(np.asarray(terms[n].damping, float) for n in films) / fl.viscosity
    rest_torque, rest_damping = totals({k: v for k, v in terms.items() if k not in films})
    size = currents.shape[0]
    coil = {k: np.broadcast_to(np.asarray(v, float), (size,)) for k, v in
            (("coil_turns", rg.fields["coil_turns"]), ("wire_diameter", rg.fields["wire_diameter"]),
             ("coil_in", rg.at["coil_in"]), ("coil_out", rg.at["coil_out"]))}  # fmt: skip
    return Group(coil, thermal.network(rg, op.ambient_temperature, fl.temperature_range[1]), fl,
                 currents, np.maximum.accumulate(per.sum(axis=-1), axis=-1), limit,
                 op.input_speed, base.amplifier, np.broadcast_to(per_eta, (size,)),
                 np.broadcast_to(np.asarray(rest_torque, float), (size,)),
                 np.broadcast_to(np.asarray(rest_damping, float), (size,)),
                 op.fluid_temperature)  # fmt: skip


def drag_at(gp: Group, temperature: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(off-state torque N·m, damping N·m·s) at fluid temperatures (S,), as
    ``duty.drag_at``: η(T) clipped to the fluid's range."""
    lo, hi = gp.fluid.temperature_range
    eta = np.asarray(gp.fluid.viscosity_at(np.clip(temperature, lo, hi)), float)
    films = gp.film_per_viscosity * eta
    return gp.rest_torque + films * gp.slip_speed, gp.rest_damping + films


def torque_at(gp: Group, current: FloatArray, temps: FloatArray) -> FloatArray:
    """N·m at the currents (S,) and node temperatures (S, 3), as ``duty.torque_at``."""
    f = np.asarray(tau_y_factor(gp.fluid, temps[:, 1]), float)
    return f * interp_rows(current, gp.currents, gp.yield_cold) + drag_at(gp, temps[:, 1])[0]


def supply_at(gp: Group, coil_temperature: FloatArray) -> FloatArray:
    """A: V/R(T) of each design at its coil temperature (``duty.supply_at``)."""
    return np.asarray(supply_current(gp.coil, gp.coil, gp.amplifier, coil_temperature))


def _rows(a: Any, size: int, tail: tuple[int, ...] = ()) -> FloatArray:
    return np.broadcast_to(np.asarray(a, float), (size, *tail))


def merged(groups: list[Group]) -> Group:
    """One ``Group`` of the rows of ``groups`` (one fluid, one operating point): the rows of
    every drum count marched together."""
    first = groups[0]
    sizes = [g.currents.shape[0] for g in groups]

    def cat(f: Callable[[Group], Any], tail: tuple[int, ...] = ()) -> FloatArray:
        return np.concatenate([_rows(f(g), n, tail) for g, n in zip(groups, sizes, strict=True)])

    net = thermal.Network(cat(lambda g: g.net.capacity, (3,)),
                          cat(lambda g: g.net.conductance, (3, 3)),
                          cat(lambda g: g.net.to_air), cat(lambda g: g.net.r20),
                          first.net.ambient, cat(lambda g: g.net.inverse, (3, 3)))  # fmt: skip
    return Group({k: cat(lambda g, k=k: g.coil[k]) for k in first.coil}, net, first.fluid,
                 cat(lambda g: g.currents, (GRID,)), cat(lambda g: g.yield_cold, (GRID,)),
                 cat(lambda g: g.current_limit), first.slip_speed, first.amplifier,
                 cat(lambda g: g.film_per_viscosity), cat(lambda g: g.rest_torque),
                 cat(lambda g: g.rest_damping), first.fluid_temperature)  # fmt: skip


Load = Callable[[FloatArray], tuple[FloatArray, FloatArray]]


def peak_load(gp: Group) -> Load:
    """``duty.peak_load`` of the group: I = min(limit, V/R(T_coil)), slip power T·ω."""

    def load(temps: FloatArray) -> tuple[FloatArray, FloatArray]:
        i = np.minimum(gp.current_limit, supply_at(gp, temps[:, 0]))
        return i, torque_at(gp, i, temps) * gp.slip_speed

    return load


def duty_load(gp: Group, torque: float) -> Load:
    """``duty.duty_load`` of the group: the current that holds ``torque`` (the cold yield
    inverted at (T − drag)/factor), capped at the limit and the supply."""

    def load(temps: FloatArray) -> tuple[FloatArray, FloatArray]:
        f = np.asarray(tau_y_factor(gp.fluid, temps[:, 1]), float)
        need = np.maximum(torque - drag_at(gp, temps[:, 1])[0], 0.0) / f
        i = interp_rows(need, gp.yield_cold, gp.currents)
        i = np.minimum(np.minimum(i, gp.current_limit), supply_at(gp, temps[:, 0]))
        return i, torque_at(gp, i, temps) * gp.slip_speed

    return load


def hold(gp: Group, load: Load, seconds: float, b1: FloatArray, reduction: float
         ) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """(torque N·m, b1 N·s/m) after ``seconds`` of ``load``, as ``duty.hold``: the pair's
    b1 plus both clutches' change of the films' damping, 2 r² Δc (Eq. 3)."""
    temps = march_batch(gp.net, load, seconds, STEPS).final
    i = load(temps)[0]
    cold = drag_at(gp, np.full(temps.shape[0], gp.fluid_temperature))[1]
    damp = drag_at(gp, temps[:, 1])[1]
    return torque_at(gp, i, temps), b1 + 2 * reduction**2 * (damp - cold)


def fluid_groups(p: Mapping[str, np.ndarray], ok: np.ndarray, mats: Any, base: Any
                 ) -> list[tuple[np.ndarray, Group]]:  # fmt: skip
    """(rows, ``Group``) per fluid: each drum count's (and material choice's) ``group``,
    those of one fluid ``merged`` to be marched together."""
    built: list[tuple[np.ndarray, Group]] = []

    def fn(rg: Regions, rows: np.ndarray) -> dict[str, np.ndarray]:
        built.append((rows, group(rg, base)))
        return {}

    regions.per_topology(p, ok, fn, mats)
    out = []
    for name in sorted({g.fluid.name for _, g in built}):
        mine = [(rows, g) for rows, g in built if g.fluid.name == name]
        out.append((np.concatenate([rw for rw, _ in mine]), merged([g for _, g in mine])))
    return out


def hot_batch(fields: Mapping[str, Any], base: Any, r: Mapping[str, np.ndarray],
              mr: HapticParams) -> dict[str, np.ndarray]:  # fmt: skip
    """``HOT_COLUMNS`` for S designs (a sweep's fields around ``base``, a ``ClutchDesign``),
    the figures of ``duty.hot_batch`` with every design of a fluid marched at once.
    ``r``: ``evaluate_batch``'s rows; ``mr``: the pair at the hand of its valid rows
    (``at_hand.mr_at_hand``)."""
    p, mats = batch_fields(fields, base)
    rated = np.asarray(r["valid"]) == 1
    ok = valid(p) & rated
    b1_all = np.broadcast_to(np.asarray(mr.b1, float), (int(rated.sum()),))
    at = np.cumsum(rated) - 1  # row → its place among the valid rows (mr's index)
    duty = design_duty(base)
    red = base.transmission.reduction
    out = {k: np.full(np.shape(r["valid"]), np.nan) for k in HOT_COLUMNS}
    if not ok.any():
        return out
    for rows, gp in fluid_groups(p, ok, mats, base):  # one march per fluid
        b1 = b1_all[at[rows]]
        for k, v in zip(HOT_COLUMNS[:2], hold(gp, peak_load(gp), duty.peak_time, b1, red),
                        strict=True):  # fmt: skip
            out[k][rows] = v
        if duty.torque > 0:
            end = hold(gp, duty_load(gp, duty.torque), duty.time, b1, red)
            for k, v in zip(HOT_COLUMNS[2:], end, strict=True):
                out[k][rows] = v
    return out


def duty_hot_ends(fields: Mapping[str, Any], base: Any, ok: np.ndarray | None = None
                  ) -> np.ndarray:  # fmt: skip
    """°C (S,): each design's own hot end of ``fluid_temperature_C = "duty"``
    (``mrclutch.hot_range``) — the fluid node's temperature at the end of ``base``'s duty
    hold (the duty torque for ``time_s``; without one, the current limit for
    ``peak_time_s``), never below the operating temperature and capped at the row's
    fluid's upper limit (``hot_range.duty_range``), every design of a fluid marched at
    once. NaN where the row is not ``ok`` (default: every valid row)."""
    p, mats = batch_fields(fields, base)
    ok = valid(p) if ok is None else (np.asarray(ok, bool) & valid(p))
    out = np.full(np.shape(p["n_drums"]), np.nan)
    if not ok.any():
        return out
    duty, t_op = design_duty(base), float(base.operating.fluid_temperature)
    for rows, gp in fluid_groups(p, ok, mats, base):  # one march per fluid
        if duty.torque > 0:
            load, seconds = duty_load(gp, duty.torque), duty.time
        else:
            load, seconds = peak_load(gp), duty.peak_time
        end = march_batch(gp.net, load, seconds, STEPS).final[:, 1]
        hi = np.minimum(np.maximum(end, t_op), gp.fluid.temperature_range[1])  # duty_range
        out[rows] = np.maximum(hi, t_op)
    return out
