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

This module is the single-design path (``evaluate``, ``rendered``, the ``Evaluation`` and
what its null figures mean). Its stages live by what they compute: the clutch figures in
``mrclutch.clutch``, the pair and the motor at the hand in ``mrclutch.at_hand``, the batch
path of sweeps and the optimiser in ``mrclutch.fast_batch``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.section import build_section
from geometry.validation import ParameterError
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
from mrclutch.duty import DUTY_INFS, DUTY_NULLS, evaluation_duty
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
        return evaluation_duty(self)

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


#: Why a figure is NaN (null in JSON) where that is its documented meaning, by key.
NAN_MEANS: dict[str, str] = {
    "resonance_hz": "no resonance: the free lever is overdamped (every zero of Eq. 2 is "
    "real; mrclutch.haptics.model.resonance)",
    "B_N_s_per_m": "no damping grid: B_top is unbounded (every damper renders passively at "
    "K = 0), so [0, B_top] cannot be sampled; the intercepts and the area say the rest",
    "K_max_N_per_m": "no passive K >= 0 at that damping (the Z-width is empty there), or no "
    "damping grid (B_N_s_per_m null)",
    "bandwidth_gain": "one side has no bandwidth (the motor unavailable, or no crossing)",
    "max_stable_K_N_per_m": "unknown: the stability scan cannot resolve this loop (it would "
    "need more than 2e5 phase-resolved frequencies, or 2e6 a step: an extreme transmission "
    "or delay)",
    "max_stable_K_torque_delay_N_per_m": "unknown: the stability scan cannot resolve this "
    "loop with that delay, or the lags are not finite",
    "bandwidth_gain_lumped": "one side has no bandwidth (the motor unavailable)",
}
NAN_MEANS["K_min_N_per_m"] = NAN_MEANS["K_max_N_per_m"]
NAN_MEANS["robust"] = (
    "not asked: the verdict is at nominal values only (--no-uncertainty, "
    "or the design's [render] verdict = 'nominal')"
)
NAN_MEANS["K_max_at_B0_N_per_m"] = (
    "no passive K >= 0 even with no virtual damping (the Z-width is empty at B = 0)"
)
NAN_MEANS["delay"] = (
    "the delay's range is not given: it spans the typed delay and the torque "
    "response's equivalent delay at the corners (mrclutch.robust)"
)
NAN_MEANS["fluid_temperature"] = "the fluid's temperature range is not given: the operating one"
NAN_MEANS["max_stable_K_typed_delay_N_per_m"] = NAN_MEANS["max_stable_K_N_per_m"]
NAN_MEANS["max_stable_K_lags_N_per_m"] = NAN_MEANS["max_stable_K_torque_delay_N_per_m"]
#: What an infinite figure (null in JSON, which has no infinity) means, by key.
INF_MEANS: dict[str, str] = {
    "time_to_wire_limit_s": "never: the coil stays below its temperature limit at the peak current",
    "time_to_fluid_limit_s": "never: the fluid stays below its temperature limit at the "
    "peak current",
}
NAN_MEANS.update(DUTY_NULLS)  # issue 41's figures (mrclutch.duty)
INF_MEANS.update(DUTY_INFS)
_UNBOUNDED = "unbounded (inf): no finite limit exists; JSON has no infinity"
#: The ends of a figure's range over the uncertain inputs (the ``robust`` block).
RANGE_ENDS = frozenset({"nominal", "worst", "best"})


def null_notes(data: Mapping[str, Any]) -> dict[str, str]:
    """Every figure of an evaluation's JSON that would be null (None, NaN or ±inf), by its
    path ("zwidth/mr/K_max_N_per_m[3]" as "zwidth/mr/K_max_N_per_m"), with why: the
    documented meaning of a NaN or an inf, or the note of an unavailable side. Figures
    left without a reason would be a bug (tests/mrclutch/test_robust_inputs.py)."""
    out: dict[str, str] = {}

    def walk(v: Any, path: tuple[str, ...], note: str | None) -> None:
        if isinstance(v, Mapping):
            here = v.get("note") if isinstance(v.get("note"), str) else note
            for k, x in v.items():
                if k not in ("nulls", "note"):
                    walk(x, (*path, str(k)), here)
            return
        if isinstance(v, (list, tuple, np.ndarray)) and np.ndim(v) > 0:
            for x in v:
                walk(x, path, note)
            return
        # a range's end (robust/<figure>/nominal|worst|best) means what its figure's NaN does
        meaning = NAN_MEANS.get(path[-1]) or (
            NAN_MEANS.get(path[-2]) if len(path) > 1 and path[-1] in RANGE_ENDS else None
        )
        if v is None or (isinstance(v, (float, np.floating)) and math.isnan(v)):
            why = note or meaning
        elif isinstance(v, (float, np.floating)) and math.isinf(v):
            why = INF_MEANS.get(path[-1], _UNBOUNDED)
        else:
            return
        key = "/".join(path)
        if key not in out:
            out[key] = why or "not computed (no reason recorded)"

    walk(data, (), None)
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
    fig = clutch_figures(design, fidelity, accuracy)
    if accuracy is not None:
        fidelity = f"accuracy={accuracy:g}"
    resp = torque_response(
        build_section(design.clutch, design.materials).table,
        fig.max_current,
        design.amplifier,
        design.laminations,
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
                                 float(backdrive_force(mr))))  # fmt: skip
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
