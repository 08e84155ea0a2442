"""Whether an evaluated design meets the builder's requirements: the optimiser's re-check
at reference fidelity (``optimize``'s candidates and Pareto members), each missed limit as
a phrase. Application logic (issue 43: no decision logic under ``mrclutch/cli/``): it reads
an evaluation's JSON (``verdict.judge``) and the limits of ``optimize.Constraints``."""

from __future__ import annotations

import numpy as np

from mrclutch.design import ClutchDesign, design_preset
from mrclutch.optimize import CONTINUOUS, Constraints, limit_columns
from mrclutch.verdict import verdict_of


def reference_row(ev: dict, design: ClutchDesign, cons: Constraints) -> dict[str, np.ndarray]:
    """One evaluated design (``Evaluation.as_json()``) as a row of the columns
    ``Constraints.terms`` reads, the builder's limits (power, time at peak, duty) computed
    from its own torques (``limit_columns``)."""
    c, h = ev["clutch"], ev["haptic"]
    d, length = c["envelope_m"]
    r = {"valid": 1.0, "max_torque_N_m": c["max_torque_N_m"],
         "off_state_torque_N_m": c["off_state_torque_N_m"],
         "continuous_torque_N_m": c["continuous_torque_N_m"],
         "clutch_mass_kg": c["clutch_mass_kg"], "diameter_m": d, "length_m": length,
         "K_N_per_m": h["K_N_per_m"], "max_passive_K_N_per_m": h["max_passive_K_N_per_m"],
         "max_stable_K_N_per_m": h["max_stable_K_N_per_m"]}  # fmt: skip
    feel, duty = ev.get("feel") or {}, ev.get("duty") or {}
    if feel:  # issue 41: the steel's memory and the runout ripple (mrclutch.feel)
        r["residual_torque_N_m"] = feel["hysteresis"]["residual_torque_N_m"]
        r["ripple_force_N"] = feel["ripple"]["ripple_force_N"]
    if duty and duty.get("fluid", {}).get("life_h") is not None:  # mrclutch.duty
        r["fluid_life_h"] = duty["fluid"]["life_h"]
    row = {k: np.array([float(v)]) for k, v in r.items()}
    fields = {k: np.array([getattr(design.clutch, k)]) for k in ("gap", "n_drums")}
    row.update(limit_columns(fields, design, row, cons.duty_torque))
    return row


#: How each builder's limit is told when missed: term → (column, unit, scale, limit field).
LIMIT_PHRASES = {
    "continuous torque": ("continuous torque above drag", CONTINUOUS, "N·m", 1.0,
                          "min_continuous_torque", "below"),
    "power": ("coil power", "coil_power_W", "W", 1.0, "max_power", "above"),
    "time at peak": ("time at peak", "time_at_peak_s", "s", 1.0, "peak_time", "below"),
    "duty cycle": ("time at the duty torque", "time_at_duty_s", "s", 1.0, "duty_time", "below"),
    "residual torque": ("residual torque at 0 A", "residual_torque_N_m", "mN·m", 1e3,
                        "max_residual_torque", "above"),
    "ripple": ("runout ripple at the hand", "ripple_force_N", "mN", 1e3, "max_ripple_force",
               "above"),
    "fluid life": ("fluid life", "fluid_life_h", "h", 1.0, "min_life", "below"),
}  # fmt: skip


def requirement_violations(ev: dict, cons: Constraints, design: ClutchDesign | None = None
                           ) -> list[str]:  # fmt: skip
    """Every limit of ``cons`` the evaluated design misses, each as a phrase (empty: none).
    Torque, mass and envelope within 1e-9 relative (rounding) of their limits pass.
    ``design``: the design evaluated (its amplifier and operating point resolve the
    default power and peak limits; the paper preset's when None)."""
    design = design if design is not None else design_preset("paper")
    cons = cons.resolved(design)
    c, v = ev["clutch"], verdict_of(ev)  # the one verdict, from the evaluation's own data
    tol = 1e-9
    out = []
    if c["max_torque_N_m"] < cons.min_torque * (1 - tol):
        out.append(f"torque {c['max_torque_N_m']:.4g} N·m below the {cons.min_torque:g} N·m floor")
    if c["clutch_mass_kg"] > cons.max_mass * (1 + tol):
        out.append(f"mass {c['clutch_mass_kg'] * 1e3:.4g} g above {cons.max_mass * 1e3:g} g")
    d, length = c["envelope_m"]
    if d > cons.max_diameter * (1 + tol) or length > cons.max_length * (1 + tol):
        out.append(f"envelope Ø{d * 1e3:.4g} × {length * 1e3:.4g} mm outside the limits")
    row = reference_row(ev, design, cons)
    terms = cons.terms(row)
    for term, (label, col, unit, scale, limit, side) in LIMIT_PHRASES.items():
        if term in terms and terms[term][0] > tol:
            out.append(f"{label} {row[col][0] * scale:.4g} {unit} {side} the "
                       f"{getattr(cons, limit) * scale:.4g} {unit} limit")  # fmt: skip
    k, h = v["K_N_per_m"], ev["haptic"]
    scope = "over the uncertainty ranges" if v["over"] == "ranges" else "at nominal values"
    for need, name, key, what in ((cons.stable, "stable", "max_stable_K_N_per_m", "stability"),
                                  (cons.passive, "passive", "max_passive_K_N_per_m",
                                   "passivity")):  # fmt: skip
        holds = v[name]["holds"]
        if need and holds != "always":
            how = "for part of them" if holds == "depends" else ""
            out.append(f"not {name} at K = {k:.4g} N/m {scope}{' ' + how if how else ''} "
                       f"(largest {name} K {h[key]:.4g} N/m at nominal values); {what} was "
                       "required")  # fmt: skip
    return out
