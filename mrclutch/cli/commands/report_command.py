"""``mrclutch report``: the full report of one design, written by the HTML report writer
(``mrclutch.cli.report.write_report``), its steps shown as they run."""

from __future__ import annotations

import argparse

from geometry.validation import check_choice
from mrclutch.cli.commands._common import add_design_args, load_design_args
from mrclutch.cli.progress import bar as progress_bar
from mrclutch.cli.report import write_report
from mrclutch.pipeline import FIDELITIES


def register(sub: argparse._SubParsersAction) -> None:
    """``mrclutch report``: its arguments (``mrclutch report --help``)."""
    p = sub.add_parser(
        "report",
        help="the full report of one design: CAD, views, torque curve, haptic plots, HTML",
        description="Write report.html (read it first), clutch.step, clutch.materials.json "
        "(each solid's material and density), <part>.stl, view.png, section.png, torque.png, "
        "haptic.png, zwidth.png, response.png and metrics.json into --out (built aside and "
        "moved in only when complete).",
    )
    add_design_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="folder to write")
    p.add_argument(
        "--fidelity", default="reference", help="reference (default) or fast, as for evaluate"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_report)


def _report(args: argparse.Namespace) -> int:
    design = load_design_args(args)
    check_choice("fidelity", args.fidelity, FIDELITIES)
    steps = 9  # the tick() calls of mrclutch.cli.report._steps
    with progress_bar(steps, "report", "step", not args.no_progress) as done:
        started = 0

        def tick(msg: str) -> None:  # called as each step starts: its line, then the bar
            nonlocal started
            started += 1
            done(started - 1, f"mrclutch report: step {started}/{steps}: {msg}")

        rep = write_report(design, args.out, fidelity=args.fidelity, progress=tick)
        done(steps)
    print(rep.metrics["verdict"]["line"])  # the one verdict, as the page's badge says it
    print(f"report written to {rep.out_dir}/report.html ({len(rep.files)} files)")
    return 0
