"""Why a figure of an evaluation is null: the documented meaning of each NaN and infinity
by key (``NAN_MEANS``, ``INF_MEANS``, with ``mrclutch.duty``'s) and ``null_notes``, which
gives every null figure of a JSON its reason. Light to import (numpy only): the catalogue's
``haptic`` and ``compare`` print it without loading the pipeline (issue 40)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

#: Why a figure of ``evaluation_duty`` is null (None or NaN), by key (NAN_MEANS).
DUTY_NULLS: dict[str, str] = {
    "duty": "no duty torque asked: give --duty NM:S or a design's [duty] torque_N_m",
    "tau_y_coefficient_per_K": "the fluid gives no carrier expansion: τy(T) not modelled",
    "lifetime_energy_J_per_m3": "the fluid gives no lifetime dissipated energy",
    "life_h": "the fluid gives no lifetime dissipated energy: no life figure",
    "life_off_h": "the fluid gives no lifetime dissipated energy: no life figure",
    "duty_fluid_temperature_C": "no duty torque asked: no duty hold to compare",
    "covered": "no duty torque asked: no duty hold to compare",
}
#: What an infinite figure of ``evaluation_duty`` means (INF_MEANS).
DUTY_INFS: dict[str, str] = {
    "life_h": "never: the duty dissipates no power in the fluid",
    "life_off_h": "never: the off clutch dissipates no power (no slip)",
    "time_at_duty_s": "never: no duty torque asked (give --duty NM:S), or at the duty torque "
    "the coil and the fluid stay below their temperature limits",
}
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
