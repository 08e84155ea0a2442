"""The clutch pair at the hand: the antagonistic pair of clutches reflected through the
transmission (``mr_at_hand``, Eq. 3-4, the one function ``evaluate`` and the batch path
feed the haptic model), the equal-force motor beside it (``motor_transmission``), what a
bench measured put in (``with_measured``), the torque response's stable K
(``response_figures``) and the b1 and m1 budgets at the hand (``hand_budget``)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from geometry.params import preset
from mrclutch.clutch import ClutchFigures
from mrclutch.design import ClutchDesign
from mrclutch.haptics.actuator import (
    EM_170,
    TABLE2_MR,
    Actuator,
    HapticParams,
    Transmission,
    reflect,
)
from mrclutch.haptics.delay import lag_stable_stiffness
from mrclutch.haptics.hand import hand_figures, hand_figures_at
from mrclutch.haptics.model import (
    StabilitySearchError,
    max_stable_stiffness,
)

#: The motor of the paper's equal-force comparison (Fig. 7c).
MOTOR = "maxon-136206"


def mr_at_hand(design: ClutchDesign, inertia: Any, damping: Any, torque: Any, mass: Any,
               delay: Any = None) -> HapticParams:  # fmt: skip
    """The antagonistic pair of clutches with these figures (floats or arrays of designs),
    seen at the hand through the design's transmission (Eq. 3–4): what ``evaluate`` and
    ``evaluate_batch`` both feed the haptic model. ``delay``: the torque response's
    equivalent delay, used where ``operating.delay_source`` is "geometry"."""
    op = design.operating
    pair = Actuator.mr_pair(inertia, damping, torque, mass, op.delay, design.name)
    hp = reflect(pair, design.transmission)
    if op.delay_source == "geometry" and delay is not None:
        hp = replace(hp, delay=delay)  # one delay per design (arrays in a sweep)
    return hp


def motor_transmission(mr: HapticParams, mr_tr: Transmission, motor: Actuator) -> Transmission:
    """The paper's EM bench on the MR design's lever and workspace, geared to equal force."""
    em = EM_170.with_lever(mr_tr.lever) if mr_tr.lever != EM_170.lever else EM_170
    em = replace(em, workspace=mr_tr.workspace)
    base_force = motor.max_torque * em.reduction  # F = T nG/l (Eq. 4)
    return replace(em, gearing=float(mr.f_max) / base_force)


#: The label beside a figure at the hand: where its torque, mass and damping come from.
SOURCE_LABELS = {"fast": "fast model", "reference": "reference model"}


def source_label(fidelity: str) -> str:
    """ "fast model", "reference model", or the accuracy target's label."""
    return SOURCE_LABELS.get(fidelity, f"model, {fidelity}")


def with_measured(design: ClutchDesign, mr: HapticParams, current: float, source: str
                  ) -> tuple[HapticParams, str]:  # fmt: skip
    """The pair at the hand with what the bench measured put in (``[measured]`` with
    ``use_in_model``): m1, b1, the step delay and, measured at the current limit, the
    torque (F_max through Eq. 4's reduction); the label then names them as measured."""
    meas = design.measured
    if meas is None or not meas.use_in_model:
        return mr, source
    new: dict[str, float] = {}
    if meas.m1 is not None:
        new["m1"] = meas.m1
    if meas.b1 is not None:
        new["b1"] = meas.b1
    if meas.step_delay is not None:
        new["delay"] = meas.step_delay
    at_limit = [p.torque for p in meas.torque if math.isclose(p.current, current, rel_tol=1e-9)]
    if at_limit:
        new["f_max"] = at_limit[0] * design.transmission.reduction  # Eq. 4: F = T nG/l
    if not new:
        return mr, source
    names = {"m1": "m1", "b1": "b1", "delay": "delay", "f_max": "torque"}
    return replace(mr, **new), f"measured ({', '.join(names[k] for k in new)}) + {source}"


def hand_or_why(p: HapticParams, k: float, unavailable: dict[str, str], side: str,
                prior: Mapping[str, Any] | None = None) -> dict[str, Any]:  # fmt: skip
    """``hand_figures``, or (where the stability scan cannot resolve the loop) the same keys
    None with a note, the reason also in ``unavailable``. ``prior``: this design's hand
    figures at another K, taken to ``k`` (``hand_figures_at``) instead of searching the
    hands again."""
    if prior is not None and "note" not in prior:
        return hand_figures_at(prior, k)
    try:
        return hand_figures(p, k)
    except StabilitySearchError as exc:
        why = f"the hand figures are unknown: {exc}"
        unavailable[f"hand_{side}"] = why
        return {**nones(HAND_KEYS), "notes": [], "note": why}


#: The keys of ``hand_figures`` (nested), for a side whose figures are unavailable.
HAND_KEYS: dict[str, Any] = {
    "K_N_per_m": 0, "coupled_stable": 0, "max_stable_K_all_hands_N_per_m": 0,
    "worst_hand": {"m_kg": 0, "b_N_s_per_m": 0, "k_N_per_m": 0}, "hands_checked": 0,
    "max_stable_K_hands_off_N_per_m": 0, "max_passive_K_N_per_m": 0, "backdrive_force_N": 0,
    "felt_damping_N_s_per_m": 0, "felt_mass_kg": 0,
    "motion": {"amplitude_m": 0, "frequency_hz": 0},
}  # fmt: skip


def response_figures(design: ClutchDesign, resp: Any, mr: HapticParams,
                     unavailable: dict[str, str] | None = None) -> dict[str, Any]:  # fmt: skip
    """The torque response of one design (``magnetics.dynamics.TorqueResponse``) and what it
    does to the haptic loop: the largest stable K with the typed delay, with the
    equivalent delay τ_eq, and with the lags themselves (the reference τ_eq approximates).
    Where the lags are not finite those two K are None and ``unavailable`` (filled in
    place) says why."""
    op = design.operating
    tau_eq = float(resp.equivalent_delay[0])
    k_typed = max_stable_stiffness(replace(mr, delay=op.delay))
    k_eq = k_lags = None
    if np.all(np.isfinite(resp.lags[0])):
        k_eq = max_stable_stiffness(replace(mr, delay=tau_eq))
        k_lags = lag_stable_stiffness(replace(mr, delay=0.0), resp.lags[0])
    elif unavailable is not None:
        unavailable["torque_response"] = (
            f"the current does not reach 90 % of {float(resp.current[0]):.3g} A on the "
            f"{design.amplifier.supply_voltage:g} V supply: no equivalent delay, and no "
            "stable K with it")  # fmt: skip
    return {
        **resp.item(0),
        "delay_source": op.delay_source,
        "typed_delay_s": op.delay,
        "supply_voltage_V": design.amplifier.supply_voltage,
        "current_bandwidth_hz": design.amplifier.current_bandwidth_hz,
        "max_stable_K_typed_delay_N_per_m": k_typed,
        "max_stable_K_torque_delay_N_per_m": k_eq,
        "max_stable_K_lags_N_per_m": k_lags,
    }


#: The sides of ``Evaluation.zwidth`` and ``.hand``: the MR pair and the equal-force motor.
ZWIDTH_SIDES = ("mr", "motor")


#: Why the budget of b1 may not reach the paper's identified value, least certain first.
B1_UNCERTAIN = (
    "the fluid's viscosity law: the carrier grade is not disclosed (a PAO 4 is assumed), "
    "and the datasheet η is ±18 % at 40 °C",
    "the gap: the paper's clutch gaps are not published (the preset's 0.7 mm was inferred); "
    "the film damping scales as 1/gap",
    "Table 2's b1 was fitted by eye to the bench's response (paper §III), lever and cable included",
)


def hand_budget(design: ClutchDesign, fig: ClutchFigures, mr: HapticParams,
                table2: Mapping[str, Any]) -> dict[str, Any]:  # fmt: skip
    """b1 and m1 at the hand as named terms (the pair's two clutches, Eq. 3), each with its
    value, share and source, beside the paper's Table 2; the terms sum to the values the
    haptic model uses. ``table2``: the pair's metrics with Table 2's b1 instead."""
    r2 = 2 * design.transmission.reduction**2  # both clutches of the pair, Eq. 3
    b_terms = [(k, t.damping * r2, t.source) for k, t in fig.drag.terms.items()]
    labels = {"rotor": "output rotor (hub + drums)", "shaft": "output shaft"}
    how = f"inertia by {fig.methods['inertia']}"
    m_terms = [(labels.get(k, k), v * r2, how) for k, v in fig.inertia_parts.items()]
    m_terms.append(("carried fluid", fig.fluid_inertia * r2, "linear Couette (magnetics.drag)"))

    def table(terms: list[tuple[str, float, str]], total: float, paper: float) -> dict[str, Any]:
        rows = [
            {"name": n, "value": v, "share": v / total if total else math.nan, "source": src}
            for n, v, src in terms
        ]
        return {
            "terms": rows,
            "total": total,
            "paper_table2": paper,
            "unexplained": paper - total,
            "ratio_to_paper": total / paper,
        }

    b1, m1 = float(mr.b1), float(mr.m1)
    return {
        # Table 2 identified the paper's own clutch: "unexplained" means something only there
        "paper_clutch": design.clutch == preset("paper"),
        "b1_N_s_per_m": {
            **table(b_terms, b1, float(TABLE2_MR.b1)),
            "least_certain": list(B1_UNCERTAIN),
        },
        "m1_kg": table(m_terms, m1, float(TABLE2_MR.m1)),
        "with_table2_b1": {
            "b1_N_s_per_m": float(TABLE2_MR.b1),
            "passive": bool(table2["passive"]),
            "max_passive_K_N_per_m": table2["max_passive_K_N_per_m"],
            "max_stable_K_N_per_m": table2["max_stable_K_N_per_m"],
        },
    }


def nones(d: Mapping[str, Any]) -> dict[str, Any]:
    """The same keys (nested), every value None: a side whose figures are unavailable."""
    return {k: nones(v) if isinstance(v, Mapping) else None for k, v in d.items()}
