"""From the drums to the hand: a ClutchDesign → clutch figures → Actuator → haptic metrics.

Two fidelities (README "Speed against accuracy"):

* ``fast`` — analytic inertia from the section, torque from the saturating magnetic
  circuit, drag from the closed-form films. Milliseconds; the default for sweeps.
* ``reference`` — inertia from the exact B-rep (build123d/OpenCascade), torque from the
  axisymmetric FEM. Seconds; for the final check of a design.

The MR actuator is the paper's antagonistic pair of clutches on the design's
transmission. The motor it is compared with is the Maxon 136206 on the paper's EM bench
with the same lever, geared (G = F_max,MR / F_max,EM) so both render the same force
— the *equal-force* comparison of the paper's Fig. 7c made exact — at the same virtual
stiffness K = K_max of the MR system.

This module is the single-design path (``evaluate``, ``rendered``, the ``Evaluation``);
what its null figures mean is ``mrclutch.nulls`` (re-exported here). Its stages live by
what they compute: the clutch figures in ``mrclutch.clutch``, the pair and the motor at
the hand in ``mrclutch.at_hand``, the batch path of sweeps and the optimiser in
``mrclutch.fast_batch``.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.validation import ParameterError
from magnetics.circuit import path_from_section
from magnetics.dynamics import torque_response
from mrclutch.at_hand import (
    HAND_KEYS,
    MOTOR,
    ZWIDTH_SIDES,
    hand_budget,
    hand_or_why,
    motor_transmission,
    mr_at_hand,
    nones,
    response_figures,
    source_label,
    with_measured,
)
from mrclutch.batch import batch_fields
from mrclutch.clutch import (
    FIDELITIES,
    FLUID_LIMIT,
    ClutchFigures,
    clutch_figures,
    current_notes,
    dynamic_range_db,
    fluid_limit,
)
from mrclutch.design import ClutchDesign
from mrclutch.design_network import section_network
from mrclutch.duty import evaluation_duty
from mrclutch.fast_batch import BatchEvaluator, evaluate_batch
from mrclutch.feel import feel_figures
from mrclutch.haptics.actuator import (
    TABLE2_MR,
    HapticParams,
    Transmission,
    actuator,
    reflect,
)
from mrclutch.haptics.hand import backdrive_force
from mrclutch.haptics.model import (
    metrics_of,
)
from mrclutch.haptics.zwidth import ZWIDTH_KEYS
from mrclutch.haptics.zwidth import zwidth as zwidth_of
from mrclutch.hot_range import resolved_ranges
from mrclutch.nulls import INF_MEANS, NAN_MEANS, null_notes

#: The application's evaluation API: the single-design path defined here and, from the
#: modules of its stages (mrclutch.clutch, mrclutch.at_hand, mrclutch.fast_batch), the
#: names commands and scripts import from here.
__all__ = [
    "FAST_BANDWIDTH_ERROR",
    "FIDELITIES",
    "FLUID_LIMIT",
    "HAND_KEYS",
    "INF_MEANS",
    "NAN_MEANS",
    "BatchEvaluator",
    "ClutchFigures",
    "Evaluation",
    "batch_fields",
    "clutch_figures",
    "current_notes",
    "dynamic_range_db",
    "evaluate",
    "evaluate_batch",
    "fluid_limit",
    "mr_at_hand",
    "null_notes",
    "rendered",
    "source_label",
]  # fmt: skip

#: Stated relative error of the fast path's rendering bandwidth against the reference
#: fidelity. Bandwidth ∝ √(K_max/(m1+m2)) with K_max ∝ torque, so its error is about
#: half the torque error plus half the reflected-mass error (analytic inertia is exact
#: for the axisymmetric section). Holds where the network is within 10 % of the FEM —
#: on all of its measured map (docs/magnetics.md); its map bounds the torque error per
#: design (torque_error_bound in sweep rows; a note on evaluate where it exceeds 10 %).
#: Checked on the paper preset, variants and the optimiser's optimum in
#: tests/mrclutch/test_pipeline.py.
FAST_BANDWIDTH_ERROR = 0.05


@dataclass(frozen=True)
class Evaluation:
    """A design evaluated: the clutch, the MR pair at the hand and the equal-force motor."""

    design: ClutchDesign
    fidelity: str
    clutch: ClutchFigures
    mr: HapticParams
    motor: HapticParams | None  # None: unavailable (``unavailable["motor"]`` says why)
    motor_gearing: float | None
    haptic: Mapping[str, Any]  # metrics of the MR pair at K_max
    motor_metrics: Mapping[str, Any]  # metrics of the motor at the same K
    budget: Mapping[str, Any]  # b1 and m1 as named terms beside the paper's Table 2
    zwidth: Mapping[str, Any]  # side → the Z-width (``zwidth.zwidth``) of MR pair and motor
    hand: Mapping[str, Any]  # side → ``hand.hand_figures``: coupled stability, transparency
    response: Mapping[str, Any] = field(default_factory=dict)  # ``response_figures``
    torque_response: Any = None  # its ``magnetics.dynamics.TorqueResponse`` (step, lags)
    #: secondary figures that could not be computed → why (the motor comparison, the
    #: torque response's delay); the rest of the evaluation stands
    unavailable: Mapping[str, str] = field(default_factory=dict)
    source: str = "fast model"  # where the pair's figures at the hand come from
    model_mr: HapticParams | None = None  # the model's pair where measured values replace it
    #: ``mrclutch.feel.feel_figures``: the residual torque and its loop, the runout ripple
    feel: Mapping[str, Any] = field(default_factory=dict)
    #: the pair's and the motor's parameters ``hand`` was computed on (by identity: a
    #: ``rendered`` at another K reuses those figures, whose search does not depend on K)
    hand_of: tuple[HapticParams, ...] = field(default=(), repr=False, compare=False)

    @functools.cached_property
    def duty(self) -> dict[str, Any]:
        """Issue 41: the hot peak and duty holds, the fluid's volume and life and the b1
        budget's new terms (``mrclutch.duty.evaluation_duty``), computed when first read."""
        return evaluation_duty(self, resolved_ranges(self.design))

    def as_json(self) -> dict[str, Any]:
        mr_m, em_m = dict(self.haptic), dict(self.motor_metrics)
        zw = {k: dict(v) for k, v in self.zwidth.items()}
        hand = {k: dict(v) for k, v in self.hand.items()}
        motor = {**em_m, "actuator": MOTOR, "gearing": self.motor_gearing}
        if self.motor is None:  # every figure of the motor's side None, and why
            why = self.unavailable["motor"]
            motor = {**dict.fromkeys(mr_m), "actuator": MOTOR, "gearing": None, "note": why}
            zw["motor"] = {**dict.fromkeys(zw["mr"]), "note": why}
            hand["motor"] = {**nones(hand["mr"]), "note": why}
        out = {
            "design": self.design.name,
            "fidelity": self.fidelity,
            "clutch": self.clutch.as_json(),
            "haptic": mr_m,
            "budget": dict(self.budget),
            "motor": motor,
            "bandwidth_gain": _gain(mr_m["bandwidth_hz"], motor["bandwidth_hz"]),
            "bandwidth_gain_lumped": _gain(
                mr_m["bandwidth_lumped_hz"], motor["bandwidth_lumped_hz"]
            ),
            "zwidth": zw,
            "hand": hand,
            "response": dict(self.response),
            "unavailable": dict(self.unavailable),
            "source": self.source,
            "feel": {k: dict(v) for k, v in self.feel.items()},
            "duty": self.duty,
        }
        out["nulls"] = null_notes(out)
        return out


def _gain(a: float | None, b: float | None) -> float | None:
    if a is None or b is None or not np.isfinite(a) or not np.isfinite(b):
        return None
    return a / b - 1.0


def evaluate(
    design: ClutchDesign,
    fidelity: str = "fast",
    accuracy: float | None = None,
    K: float | None = None,
) -> Evaluation:
    """The clutch figures and their haptic consequences, beside the equal-force motor, at
    the virtual stiffness ``K`` (N/m; None: the MR pair's K_max, Eq. 4). ``accuracy``
    (relative): pick per quantity the cheapest method that meets it (mrclutch.trust.choose);
    the Evaluation's fidelity then reads "accuracy=…". The design's own ``[render]`` rule
    is applied by ``mrclutch.verdict.judge``, which calls this."""  # fmt: skip
    # one section and one circuit: the thermal rating's, the torque response's and the feel's
    section, _ = section_network(design.clutch, design.materials)
    path = path_from_section(section)
    fig = clutch_figures(design, fidelity, accuracy, path=path)
    if accuracy is not None:
        fidelity = f"accuracy={accuracy:g}"
    resp = torque_response(
        section.table,
        fig.max_current,
        design.amplifier,
        design.laminations,
        path=path,
        coil_temperature=design.operating.coil_temperature,
    )
    mr = mr_at_hand(design, fig.moving_inertia, fig.drag_damping, fig.max_torque,
                    fig.clutch_mass, float(resp.equivalent_delay[0]))  # fmt: skip
    model_mr = mr
    mr, source = with_measured(design, mr, fig.max_current, source_label(fidelity))
    motor = actuator(MOTOR)
    unavailable: dict[str, str] = {}
    try:  # a secondary figure: a motor that cannot be geared to the force is left out
        em_tr: Transmission | None = motor_transmission(mr, design.transmission, motor)
        em: HapticParams | None = reflect(motor, em_tr)
    except ParameterError as exc:
        em_tr = em = None
        unavailable["motor"] = (f"the equal-force {MOTOR} is left out: matching the MR pair's "
                                f"{float(mr.f_max):.4g} N would need {exc}")  # fmt: skip
    sides = [mr] if em is None else [mr, em]
    zw = zwidth_of(HapticParams.stack(sides))
    names = ZWIDTH_SIDES[: len(sides)]
    zws = {side: {key: zw[key][i] if np.ndim(zw[key]) > 1 else float(zw[key][i])
                  for key in ZWIDTH_KEYS} for i, side in enumerate(names)}  # fmt: skip
    gearing = em_tr.gearing if em_tr is not None else None
    ev = Evaluation(design, fidelity, fig, mr, em, gearing, {}, {}, {}, zws, {},
                    response_figures(design, resp, mr, unavailable), resp,
                    MappingProxyType(unavailable), source, model_mr,
                    feel_figures(design, fig.max_torque, fig.yield_torque, fig.off_state_torque,
                                 float(backdrive_force(mr)), path))  # fmt: skip
    return rendered(ev, float(mr.k_max) if K is None else K)


def rendered(ev: Evaluation, K: float) -> Evaluation:
    """``ev`` with the MR pair and the equal-force motor rendering the virtual spring ``K``
    (N/m): the metrics at the hand, the b1 budget's Table 2 check and the hand figures are
    taken at K; the clutch, the pair's parameters, K_max and the Z-width do not depend on
    it. ``haptic["K_max_N_per_m"]`` is the pair's F_max/d (Eq. 4) whatever K is."""
    mr, em = ev.mr, ev.motor
    unavailable = {k: v for k, v in ev.unavailable.items() if not k.startswith("hand_")}
    table2 = replace(mr, b1=TABLE2_MR.b1)  # the same pair with the paper's identified b1
    sides = [mr] if em is None else [mr, em]
    *side_m, t2_m = metrics_of([*sides, table2], [K] * (len(sides) + 1))
    mr_m, em_m = side_m[0], (side_m[1] if em is not None else {})
    mr_m = {**mr_m, "K_max_N_per_m": float(mr.k_max)}
    if em is not None:
        em_m = {**em_m, "K_max_N_per_m": float(em.k_max)}
    budget = hand_budget(ev.design, ev.clutch, mr, t2_m)
    names = ZWIDTH_SIDES[: len(sides)]
    same = len(ev.hand_of) == len(sides) and all(
        a is b for a, b in zip(ev.hand_of, sides, strict=True))  # fmt: skip
    hand = {side: hand_or_why(p, K, unavailable, side, ev.hand.get(side) if same else None)
            for side, p in zip(names, sides, strict=True)}  # fmt: skip
    return replace(ev, haptic=mr_m, motor_metrics=em_m, budget=budget, hand=hand,
                   unavailable=MappingProxyType(unavailable), hand_of=tuple(sides))  # fmt: skip
