"""The one place a design becomes its verdict: the K it renders and whether it is stable
and passive there.

Every command that judges a design (``evaluate``, ``report``, ``compare``, ``haptic``,
``optimize``) calls :func:`judge` (or :func:`judge_evaluation` on an ``Evaluation`` it
already has), so a design file gets the same K, K_max and verdict from each of them at
one fidelity (docs/verdicts.md):

* the K comes from the design's ``[render]`` rule (mrclutch/render.py): K_max = F_max/d
  (Eq. 4 of [lebel]), the largest K stable and passive over the ``[uncertainty]`` ranges
  (the worst case, as the optimiser renders), or a typed K;
* the delay is the design's (``[operating] delay_source``: typed, or the torque
  response's equivalent delay);
* the verdict is taken over the ranges (``render.verdict = "robust"``, the default:
  ``mrclutch.robust.robust_verdicts``) or at nominal values only, and said in one line:
  **stable and passive**, **not** (a verdict fails for every value, or at nominal values
  when nominal), or **depends** (on the inputs whose threshold lies inside its range);
* the hand-held case (the hand's impedance coupled to the lever, mrclutch.haptics.hand) is
  a second, labelled verdict, never mixed with the first.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from mrclutch.design import ClutchDesign
from mrclutch.outputs import format_kmax
from mrclutch.pipeline import Evaluation, evaluate, rendered
from mrclutch.render import Render
from mrclutch.robust import (
    THRESHOLD_INPUTS,
    RobustBox,
    measured_comparison,
    robust_box,
    robust_verdicts,
)
from mrclutch.uncertainty import Uncertainty

#: The verdict's status: stable and passive for every value of the ranges (or at nominal
#: values without ranges); stable or passive fails for every value (or at nominal values);
#: the answer depends on the inputs.
STATUS = ("pass", "fail", "depends")
#: Relative margin under the worst-case limits of the ``worst_case`` rule (as the
#: optimiser's ``WorstCase.full``): the K holds at the limit's own rounding.
WORST_CASE_MARGIN = 1e-6


def rendered_K(ev: Evaluation, prepared: RobustBox | None = None) -> tuple[float, str]:
    """The K (N/m) ``ev.design`` renders by its ``[render]`` rule, and a note where the rule
    could not be followed (empty otherwise). ``prepared``: ``robust.robust_box(ev)`` if
    already made (the worst case reads its limits, which do not depend on K)."""
    rule = ev.design.render
    k_max = float(ev.mr.k_max)
    if rule.rule == "typed":
        assert rule.K is not None  # Render's own check
        return float(rule.K), ""
    if rule.rule == "K_max":
        return k_max, ""
    lim = (prepared if prepared is not None else robust_box(ev)).limits
    ks, kp = float(lim["max_stable_K_worst"][0]), float(lim["max_passive_K_worst"][0])
    cap = min(ks, kp) * (1 - WORST_CASE_MARGIN)
    if not (math.isfinite(cap) and cap > 0):
        return k_max, ("render.rule = 'worst_case': no K > 0 is stable and passive over the "
                       "whole of the ranges; rendering K_max instead")  # fmt: skip
    return min(k_max, cap), ""


def judge(design: ClutchDesign, fidelity: str = "fast", accuracy: float | None = None,
          robust: bool | None = None) -> dict[str, Any]:  # fmt: skip
    """``design`` evaluated at ``fidelity`` (or the ``accuracy`` target), rendering the K of
    its ``[render]`` rule, with its verdict: ``Evaluation.as_json()`` plus ``robust`` (the
    verdicts over the ranges, None when nominal), ``measured`` (the model against the
    design's bench) and ``verdict`` (:func:`verdict_of`). ``robust``: override the design's
    ``render.verdict`` (False: nominal values only). What every command prints."""
    return judge_evaluation(evaluate(design, fidelity, accuracy=accuracy), robust)


def judge_evaluation(ev: Evaluation, robust: bool | None = None) -> dict[str, Any]:
    """:func:`judge` of an evaluation already made (at any K: the rule sets it again). The
    box over the ranges is built once, for the worst-case K and the verdict alike."""
    over_ranges = ev.design.render.verdict == "robust" if robust is None else robust
    needs_box = over_ranges or ev.design.render.rule == "worst_case"
    prepared = robust_box(ev) if needs_box else None
    K, note = rendered_K(ev, prepared)
    if K != float(ev.haptic["K_N_per_m"]):
        ev = rendered(ev, K)
    data = ev.as_json()
    data["robust"] = robust_verdicts(ev, prepared=prepared) if over_ranges else None
    data["measured"] = measured_comparison(ev)
    data["render"] = {"rule": ev.design.render.rule, "describe": ev.design.render.describe(),
                      "verdict": "robust" if over_ranges else "nominal",
                      "K_N_per_m": K, "note": note}  # fmt: skip
    extra = ([note] if note else []) + resonance_notes(data)
    if extra:
        data["clutch"]["notes"] = [*data["clutch"]["notes"], *extra]
    data["verdict"] = verdict_of(data)
    return data


#: Relative nearness of a full-response bandwidth to the free lever's resonance below which
#: the bandwidth is the resonance's (``resonance_notes``).
AT_RESONANCE = 0.05


def resonance_notes(data: dict[str, Any], sides: tuple[str, ...] = ("haptic", "motor")
                    ) -> list[str]:  # fmt: skip
    """Why a full-response bandwidth equal to a resonance is no error: where a side's first
    k_eff crossing (the bandwidth, mrclutch.haptics.model.bandwidth) lies within
    ``AT_RESONANCE`` of the free lever's resonance (Eq. 2), the crossing is that mode's
    (its reflected mass is too large for √(K/(m1+m2)) to come first), and a gain on the
    full response compares a spring's bandwidth with a mode. ``sides``: the JSON's
    ``haptic`` (the MR pair) and/or ``motor`` (the equal-force Maxon)."""
    out = []
    labels = {"haptic": "MR pair", "motor": "Maxon 136206"}
    for side, label in ((s, labels[s]) for s in sides):
        h = data.get(side) or {}
        bw, res, lumped = h.get("bandwidth_hz"), h.get("resonance_hz"), h.get("bandwidth_lumped_hz")
        if bw is None or res is None or not (math.isfinite(bw) and math.isfinite(res)):
            continue
        if abs(bw / res - 1.0) <= AT_RESONANCE:
            out.append(f"the {label}'s full-response bandwidth {bw:.4g} Hz is its transmission "
                       f"resonance ({res:.4g} Hz): its effective stiffness stays spring-like up "
                       f"to that mode, far above its lumped √(K/(m1+m2)) = {lumped:.4g} Hz; "
                       "read the lumped figure for the spring it renders, and a gain on the "
                       "full response as spring against mode")  # fmt: skip
    return out


def _holds_nominal(h: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The nominal verdicts at K in ``robust_verdicts``' form (no ranges: always or never)."""
    stable = bool(h["K_N_per_m"] <= h["max_stable_K_N_per_m"] * (1 + 1e-9))
    passive = bool(h["passive"])
    return {n: {"nominal": v, "holds": "always" if v else "never", "thresholds": {}}
            for n, v in (("stable", stable), ("passive", passive))}  # fmt: skip


def inside(t: dict[str, Any]) -> bool:
    """Whether a threshold (``robust.threshold`` with its ``range``) lies inside its range:
    only then does that input alone decide the verdict."""
    lo, hi = t["range"]
    return bool(lo <= t["value"] <= hi)


def _threshold_text(field: str, t: dict[str, Any]) -> str:
    label, unit, scale = next((lb, u, s) for f, lb, u, s in THRESHOLD_INPUTS if f == field)
    lo, hi = (x * scale for x in t["range"])
    return (f"{label} {t['sense']} {t['value'] * scale:.3g} {unit} (its range "
            f"{lo:.3g}–{hi:.3g} {unit})")  # fmt: skip


def verdict_of(data: dict[str, Any]) -> dict[str, Any]:
    """The one verdict of a judged design (``judge``'s data): ``status`` (one of
    ``STATUS``), ``line`` (the sentence every command leads with), the K, K_max, fidelity,
    rule and delay it is taken at, per verdict whether it holds ("always", "never",
    "depends") with the thresholds inside their ranges, and ``hand``: the second, labelled
    verdict of the lever held by a hand."""
    h = data["haptic"]
    r = data.get("robust")
    verdicts = r["verdicts"] if r else _holds_nominal(h)
    holds = {n: verdicts[n]["holds"] for n in ("stable", "passive")}
    deciding = {n: {f: t for f, t in verdicts[n]["thresholds"].items() if inside(t)}
                for n in ("stable", "passive")}  # fmt: skip
    if all(v == "always" for v in holds.values()):
        status = STATUS[0]
    elif any(v == "never" for v in holds.values()):
        status = STATUS[1]
    else:
        status = STATUS[2]
    words = {"stable": ("stable", "unstable"), "passive": ("passive", "not passive")}
    scope = "over the whole of the [uncertainty] ranges" if r else "at nominal values"
    parts = []
    if status == "pass":
        parts.append(f"stable and passive {scope}")
    ks = h.get("max_stable_K_N_per_m")  # NaN: the scan cannot resolve this loop (inf: none)
    unresolved = ks is None or math.isnan(ks)
    for n in ("stable", "passive") if status != "pass" else ():
        yes, no = words[n]
        if n == "stable" and unresolved:  # not met, but not shown unstable either
            parts.append("stability unknown (the stability scan cannot resolve this loop: an "
                         "extreme transmission or delay), not taken as stable")  # fmt: skip
        elif holds[n] == "always":
            parts.append(f"{yes} {scope}")
        elif holds[n] == "never":
            parts.append(f"{no} {scope}")
        else:
            nominal = yes if verdicts[n]["nominal"] else no
            cond = " or ".join(_threshold_text(f, t) for f, t in deciding[n].items())
            parts.append(f"{yes} only if {cond}" if cond else
                         f"{yes} for part of the ranges (no one input decides it: m1, b1, the "
                         "delay and K_max jointly)")  # fmt: skip
            parts[-1] += f", {nominal} at nominal values"
    render = data.get("render") or {}
    rule = render.get("describe", "K_max = F_max/d")
    delay_src = data["response"].get("delay_source", "fixed") if data.get("response") else "fixed"
    source = data.get("source", data["fidelity"])
    kmax = format_kmax(h["K_max_N_per_m"], f"MR pair, {source}")
    at = (f"K = {h['K_N_per_m']:.4g} N/m ({rule}; {kmax}), "
          f"delay {h['delay_s'] * 1e3:.3g} ms ({'typed' if delay_src == 'fixed' else delay_src}), "
          f"{source}")  # fmt: skip
    line = f"VERDICT: {status.upper()} — " + "; ".join(parts) + f" — at {at}."
    return {
        "status": status,
        "line": line,
        "over": "ranges" if r else "nominal",
        "K_N_per_m": h["K_N_per_m"],
        "K_max_N_per_m": h["K_max_N_per_m"],
        "rule": render.get("rule", "K_max"),
        "fidelity": data["fidelity"],
        "delay_s": h["delay_s"],
        "delay_source": delay_src,
        "stable": {"holds": holds["stable"], "nominal": verdicts["stable"]["nominal"],
                   "thresholds": deciding["stable"]},
        "passive": {"holds": holds["passive"], "nominal": verdicts["passive"]["nominal"],
                    "thresholds": deciding["passive"]},
        "hand": hand_verdict(data),
    }  # fmt: skip


def hand_verdict(data: dict[str, Any]) -> dict[str, Any]:
    """The second verdict: the MR pair held by a hand (the hand models of docs/hand.md
    coupled to the lever, mrclutch.haptics.hand), at the same K, labelled as such."""
    hm = (data.get("hand") or {}).get("mr") or {}
    if hm.get("note") or hm.get("coupled_stable") is None:
        why = hm.get("note", "the hand figures were not computed")
        return {"stable": None, "line": f"held by a hand: unknown ({why})", "note": why}
    ok = bool(hm["coupled_stable"])
    w = hm["worst_hand"]
    line = (f"held by a hand (second verdict, docs/hand.md): "
            f"{'stable' if ok else 'NOT stable'} at K = {hm['K_N_per_m']:.4g} N/m for "
            f"{'every hand checked' if ok else 'the worst hand checked'}; stable up to "
            f"{hm['max_stable_K_all_hands_N_per_m']:.4g} N/m for every hand (worst: "
            f"{w['m_kg']:g} kg, {w['b_N_s_per_m']:g} N·s/m, {w['k_N_per_m']:g} N/m)")  # fmt: skip
    return {"stable": ok, "line": line}


def verdict_lines(data: dict[str, Any]) -> list[str]:
    """The two lines every command that judges a design leads with."""
    v = data["verdict"]
    return [v["line"], "  " + v["hand"]["line"]]


def for_workshop(design: ClutchDesign, uncertainty: Uncertainty | None
                 ) -> tuple[ClutchDesign, list[str]]:  # fmt: skip
    """``design`` as the optimiser hands it on (its members, ``--out``): rendering by the
    optimiser's own rule — with ``uncertainty`` (the ranges its worst case was taken over,
    written into the file) the largest K stable and passive over them, judged over them;
    without (``--nominal``) K_max, judged at nominal values — and with no ``[measured]``
    table (a bench belongs to a built device). Returns the design and the notes to print."""
    notes = []
    if design.measured is not None:
        notes.append("the base design's [measured] bench table was dropped from the files "
                     "written: a bench belongs to a built device")  # fmt: skip
    if uncertainty is not None:
        render = Render("worst_case")
    else:
        render, uncertainty = Render("K_max", verdict="nominal"), design.uncertainty
    return replace(design, render=render, uncertainty=uncertainty, measured=None), notes
