"""A design's ``mrclutch haptic`` and ``mrclutch compare`` (``mrclutch.cli.commands.haptic``
loads this module when the options name a design): the design judged as ``evaluate``
judges it (``mrclutch.verdict``), its MR pair's metrics, or its pair beside the Maxon
136206 geared to the pair's force at the same fidelity."""

from __future__ import annotations

import argparse
from typing import Any

from geometry.validation import check_choice
from mrclutch.cli.commands._common import load_design_args, print_json
from mrclutch.cli.errors import CLIError
from mrclutch.cli.metrics_format import print_metrics
from mrclutch.cli.plots.haptic import compare_figure
from mrclutch.pipeline import evaluate, null_notes
from mrclutch.verdict import judge_evaluation, resonance_notes, verdict_lines


def run_haptic(args: argparse.Namespace) -> int:
    """``haptic`` of the design the options name: its MR pair at its ``[render]`` K."""
    _, data = _judged(args, "haptic")
    h = data["haptic"]
    notes = resonance_notes(data, ("haptic",))  # a bandwidth that is a resonance
    if args.json:
        out = {**h, "source": data["source"], "verdict": data["verdict"],
               "render": data["render"], "notes": notes}  # fmt: skip
        print_json({**out, "nulls": null_notes(out)})  # every null with its reason
        return 0
    print("\n".join(verdict_lines(data)))
    print(f"MR pair of design {data['design']} ({data['source']})")
    print_metrics(h, f"MR pair, {data['source']}", rule=data["render"]["describe"])
    for note in notes:
        print(f"note: {note}")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    """``compare`` of the design the options name (``_compare_design``)."""
    return _compare_design(args, *_judged(args, "compare"))


def _judged(args: argparse.Namespace, command: str) -> tuple[Any, dict[str, Any]]:
    """(Evaluation, ``verdict.judge`` data) of the design the options name. The catalogue's
    options are refused beside a design (the design has its own K rule, delay and
    transmission)."""
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
    print_metrics(h, src, rule=data["render"]["describe"])
    if m.get("gearing") is None:
        print(f"Maxon 136206: unavailable: {m.get('note')}")
    else:
        print(f"Maxon 136206, geared ×{m['gearing']:.3g} to the MR pair's force ({src})")
        print_metrics(m, f"Maxon 136206 geared to the MR pair's force, {data['source']}",
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
