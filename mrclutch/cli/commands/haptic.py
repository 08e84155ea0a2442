"""``mrclutch haptic`` (one actuator on the lever → metrics) and ``mrclutch compare`` (the
paper's equal-force comparison, Fig. 7c). Given a design (``DESIGN.toml`` or ``--preset``)
both judge it as ``evaluate`` does (``mrclutch.verdict``: its ``[render]`` K, its verdict,
the equal-force Maxon geared from its K_max at the same fidelity). Imports nothing heavy at
module level."""

from __future__ import annotations

import argparse
import math
from typing import Any

from geometry.validation import check_choice, check_range
from mrclutch.cli.commands._common import add_design_args, load_design_args, print_json
from mrclutch.cli.errors import CLIError
from mrclutch.cli.plots.haptic import compare_figure
from mrclutch.design import MAX_DELAY
from mrclutch.haptic_run import (
    ACTUATOR_NAMES,
    GEARING_RANGE,
    LEVER_RANGE,
    STIFFNESS_MAX,
    TABLE2_SOURCE,
    WORKSPACE_RANGE,
    catalogue_metrics,
    catalogue_source,
    compare_k_source,
    compare_params,
    compare_result,
)
from mrclutch.outputs import format_kmax
from mrclutch.pipeline import evaluate, null_notes
from mrclutch.verdict import judge_evaluation, resonance_notes, verdict_lines


def register(sub: Any) -> None:
    p = sub.add_parser(
        "haptic",
        help="one actuator + transmission + virtual spring K → haptic metrics",
        description="Reflect a catalogue actuator through the paper's bench transmission "
        "(Eq. 3-4) and report the 2-DOF lever metrics at the virtual stiffness K.",
    )
    p.add_argument(
        "--actuator",
        default="mr-paper",
        metavar="NAME",
        help=f"catalogue actuator: {', '.join(ACTUATOR_NAMES)} (default mr-paper)",
    )
    p.add_argument("--lever-mm", type=float, default=170.0, help="lever length [mm] (170)")
    p.add_argument("--gearing", type=float, default=1.0, help="gear factor G multiplying n (1)")
    _common(p)
    _design(p)
    p.set_defaults(func=run_haptic)

    c = sub.add_parser(
        "compare",
        help="the paper's equal-force comparison: MR pair vs Maxon 136206 (Fig. 7c)",
        description="Table 2's identified MR set against the Maxon 136206 (Table 1 inertia "
        "through the EM transmission), both at the same virtual stiffness K (default: the "
        "smaller K_max, i.e. the force both can produce).",
    )
    _common(c)
    _design(c)
    c.add_argument("--plot", metavar="FILE.png", help="write Bode / effective impedance figure")
    c.set_defaults(func=run_compare)


def _design(p: argparse.ArgumentParser) -> None:
    """A design instead of the catalogue: judged as ``evaluate`` judges it."""
    add_design_args(p)
    p.add_argument("--fidelity", default="fast",
                   help="with a design: the fidelity it is evaluated at (default fast), as "
                   "evaluate --fidelity")  # fmt: skip


def _judged(args: argparse.Namespace, command: str) -> tuple[Any, dict[str, Any]] | None:
    """(Evaluation, ``verdict.judge`` data) of the design the options name, or None for the
    catalogue. The catalogue's options are refused beside a design (the design has its own
    K rule, delay and transmission)."""
    if args.design is None and args.preset is None:
        return None
    for opt, given in (("--stiffness", args.stiffness is not None),
                       ("--delay-ms", args.delay_ms is not None),
                       ("--workspace-mm", args.workspace_mm != 50.0),
                       ("--actuator", getattr(args, "actuator", "mr-paper") != "mr-paper"),
                       ("--lever-mm", getattr(args, "lever_mm", 170.0) != 170.0),
                       ("--gearing", getattr(args, "gearing", 1.0) != 1.0)):  # fmt: skip
        if given:
            raise CLIError(f"{command} {opt}: not with a design (its [render], [operating] and "
                           "[transmission] tables set it)")  # fmt: skip
    check_choice("--fidelity", args.fidelity, ("fast", "reference"))

    ev = evaluate(load_design_args(args), args.fidelity)
    data = judge_evaluation(ev)
    return ev, data


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--stiffness", type=float, default=None, help="virtual stiffness K [N/m] (default K_max)"
    )
    p.add_argument(
        "--delay-ms", type=float, default=None, help="actuator delay [ms] (default: catalogue)"
    )
    p.add_argument(
        "--workspace-mm", type=float, default=50.0, help="workspace d for K_max [mm] (50)"
    )
    p.add_argument("--json", action="store_true", help="print JSON (SI keys)")


def _edge(args: argparse.Namespace) -> tuple[float | None, float | None, float]:
    """mm/ms at the edge → SI, validated with the option's own name."""
    K = None
    if args.stiffness is not None:
        K = check_range("--stiffness", args.stiffness, 0.0, STIFFNESS_MAX, " N/m", lo_open=True)
    delay = None
    if args.delay_ms is not None:
        delay = check_range("--delay-ms", args.delay_ms, 0.0, MAX_DELAY * 1e3, " ms") * 1e-3
    lo, hi = WORKSPACE_RANGE
    workspace = check_range("--workspace-mm", args.workspace_mm, lo * 1e3, hi * 1e3, " mm") * 1e-3
    return K, delay, workspace


def run_haptic(args: argparse.Namespace) -> int:
    K, delay, workspace = _edge(args)
    judged = _judged(args, "haptic")
    if judged is not None:
        _, data = judged
        h = data["haptic"]
        notes = resonance_notes(data, ("haptic",))  # a bandwidth that is a resonance
        if args.json:
            out = {**h, "source": data["source"], "verdict": data["verdict"],
                   "render": data["render"], "notes": notes}  # fmt: skip
            print_json({**out, "nulls": null_notes(out)})  # every null with its reason
            return 0
        print("\n".join(verdict_lines(data)))
        print(f"MR pair of design {data['design']} ({data['source']})")
        _print_metrics(h, f"MR pair, {data['source']}", rule=data["render"]["describe"])
        for note in notes:
            print(f"note: {note}")
        return 0
    lo, hi = LEVER_RANGE  # Transmission's own rule, stated in the option's unit
    lever = check_range("--lever-mm", args.lever_mm, lo * 1e3, hi * 1e3, " mm") * 1e-3
    gearing = check_range("--gearing", args.gearing, *GEARING_RANGE)
    name = check_choice("--actuator", args.actuator, ACTUATOR_NAMES)
    act, tr, m = catalogue_metrics(name, lever, gearing, workspace, delay, K)
    src = catalogue_source(act.name)
    if args.json:
        print_json({**m, "source": src, "nulls": null_notes(m)})
    else:
        print(f"{act.name} on a {lever * 1e3:g} mm lever, gearing {gearing:g}, n = {tr.ratio:.3f}")
        _print_metrics(m, src if K is None else "typed")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    K, delay, workspace = _edge(args)
    judged = _judged(args, "compare")
    if judged is not None:
        return _compare_design(args, *judged)
    typed = K is not None
    mr, em, K = compare_params(K, delay, workspace)
    res = compare_result(mr, em, K)
    src = compare_k_source(mr, em, K, typed)
    res["K_source"] = src
    res["sources"] = {"mr": TABLE2_SOURCE, "em": catalogue_source("maxon-136206")}
    if args.plot:
        compare_figure({"MR pair (Table 2)": mr, "Maxon 136206": em}, K, args.plot)
    if args.json:
        print_json({**res, "nulls": null_notes(res)})  # every null with its reason
        return 0
    for side, title, p in (("mr", "MR pair (Table 2 identified)", mr),
                           ("em", "Maxon 136206", em)):  # fmt: skip
        print(title)
        _print_metrics(res[side], src, res["sources"][side], own_kmax=float(p.k_max))
    g, g0 = res["bandwidth_gain"], res["bandwidth_gain_mr_without_delay"]
    print(
        f"At {format_kmax(K, src) if not typed else f'K = {K:.4g} N/m [typed]'} (the smaller "
        f"of the two K_max: {float(mr.k_max):.4g} N/m [{TABLE2_SOURCE}], "
        f"{float(em.k_max):.4g} N/m [{catalogue_source('maxon-136206')}]) the MR lever renders "
        f"{100 * res['bandwidth_gain_lumped']:.1f} % more "
        f"lumped bandwidth (paper: 52.8 %), {100 * g:.1f} % on the full model with its "
        f"{mr.delay * 1e3:g} ms delay ({100 * g0:.1f} % without); its damping b1 is "
        f"{res['damping_ratio_mr_over_em']:.2f}× the motor's. MR: "
        f"{_ps(res['mr']['passive'], res['stable']['mr'])}; EM: "
        f"{_ps(res['em']['passive'], res['stable']['em'])}."
    )
    if args.plot:
        print(f"figure: {args.plot}")
    return 0


def _compare_design(args: argparse.Namespace, ev: Any, data: dict[str, Any]) -> int:
    """``compare`` of a design: its MR pair at the K its ``[render]`` rule picks beside the
    Maxon 136206 geared to the pair's force at the same fidelity (what ``evaluate`` puts
    side by side), led by the design's one verdict."""
    h, m = data["haptic"], data["motor"]
    K = float(h["K_N_per_m"])
    src = f"MR pair, {data['source']}"
    res = {
        "design": data["design"],
        "fidelity": data["fidelity"],
        "verdict": data["verdict"],
        "render": data["render"],
        "mr": h,
        "em": m,
        "K_N_per_m": K,
        "bandwidth_gain": data["bandwidth_gain"],
        "bandwidth_gain_lumped": data["bandwidth_gain_lumped"],
        "sources": {"mr": src, "em": f"Maxon 136206 geared to the pair's force ({src})"},
        "notes": resonance_notes(data),  # a bandwidth that is a resonance says so
    }
    res["nulls"] = null_notes(res)  # every null with its reason (evaluate's table)
    if args.plot:
        sides = {"MR pair": ev.mr, "Maxon 136206 (equal force)": ev.motor}
        compare_figure({n: p for n, p in sides.items() if p is not None}, K, args.plot)
    if args.json:
        print_json(res)
        return 0
    print("\n".join(verdict_lines(data)))
    print(f"MR pair of design {data['design']} ({data['source']})")
    _print_metrics(h, src, rule=data["render"]["describe"])
    if m.get("gearing") is None:
        print(f"Maxon 136206: unavailable: {m.get('note')}")
    else:
        print(f"Maxon 136206, geared ×{m['gearing']:.3g} to the MR pair's force ({src})")
        _print_metrics(m, f"Maxon 136206 geared to the MR pair's force, {data['source']}",
                       rule=f"the MR pair's K ({data['render']['describe']})")  # fmt: skip
        gl, g = data["bandwidth_gain_lumped"], data["bandwidth_gain"]
        full = "none" if g is None else f"{100 * g:.1f} %"
        print(f"At K = {K:.4g} N/m the MR lever renders {100 * gl:.1f} % more lumped bandwidth, "
              f"{full} on the full response.")  # fmt: skip
    for note in res["notes"]:
        print(f"note: {note}")
    if args.plot:
        print(f"figure: {args.plot}")
    return 0


def _ps(passive: bool, stable: bool) -> str:
    return f"{'passive' if passive else 'NOT passive'}, {'stable' if stable else 'UNSTABLE'}"


def _print_metrics(m: dict[str, Any], k_source: str, source: str | None = None,
                   rule: str | None = None, own_kmax: float | None = None) -> None:  # fmt: skip
    """The metrics of one side; ``k_source``: where K comes from ("typed", or the source of
    the K_max rendered), ``source``: where m1, b1 come from (default ``k_source``);
    ``rule``: the design's K rule (K then printed as "K … N/m (rule; K_max …)");
    ``own_kmax``: this side's own K_max where the K rendered is another's (catalogue)."""

    def f(v: float, scale: float = 1.0, unit: str = "") -> str:
        return "none" if v is None or not math.isfinite(v) else f"{v * scale:.4g}{unit}"

    if rule is not None:
        k_text = (f"K {f(m['K_N_per_m'])} N/m ({rule}; "
                  f"{format_kmax(m['K_max_N_per_m'], k_source)})")  # fmt: skip
    elif k_source == "typed":
        k_text = f"K {f(m['K_N_per_m'])} N/m [typed]"
    else:
        k_text = format_kmax(m["K_N_per_m"], k_source)
    if own_kmax is not None and rule is None and k_source != source and source is not None:
        k_text = (f"K {f(m['K_N_per_m'])} N/m (the smaller K_max of the two, [{k_source}]; "
                  f"this side's own K_max {f(own_kmax)} N/m [{source}])")  # fmt: skip
    print(
        f"  m1 {f(m['m1_kg'], 1e3)} g  m2 {f(m['m2_kg'], 1e3)} g  b1 {f(m['b1_N_s_per_m'])} N·s/m"
        f"  k {f(m['k_N_per_m'])} N/m  b {f(m['b_N_s_per_m'])} N·s/m"
        f"  delay {f(m['delay_s'], 1e3)} ms  [{source or k_source}]"
    )
    print(
        f"  {k_text}: bandwidth {f(m['bandwidth_hz'], unit=' Hz')}"
        f" (lumped {f(m['bandwidth_lumped_hz'], unit=' Hz')}),"
        f" resonance {f(m['resonance_hz'], unit=' Hz')},"
        f" rendering area {f(m['rendering_area_dB_decade'])} dB·decade"
    )
    print(
        f"  {'passive' if m['passive'] else 'NOT passive'} (up to "
        f"{f(m['max_passive_K_N_per_m'], unit=' N/m')}), stable up to "
        f"{f(m['max_stable_K_N_per_m'], unit=' N/m')}"
    )
