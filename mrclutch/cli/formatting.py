"""Text formatting shared by the commands (``evaluate``, ``optimize``, ``sweep``, ``compare``
…): an evaluation's tables (``format_evaluation`` and its sections), the optimiser's
verdict and limits, a design explained beside the paper preset, the FEM check table.
Presentation only: every figure comes from the application layer's JSON."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mrclutch.design import ClutchDesign
from mrclutch.outputs import CLUTCH_ROWS, HAND_ROWS, format_kmax, output, row_label
from mrclutch.process import MAX_ECCENTRICITY
from mrclutch.verdict import verdict_lines

if TYPE_CHECKING:  # annotations only: evaluate and compare do not load the optimiser
    from mrclutch.optimize import Constraints, WorstCase


def format_robust(r: dict) -> list[str]:
    """Nominal, worst and best of each verdict over the ranges (docs/verdicts.md)."""
    lines = ["", f"{'over the uncertain inputs (MR pair)':<40}{'nominal':>10}{'worst':>10}"
             f"{'best':>10}"]  # fmt: skip
    rows = (("largest stable K (N/m)", "max_stable_K_N_per_m", 1.0),
            ("largest passive K (N/m)", "max_passive_K_N_per_m", 1.0),
            ("bandwidth at K_max (Hz)", "bandwidth_hz", 1.0),
            ("rendering area (dB·decade)", "rendering_area_dB_decade", 1.0),
            ("Z-width area (N²·s/m²)", "zwidth_area_N2_s_per_m2", 1.0))  # fmt: skip
    for label, key, sc in rows:
        v = r[key]
        lines.append(f"  {label:<38}" + "".join(f"{_g(v[c] * sc):>10}" for c in
                                                 ("nominal", "worst", "best")))  # fmt: skip
    words = {"always": "yes, for every value", "never": "no, for any value",
             "depends": "depends on the inputs"}  # fmt: skip
    for n in ("stable", "passive"):
        v = r["verdicts"][n]
        lines.append(f"  {n + ' at K':<38}{'yes' if v['nominal'] else 'no':>10}  "
                     f"{words[v['holds']]}")  # fmt: skip
    g = r["ranges"]
    lines.append(f"  ranges: m1 {g['m1_kg'][0] * 1e3:.3g}–{g['m1_kg'][1] * 1e3:.3g} g, b1 "
                 f"{g['b1_N_s_per_m'][0]:.3g}–{g['b1_N_s_per_m'][1]:.3g} N·s/m, delay "
                 f"{g['delay_s'][0] * 1e3:.3g}–{g['delay_s'][1] * 1e3:.3g} ms, K_max "
                 f"{g['K_max_N_per_m'][0]:.4g}–{g['K_max_N_per_m'][1]:.4g} N/m "
                 "([uncertainty], docs/verdicts.md)")  # fmt: skip
    return lines


def format_measured(rows: list) -> list[str]:
    """Model against the bench (``[measured]``), error in %."""
    if not rows:
        return []
    scale = {"N·m": (1.0, "N·m"), "s": (1e3, "ms"), "kg": (1e3, "g"), "N·s/m": (1.0, "N·s/m")}
    lines = ["", f"{'model against the bench ([measured])':<34}{'model':>10}{'measured':>10}"
             f"{'error':>9}"]  # fmt: skip
    for r in rows:
        f, unit = scale[r["unit"]]
        lines.append(f"  {r['quantity'] + f' ({unit})':<32}{r['model'] * f:>10.4g}"
                     f"{r['measured'] * f:>10.4g}{r['error'] * 100:>+8.1f} %  "
                     f"{r['model_source']}")  # fmt: skip
    return lines


#: The notes that say the current limit is not the typed max_current_A (mrclutch.pipeline).
CAP_NOTE = "the current-density limit caps the current"


SUPPLY_NOTE = "supply holds at most"


def format_evaluation(data: dict, lead: bool = True) -> str:
    """A person's view of ``verdict.judge``'s data: the verdict first, said once (``lead``
    False: a table inside another command's output, which leads with its own verdict
    line; the table then names its verdict's status and fidelity only)."""
    c = data["clutch"]
    v = data["verdict"]
    head = (verdict_lines(data) if lead else
            [f"(verdict at {v['fidelity']} fidelity: {v['status']}; the line above is the "
             "design's)"])  # fmt: skip
    lines = [
        *head,
        f"design {data['design']}  (fidelity {data['fidelity']}: inertia by "
        f"{c['methods']['inertia']}, torque by {c['methods']['torque']})",
        "",
        "clutch",
    ]
    capped = any(CAP_NOTE in n or SUPPLY_NOTE in n for n in c["notes"])
    for key in CLUTCH_ROWS:
        o = output(key)
        mark = "  (capped: see the note below)" if key == "max_current_A" and capped else ""
        lines.append(f"  {o.label:<30}{o.display(c[key]):>14} {o.shown_unit}{mark}")
    d, length = c["envelope_m"]
    lines += [
        f"  {'envelope':<30}{f'Ø{d * 1e3:.3g} × {length * 1e3:.3g}':>14} mm",
        "",
        f"{'at the hand':<32}{'MR pair':>14}{'Maxon 136206':>14}",
    ]
    h, m = data["haptic"], data["motor"]
    for key in HAND_ROWS:
        o = output(key)
        lines.append(f"  {row_label(key):<30}{o.display(h[key]):>14}{o.display(m[key]):>14}")
    if m["gearing"] is None:
        lines.append(f"  (motor unavailable: {m['note']})")
    else:
        lines.append(f"  (motor geared ×{m['gearing']:.3g} to the MR pair's force)")
    rule = (data.get("render") or {}).get("describe", "K_max = F_max/d")
    lines.append(f"  K rendered {h['K_N_per_m']:.4g} N/m ({rule}; "
                 f"{format_kmax(h['K_max_N_per_m'], 'MR pair, ' + data['source'])}, Eq. 4 of "
                 "its force); m1, b1 and the bandwidths from the same source")  # fmt: skip
    g, gl = data["bandwidth_gain"], data["bandwidth_gain_lumped"]
    lines.append(f"bandwidth gain MR over motor: {_pct(gl)} lumped, {_pct(g)} on the full response")
    if data.get("robust"):
        lines += format_robust(data["robust"])
    lines += format_measured(data.get("measured") or [])
    lines += format_zwidth(data["zwidth"])
    lines += format_hand(data["hand"])
    lines += format_budget(data["budget"])
    lines += format_response(data["response"])
    lines += [
        f"unavailable: {k}: {why}" for k, why in data.get("unavailable", {}).items() if k != "motor"
    ]  # the motor's reason is printed under its column
    return "\n".join(lines)


def format_response(r: dict) -> list[str]:
    """The torque's response time from the geometry (magnetics.dynamics; docs/dynamics.md)."""
    ms = lambda v: f"{v * 1e3:.3g}"  # noqa: E731
    src = r["delay_source"]
    lines = ["", f"torque response (magnetics.dynamics; the haptic model uses the {src} delay)",
             f"  coil: L {r['inductance_0A_H'] * 1e3:.3g} mH at 0 A, "
             f"{r['inductance_peak_H'] * 1e3:.3g} mH at the peak current (secant "
             f"{r['inductance_secant_peak_H'] * 1e3:.3g} mH), R {r['coil_resistance_ohm']:.3g} Ω; "
             f"amplifier {r['supply_voltage_V']:g} V, {r['current_bandwidth_hz']:g} Hz",
             f"  {'electrical (10–90 % / ln 9)':<30}{ms(r['electrical_time_constant_s']):>10} ms",
             f"  {'eddy currents':<30}{ms(r['eddy_time_constant_s']):>10} ms"]  # fmt: skip
    for k, e in r["eddy"].items():
        lines.append(f"    {k:<28}{ms(e['contribution_s']):>10} ms  (mean delay "
                     f"{ms(e['mean_delay_s'])} ms × share {e['weight']:.2g})")  # fmt: skip
    lines += [
        f"  {'fluid (assumed)':<30}{ms(r['fluid_time_constant_s']):>10} ms",
        f"  {'equivalent delay Σ T':<30}{ms(r['torque_delay_s']):>10} ms  (typed: "
        f"{ms(r['typed_delay_s'])} ms); −3 dB at {r['torque_bandwidth_hz']:.3g} Hz",
        f"  largest stable K: {_g(r['max_stable_K_typed_delay_N_per_m'])} N/m with the typed "
        f"delay, {_g(r['max_stable_K_torque_delay_N_per_m'])} with Σ T, "
        f"{_g(r['max_stable_K_lags_N_per_m'])} with the lags themselves",
    ]
    return lines


def _g(v: float | None, spec: str = ".4g") -> str:
    """A figure, or — where it is unavailable (None or NaN; the output says why)."""
    return "—" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def _bounded(v: float | None, side: dict | None = None) -> str:
    """A Z-width figure; inf (or None, its JSON form) where the set is unbounded; — where
    the side is unavailable (its ``note`` says why)."""
    if side is not None and "note" in side:
        return "—"
    return f"{v:.4g}" if v is not None and math.isfinite(v) else "unbounded"


def format_zwidth(zw: dict) -> list[str]:
    """The Z-width (passive virtual springs and dampers, continuous time) of both sides."""
    lines = ["Z-width: the (K, B) the device renders passively (mrclutch.haptics.zwidth)",
             f"  {'':<30}{'MR pair':>14}{'Maxon 136206':>14}"]  # fmt: skip
    for key, label in (("K_max_at_B0_N_per_m", "largest K at B = 0 (N/m)"),
                       ("B_max_at_K0_N_s_per_m", "largest B at K = 0 (N·s/m)"),
                       ("zwidth_area_N2_s_per_m2", "area ∫ΔK dB (N²·s/m²)")):  # fmt: skip
        a, b = (_bounded(zw[side][key], zw[side]) for side in ("mr", "motor"))
        lines.append(f"  {label:<30}{a:>14}{b:>14}")
    return lines


def format_hand(hand: dict) -> list[str]:
    """Stability with a hand holding the lever, and the force felt in free motion."""
    mr, em = hand["mr"], hand["motor"]
    if mr.get("note"):  # the MR side's hand figures are unavailable: say why, once
        return ["With a hand on the lever (mrclutch.haptics.hand)", f"  {mr['note']}"]
    mo = mr["motion"]
    h = mr["worst_hand"]
    yes = {True: "yes", False: "no", None: "—"}

    def col(side: dict, key: str, scale: float = 1.0) -> str:
        return f"{_g(None if side[key] is None else side[key] * scale):>14}"

    return [
        "With a hand on the lever (mrclutch.haptics.hand; hand range in docs/hand.md)",
        f"  {'':<30}{'MR pair':>14}{'Maxon 136206':>14}",
        f"  {'stable at K, any hand':<30}{yes[mr['coupled_stable']]:>14}"
        f"{yes[em['coupled_stable']]:>14}",
        f"  {'largest K stable, any hand':<30}{col(mr, 'max_stable_K_all_hands_N_per_m')}"
        f"{col(em, 'max_stable_K_all_hands_N_per_m')}  N/m",
        f"  {'largest K stable, hands off':<30}{col(mr, 'max_stable_K_hands_off_N_per_m')}"
        f"{col(em, 'max_stable_K_hands_off_N_per_m')}  N/m",
        f"  {'backdrive force (K = 0)':<30}{col(mr, 'backdrive_force_N', 1e3)}"
        f"{col(em, 'backdrive_force_N', 1e3)}  mN at ±{mo['amplitude_m'] * 1e3:g} mm, "
        f"{mo['frequency_hz']:g} Hz",
        f"  {'felt mass (K = 0)':<30}{col(mr, 'felt_mass_kg', 1e3)}"
        f"{col(em, 'felt_mass_kg', 1e3)}  g",
        f"  {'felt damping (K = 0)':<30}{col(mr, 'felt_damping_N_s_per_m')}"
        f"{col(em, 'felt_damping_N_s_per_m')}  N·s/m",
        f"  worst hand for the MR pair: {h['m_kg']:g} kg, {h['b_N_s_per_m']:g} N·s/m, "
        f"{h['k_N_per_m']:g} N/m ({mr['hands_checked']} hands checked)",
        *(f"  note ({side}): {n}" for side, d in hand.items() for n in d.get("notes") or ()),
    ]


def format_budget(budget: dict) -> list[str]:
    """b1 and m1 of the MR pair as tables of named terms, beside the paper's Table 2."""
    lines: list[str] = []
    for key, unit, scale in (("b1_N_s_per_m", "N·s/m", 1.0), ("m1_kg", "g", 1e3)):
        b = budget[key]
        lines += ["", f"{key.split('_')[0]} of the MR pair at the hand ({unit})"]
        for t in b["terms"]:
            lines.append(f"  {t['name']:<28}{t['value'] * scale:>10.4g}{t['share'] * 100:>7.1f} %"
                         f"  {t['source']}")  # fmt: skip
        lines.append(f"  {'total':<28}{b['total'] * scale:>10.4g}")
        if not budget["paper_clutch"]:  # Table 2 identified the paper's clutch, not this one
            lines.append(f"  {'paper clutch, Table 2':<28}{b['paper_table2'] * scale:>10.4g}"
                         "  (for scale: another clutch)")  # fmt: skip
            continue
        lines.append(f"  {'paper, Table 2':<28}{b['paper_table2'] * scale:>10.4g}")
        lines.append(f"  {'unexplained':<28}{b['unexplained'] * scale:>10.4g}"
                     f"  ({b['ratio_to_paper'] * 100:.0f} % of Table 2 explained)")  # fmt: skip
        lines += [f"  least certain: {why}" for why in b.get("least_certain", ())]
    if not budget["paper_clutch"]:
        return lines
    t2 = budget["with_table2_b1"]
    lines.append(
        f"with Table 2's b1 = {t2['b1_N_s_per_m']:g} N·s/m: passive at K "
        f"{'yes' if t2['passive'] else 'no'}, largest passive K "
        f"{t2['max_passive_K_N_per_m']:.4g} N/m, largest stable K "
        f"{t2['max_stable_K_N_per_m']:.4g} N/m"
    )
    return lines


def _pct(v: float | None) -> str:
    return "—" if v is None else f"{v * 100:+.1f} %"


def _bound(bound: float) -> str:
    """A map bound as the table prints it."""
    return "off map" if not math.isfinite(bound) else f"{bound:.1%}"


def format_verified(rows: list, key: str, fem_size: float, workers: int, seconds: float
                    ) -> str:  # fmt: skip
    """The --verify-top table: the network's (the sweep's) and the circuit's max torque
    against the FEM's, row by row."""
    head = (f"{'design':>8} {key:>24} {'fast (network) N·m':>19} "
            f"{f'FEM {fem_size * 1e3:g} mm N·m':>17} {'error':>8} {'map bound':>10} "
            f"{'circuit N·m':>12} {'error':>8} {'map bound':>10}")  # fmt: skip
    lines = [f"FEM check of the {len(rows)} best rows by {key} ({len(rows)} designs on "
             f"{workers} worker{'s' * (workers != 1)}, {seconds:.1f} s):", head]  # fmt: skip
    for r in rows:
        bound = _bound(r.bound)
        lines.append(f"{r.design_id:>8} {r.objective_value:>24.6g} {r.fast_torque:>19.5f} "
                     f"{r.fem_torque:>17.5f} {r.error:>+8.2%} {bound:>10} "
                     f"{r.circuit_torque:>12.5f} {r.circuit_error:>+8.2%} "
                     f"{_bound(r.circuit_bound):>10}")  # fmt: skip
    if rows:
        err = [abs(r.error) for r in rows]
        inside = sum(r.within_bound for r in rows)
        lines.append(f"network vs FEM: max |error| {max(err):.2%}, median {_median(err):.2%}; "
                     f"{inside} of {len(rows)} within the map's bound")  # fmt: skip
        circ = [abs(r.circuit_error) for r in rows]
        inside = sum(r.circuit_within_bound for r in rows)
        lines.append(f"circuit vs FEM: max |error| {max(circ):.2%}, median {_median(circ):.2%}; "
                     f"{inside} of {len(rows)} within its map's bound")  # fmt: skip
    return "\n".join(lines)


def _median(values: list[float]) -> float:
    """statistics.median's value, its steps on the same numbers (the middle one, or the
    mean of the two middle ones), without importing statistics: its fractions and decimal
    modules were a part of every evaluate's start for a line of the FEM check (issue 40)."""
    data = sorted(values)
    i = len(data) // 2
    return data[i] if len(data) % 2 else (data[i - 1] + data[i]) / 2


def explain_json(ev: dict) -> dict:
    """What ``explain`` prints, as JSON: bandwidth and resonance, the b1 budget, the
    thermal rating."""
    h, c, b = ev["haptic"], ev["clutch"], ev["budget"]["b1_N_s_per_m"]
    return {
        "bandwidth_hz": h["bandwidth_hz"], "bandwidth_lumped_hz": h["bandwidth_lumped_hz"],
        "resonance_hz": h["resonance_hz"], "K_N_per_m": h["K_N_per_m"],
        "K_max_N_per_m": h["K_max_N_per_m"] if "K_max_N_per_m" in h else h["K_N_per_m"],
        "m1_kg": h["m1_kg"], "m2_kg": h["m2_kg"], "k_N_per_m": h["k_N_per_m"],
        "b1_N_s_per_m": h["b1_N_s_per_m"],
        "b1_terms": {t["name"]: t["value"] for t in b["terms"]},
        "continuous_current_A": c["continuous_current_A"],
        "continuous_torque_N_m": c["continuous_torque_N_m"],
        "off_state_torque_N_m": c["off_state_torque_N_m"],
        "time_to_wire_limit_s": c["time_to_wire_limit_s"],
        "time_to_fluid_limit_s": c["time_to_fluid_limit_s"],
        "coil_power_W": c["coil_power_W"], "fidelity": ev["fidelity"],
    }  # fmt: skip


def _rule_note(paper: dict) -> list[str]:
    """Why the paper column's K is not the one ``evaluate --preset paper`` prints: beside a
    member it renders by the members' ``[render]`` rule (issue 39: one design, one answer,
    each K said with its rule)."""
    render = paper.get("render") or {}
    if render.get("rule", "K_max") == "K_max":
        return []
    return [f"    (both by the optimiser's rule: {render['describe']}; the paper preset's own "
            f"rule, K_max = F_max/d, renders {paper['haptic']['K_max_N_per_m']:.4g} N/m, as "
            f"evaluate --preset paper --fidelity {paper['fidelity']} prints)"]  # fmt: skip


def explain(ev: dict, paper: dict, label: str) -> str:
    """How a design's bandwidth and resonance relate, where its damping comes from (the
    b1 budget) and its thermal rating, beside the paper preset's."""
    a, p = explain_json(ev), explain_json(paper)

    def row(name: str, x: float, y: float, fmt: str = ".4g") -> str:
        def cell(v: float) -> str:
            return format(v, fmt) if math.isfinite(v) else "none" if math.isnan(v) else "∞"

        return f"  {name:<44}{cell(x):>12}{cell(y):>12}"

    def film(e: dict) -> float:
        return e["b1_terms"].get("drum gaps", 0.0) / e["b1_N_s_per_m"]

    lines = [
        f"\n{label} beside the paper preset ({a['fidelity']} / {p['fidelity']} fidelity):",
        f"  {'':<44}{label:>12}{'paper':>12}",
        row("bandwidth at the K rendered, full response (Hz)", a["bandwidth_hz"],
            p["bandwidth_hz"]),
        row("bandwidth, lumped √(K/(m1+m2)) (Hz)", a["bandwidth_lumped_hz"],
            p["bandwidth_lumped_hz"]),
        row("system resonance at K = 0 (Hz)", a["resonance_hz"], p["resonance_hz"]),
        row("K rendered (N/m)", a["K_N_per_m"], p["K_N_per_m"]),
        *_rule_note(paper),
        row("K_max = F_max/d (N/m)", a["K_max_N_per_m"], p["K_max_N_per_m"]),
        row("b1 at the hand (N·s/m)", a["b1_N_s_per_m"], p["b1_N_s_per_m"]),
        row("  share from the drum-gap films", film(a), film(p), ".0%"),
        row("continuous current (A)", a["continuous_current_A"], p["continuous_current_A"]),
        row("continuous torque above drag (N·m)",
            a["continuous_torque_N_m"] - a["off_state_torque_N_m"],
            p["continuous_torque_N_m"] - p["off_state_torque_N_m"]),
        row("off-state drag (N·m)", a["off_state_torque_N_m"], p["off_state_torque_N_m"]),
        row("time at peak to the wire limit (s)", a["time_to_wire_limit_s"],
            p["time_to_wire_limit_s"]),
        row("time at peak to the fluid limit (s)", a["time_to_fluid_limit_s"],
            p["time_to_fluid_limit_s"]),
        row("coil power at the current limit (W)", a["coil_power_W"], p["coil_power_W"]),
        "  how to read it: the bandwidth is the closed loop's, at the rendered K: the first "
        "frequency where the",
        "  effective stiffness Re(jωZ) turns from spring-like to mass-like (its "
        "anti-resonance, Eq. 1's √(K/(m1+m2))",
        "  with the transmission and the delay). The system resonance is another mode: "
        "the free device (K = 0,",
        "  Eq. 2), m1 and m2 swinging on the transmission stiffness k with b1 damping it. "
        "A bandwidth above the",
        "  resonance is no contradiction: K adds its stiffness to the loop (\"none\": "
        "Eq. 2's zeros are real, the",
        "  free device is overdamped and has no resonance). b1 is the drag the hand "
        "feels in free",
        "  motion (backdrive force); the drum films' share of it is viscous drag, which "
        "also heats the fluid and",
        "  lowers the continuous rating (the slip heat T_off·ω).",
    ]  # fmt: skip
    return "\n".join(lines)


def format_verdict(data: dict) -> str:
    """The optimum's haptic verdict beside its objective, and which limits were required."""
    v, req = data["verdict"], data["required"]
    h = (data.get("reference") or data["fast"])["haptic"]
    scope = "over the ranges" if v["over"] == "ranges" else "at nominal values"
    words = {"always": "yes", "never": "no", "depends": "depends"}
    need = {True: "required", False: "not required"}
    return "\n".join(
        [
            f"\nhaptic verdict ({v['fidelity']} fidelity) at K = {v['K_N_per_m']:.4g} N/m, "
            f"{data['objective']} {data['objective_value']:.4g}: {v['status'].upper()}",
            f"  stable at K {scope}:  {words[v['stable']['holds']]:<8}"
            f"({need[req['stable']]}); largest stable K {h['max_stable_K_N_per_m']:.4g} N/m "
            "at nominal values",
            f"  passive at K {scope}: {words[v['passive']['holds']]:<8}"
            f"({need[req['passive']]}); largest passive K {h['max_passive_K_N_per_m']:.4g} N/m "
            "at nominal values",
            "  requirements: " + ("all met" if data["requirements_met"] else "VIOLATED"),
        ]
    )


def limits_line(base: ClutchDesign, cons: Constraints, wc: WorstCase | None) -> str:
    """Every limit enforced, in one paragraph."""
    pr = base.process
    parts = [
        f"torque ≥ {cons.min_torque:g} N·m",
        f"mass ≤ {cons.max_mass * 1e3:g} g",
        f"envelope ≤ Ø{cons.max_diameter * 1e3:g} × {cons.max_length * 1e3:g} mm",
        f"continuous torque above drag ≥ {cons.min_continuous_torque:g} N·m",
        f"coil power ≤ {cons.max_power:g} W",
        f"time at peak ≥ {cons.peak_time:g} s",
    ]
    if cons.duty_time > 0:
        parts.append(f"{cons.duty_torque:g} N·m held ≥ {cons.duty_time:g} s")
    if cons.max_residual_torque is not None:
        parts.append(f"residual torque at 0 A ≤ {cons.max_residual_torque * 1e3:g} mN·m")
    if cons.max_ripple_force is not None:
        parts.append(f"runout ripple at the hand ≤ {cons.max_ripple_force * 1e3:g} mN")
    parts.append(f"gap ≥ {pr.min_gap * 1e3:.3g} mm (runout {pr.runout * 1e3:g} + tolerance "
                 f"{pr.tolerance * 1e3:g} mm, eccentricity ≤ {MAX_ECCENTRICITY:g})")  # fmt: skip
    parts.append(f"drum wall ≥ {pr.min_wall * 1e3:g} mm")
    need = [w for w, on in (("stable", cons.stable), ("passive", cons.passive)) if on]
    if need:
        parts.append(" and ".join(need) + (" over the uncertainty ranges at the K each design "
                     "renders (the largest K that holds them, at most K_max)" if wc is not None
                     else " at K = K_max (nominal values)"))  # fmt: skip
    return "limits: " + "; ".join(parts)
