"""``mrclutch evaluate``: a design judged by the one verdict (``verdict.judge``) and
printed (``mrclutch.cli.formatting``)."""

from __future__ import annotations

import argparse
from dataclasses import replace

from mrclutch.cli.commands._common import add_design_args, load_design_args, print_json
from mrclutch.cli.duty_format import duty_lines
from mrclutch.cli.errors import CLIError
from mrclutch.cli.feel_format import feel_lines
from mrclutch.cli.formatting import format_evaluation
from mrclutch.duty import parse_duty
from mrclutch.pipeline import null_notes
from mrclutch.verdict import judge


def register(sub: argparse._SubParsersAction) -> None:
    """``mrclutch evaluate``: its arguments (``mrclutch evaluate --help``)."""
    p = sub.add_parser(
        "evaluate",
        help="a clutch design and its haptic consequences, beside the equal-force motor",
        description="Torque, inertia, mass and drag of a clutch design, and what the MR pair "
        "does at the hand (m1, b1, K_max, bandwidths, rendering area, passivity, stability) "
        "beside the Maxon 136206 geared to the same force, at the same virtual stiffness.",
    )
    add_design_args(p)
    p.add_argument(
        "--fidelity",
        default="fast",
        help="fast (analytic inertia, reluctance network) or reference (exact B-rep, FEM); "
        "default fast",
    )
    p.add_argument(
        "--accuracy",
        type=float,
        default=None,
        metavar="REL",
        help="relative accuracy target (e.g. 0.01): per quantity the cheapest method that "
        "meets it (docs/fidelity.md); overrides --fidelity",
    )
    p.add_argument(
        "--no-uncertainty",
        action="store_true",
        help="the nominal verdict only: no ranges over the uncertain inputs ([uncertainty], "
        "docs/verdicts.md)",
    )
    p.add_argument(
        "--duty",
        metavar="NM:S",
        default=None,
        help="hold NM N·m (yield + drag, slipping) for S seconds: torque, b1 and the verdict "
        "at the end, with the fluid's life at that torque (overrides the design's [duty]; "
        "docs/hot.md)",
    )
    p.add_argument("--json", action="store_true", help="print JSON (SI units in the key names)")
    p.set_defaults(func=_evaluate)


def _evaluate(args: argparse.Namespace) -> int:
    design = load_design_args(args)
    if args.accuracy is not None and not 0 < args.accuracy < 1:
        raise CLIError(f"--accuracy = {args.accuracy}: need 0 < accuracy < 1 (relative)")
    if args.duty is not None:  # issue 41
        design = replace(design, duty=parse_duty(args.duty, design.duty))
    data = judge(design, args.fidelity, accuracy=args.accuracy,
                 robust=False if args.no_uncertainty else None)  # fmt: skip
    data["nulls"] = null_notes(data)  # the verdicts' sections too
    if args.json:
        print_json(data)
        return 0
    print(format_evaluation(data))
    print("\n".join(duty_lines(data["duty"])))
    print("\n".join(feel_lines(data.get("feel") or {})))
    for note in data["clutch"]["notes"]:
        print(f"note: {note}")
    seen = set()
    for path, why in data.get("nulls", {}).items():  # "—" in the table: why, once per reason
        if why not in seen and not path.startswith(("motor/", "zwidth/motor", "hand/motor")):
            seen.add(why)
            print(f"note: {path} — {why}")
    return 0
