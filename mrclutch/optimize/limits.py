"""The builder's limits a design must meet (``Constraints``), the columns they read beside
``evaluate_batch``'s (``limit_columns``: coil power, time at the peak and at a duty, the
continuous torque above the drag; ``evaluate_rows``: all of them) and which limits bind
at a design (``active_limits``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.params import valid
from geometry.validation import ParameterError, check_positive, check_range
from magnetics import thermal
from mrclutch.design import ClutchDesign, current_limit
from mrclutch.duty import duty_batch
from mrclutch.feel import feel_batch
from mrclutch.pipeline import batch_fields, evaluate_batch, fluid_limit

#: N·m: continuous torque above the off-state drag of the paper's clutch on the fast
#: path (0.0451 − 0.0041 N·m at 530 rpm; reference fidelity the same to 2 digits), the
#: default floor of ``Constraints.min_continuous_torque`` (tests/mrclutch/test_optimize.py
#: re-measures it).
PAPER_CONTINUOUS_ABOVE_DRAG = 0.041


@dataclass(frozen=True)
class Constraints:
    """Limits the optimum must meet (SI). ``max_power`` and ``peak_time`` default (None) to
    the design's own: the amplifier's supply voltage × the current limit, and the operating
    point's peak duration (``resolved``)."""

    min_torque: float = 0.4  # N·m, Table 1's rated torque
    max_mass: float = 0.100  # kg, whole clutch
    max_diameter: float = 0.030  # m, Table 1 envelope
    max_length: float = 0.040  # m
    passive: bool = True  # a passive closed loop at K = K_max (Eq. 4)
    stable: bool = True  # a stable free closed loop at K = K_max
    #: N·m held forever above the off-state drag (slipping at the input speed; 0: none)
    min_continuous_torque: float = PAPER_CONTINUOUS_ABOVE_DRAG
    max_power: float | None = None  # W of coil heat at the current limit
    peak_time: float | None = None  # s at the peak current before the wire or fluid limit
    duty_torque: float = 0.0  # N·m (yield + drag) held for duty_time s (0: no duty cycle)
    duty_time: float = 0.0  # s
    #: N·m left at 0 A after the current limit (mrclutch.feel; None: no limit)
    max_residual_torque: float | None = None
    #: N of runout ripple at the hand (mrclutch.feel; None: no limit)
    max_ripple_force: float | None = None
    #: h of fluid life at the base design's [duty] (mrclutch.duty; None: no limit)
    min_life: float | None = None

    def __post_init__(self) -> None:
        check_positive("min_torque", self.min_torque, " N·m")
        check_positive("max_mass", self.max_mass, " kg")
        check_positive("max_diameter", self.max_diameter, " m")
        check_positive("max_length", self.max_length, " m")
        check_range("min_continuous_torque", self.min_continuous_torque, 0.0, 1e3, " N·m")
        if self.max_power is not None:
            check_positive("max_power", self.max_power, " W")
        if self.peak_time is not None:
            check_range("peak_time", self.peak_time, 0.0, 1e6, " s")
        check_range("duty_torque", self.duty_torque, 0.0, 1e3, " N·m")
        check_range("duty_time", self.duty_time, 0.0, 1e7, " s")
        if self.max_residual_torque is not None:
            check_positive("max_residual_torque", self.max_residual_torque, " N·m")
        if self.max_ripple_force is not None:
            check_positive("max_ripple_force", self.max_ripple_force, " N")
        if self.min_life is not None:
            check_positive("min_life", self.min_life, " h")
        if (self.duty_torque > 0) != (self.duty_time > 0):
            raise ParameterError(
                f"duty cycle: duty_torque = {self.duty_torque:g} N·m and "
                f"duty_time = {self.duty_time:g} s: give both or neither"
            )
        for name in ("passive", "stable"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"{name} = {getattr(self, name)!r}: must be True or False")

    def resolved(self, base: ClutchDesign) -> Constraints:
        """The limits with the design's defaults filled in (max_power, peak_time)."""
        power = self.max_power
        if power is None:  # what the amplifier delivers at its limits: P = V·I
            power = base.amplifier.supply_voltage * base.operating.max_current
        peak = self.peak_time if self.peak_time is not None else base.operating.peak_duration
        return replace(self, max_power=power, peak_time=peak)

    def terms(self, r: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Each limit as g ≤ 0 (relative: g = value/limit − 1 or 1 − value/limit), by name;
        ``r``: evaluate_rows' columns. Needs ``resolved`` limits. Stability is a term where
        ``max_stable_K_N_per_m`` is present, the robust verdict where the worst-case
        columns are."""
        if self.max_power is None or self.peak_time is None:
            raise ParameterError("Constraints.terms: resolve the limits first (resolved(base))")
        g = {
            "torque": 1 - r["max_torque_N_m"] / self.min_torque,
            "mass": r["clutch_mass_kg"] / self.max_mass - 1,
            "diameter": r["diameter_m"] / self.max_diameter - 1,
            "length": r["length_m"] / self.max_length - 1,
            "power": r["coil_power_W"] / self.max_power - 1,
        }
        if self.min_continuous_torque > 0:
            g["continuous torque"] = 1 - r[CONTINUOUS] / self.min_continuous_torque
        if self.peak_time > 0:
            g["time at peak"] = 1 - r["time_at_peak_s"] / self.peak_time
        if self.duty_time > 0:
            g["duty cycle"] = 1 - r["time_at_duty_s"] / self.duty_time
        if self.max_residual_torque is not None:
            g["residual torque"] = r["residual_torque_N_m"] / self.max_residual_torque - 1
        if self.max_ripple_force is not None:
            g["ripple"] = r["ripple_force_N"] / self.max_ripple_force - 1
        if self.min_life is not None:
            g["fluid life"] = 1 - r["fluid_life_h"] / self.min_life
        if self.passive:
            g["passive"] = r["K_N_per_m"] / r["max_passive_K_N_per_m"] - 1
        if self.stable and "max_stable_K_N_per_m" in r:
            # stable for K below the first destabilising crossing (model.max_stable_stiffness)
            g["stable"] = r["K_N_per_m"] / r["max_stable_K_N_per_m"] - (1 - 1e-9)
        for key, col in ROBUST_COLUMNS.items():
            if col in r and (self.stable if key == "robust stable" else self.passive):
                g[key] = r["K_N_per_m"] / r[col] - (1 - 1e-9)
        bad = r["valid"] != 1
        return {k: np.where(bad, np.inf, np.nan_to_num(v, nan=np.inf, neginf=-1.0))
                for k, v in g.items()}  # fmt: skip

    def violation(self, r: Mapping[str, np.ndarray]) -> np.ndarray:
        """Sum of relative violations (0 where every limit holds; inf for invalid designs)."""
        v = sum(np.maximum(0, g) for g in self.terms(r).values())
        return np.where(r["valid"] == 1, np.nan_to_num(np.asarray(v, dtype=float), nan=np.inf),
                        np.inf)  # fmt: skip


#: The column of the continuous torque above the off-state drag (N·m).
CONTINUOUS = "continuous_above_drag_N_m"
#: The robust verdict's columns (worst case over the uncertainty ranges), when computed.
ROBUST_COLUMNS = {
    "robust stable": "max_stable_K_worst_N_per_m",
    "robust passive": "max_passive_K_worst_N_per_m",
}


def limit_columns(fields: Mapping[str, ArrayLike], base: ClutchDesign,
                  r: Mapping[str, np.ndarray], duty_torque: float = 0.0
                  ) -> dict[str, np.ndarray]:  # fmt: skip
    """The builder's limits' columns of S designs beside ``evaluate_batch``'s ``r``:
    coil power at the current limit (I²R at the coil temperature), seconds at the peak
    (the current limit, holding the peak torque while slipping at the input speed) before
    the wire or the fluid limit, the continuous torque above the off-state drag and, with
    ``duty_torque``, the seconds at that torque. Same thermal network and transient as
    ``evaluate`` (``pipeline.thermal_figures``); the duty's current is read on the chord
    from 0 to the peak (yield torque ∝ current): the yield torque is concave in the
    current (Carlson's tanh law [carlson], saturating steel), so the chord's current is at
    least the true one and its time a lower bound."""
    p, mats = batch_fields(fields, base)  # a material column: per row (issue 33)
    ok = valid(p) & (np.asarray(r["valid"]) == 1)
    op = base.operating
    current = current_limit(op, p["wire_diameter"])
    peak, off = np.asarray(r["max_torque_N_m"]), np.asarray(r["off_state_torque_N_m"])
    w = op.input_speed

    def fn(rg: regions.Regions, rows: np.ndarray) -> dict[str, np.ndarray]:
        limit = fluid_limit(rg.materials)
        net = thermal.network(rg, op.ambient_temperature, limit)
        return {"capacity": net.capacity, "conductance": net.conductance,
                "to_air": net.to_air, "r20": net.r20, "fluid_limit": limit}  # fmt: skip

    # each region table's network, then the transient of every row in one call (its cost is
    # mostly per call: a bisection of 120 steps, whatever the rows; each row its own)
    nets = regions.per_topology(p, ok, fn, mats)
    out = {k: np.full(off.shape, np.nan) for k in ("coil_power_W", "time_at_peak_s")}
    out["time_at_duty_s"] = np.full(off.shape, np.inf if duty_torque <= 0 else np.nan)
    rows = np.flatnonzero(ok)
    for limit in np.unique(nets["fluid_limit"][rows]):  # one call a fluid limit (materials)
        at = rows[nets["fluid_limit"][rows] == limit]
        net = thermal.Network(nets["capacity"][at], nets["conductance"][at], nets["to_air"][at],
                              nets["r20"][at], op.ambient_temperature, None)  # fmt: skip
        i = current[at]
        # R(T) = R20 (1 + α (T − 20)) (magnetics.thermal)
        out["coil_power_W"][at] = i * i * net.r20 * (
            1 + thermal.ALPHA_CU * (op.coil_temperature - 20.0))  # fmt: skip
        tw, tf = thermal.time_to_limits_batch(net, i, peak[at] * w,
                                              op.wire_temperature_limit, limit)  # fmt: skip
        out["time_at_peak_s"][at] = np.minimum(tw, tf)
        if duty_torque > 0:
            y = peak[at] - off[at]
            i_d = i * np.clip((duty_torque - off[at]) / y, 0.0, None)
            dw, df = thermal.time_to_limits_batch(
                net, i_d, duty_torque * w, op.wire_temperature_limit, limit
            )
            out["time_at_duty_s"][at] = np.where(duty_torque <= peak[at], np.minimum(dw, df), 0.0)
    out[CONTINUOUS] = np.asarray(r["continuous_torque_N_m"]) - off
    return out


def evaluate_rows(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign,
    cons: Constraints,
    *,
    stability: bool = False,
    zwidth: bool = False,
) -> dict[str, np.ndarray]:
    """``evaluate_batch`` (passivity as ``cons`` asks) and ``limit_columns``: every column
    ``Constraints.terms`` reads."""
    r = evaluate_batch(fields, base, passivity=cons.passive, stability=stability,
                       zwidth=zwidth)  # fmt: skip
    out = {**r, **limit_columns(fields, base, r, cons.duty_torque)}
    feel = tuple(
        k
        for k, on in (
            ("residual_torque_N_m", cons.max_residual_torque),
            ("ripple_force_N", cons.max_ripple_force),
        )
        if on is not None
    )
    if feel:  # the steel's memory and the runout ripple (mrclutch.feel)
        out.update(feel_batch(fields, base, feel))
    if cons.min_life is not None:  # the fluid's life at the base's [duty] (mrclutch.duty)
        out.update(duty_batch(fields, base, out))
    return out


#: A limit is *active* at a member when its relative term g lies within this of 0.
ACTIVE = 0.02


def active_limits(cons: Constraints, r: Mapping[str, np.ndarray], j: int) -> tuple[str, ...]:
    """The limits within ACTIVE of binding at row j (``cons`` resolved)."""
    return tuple(k for k, g in cons.terms(r).items() if abs(float(g[j])) <= ACTIVE)
