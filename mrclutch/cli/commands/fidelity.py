"""``mrclutch fidelity``: every method of every quantity on one design — time, error against
the reference, the chart and the table; a bar on stderr counts the methods, then the files
written, with its estimate (issue 40). Imports nothing heavy at module level."""

from __future__ import annotations

import argparse
import csv
import io
import json
from pathlib import Path
from typing import Any

from mrclutch.cli.commands._common import (
    add_design_args,
    atomic_path,
    load_design_args,
    print_json,
    to_jsonable,
)
from mrclutch.cli.errors import CLIError
from mrclutch.cli.plots.fidelity import plot_fidelity
from mrclutch.cli.progress import bar
from mrclutch.fidelity import measure, registry


def register(sub: Any) -> None:
    p = sub.add_parser(
        "fidelity",
        help="speed against accuracy: time and error of every method (chart + table)",
        description="Run every method of every quantity (inertia, torque at the current "
        "limit, stability limit of the delayed loop, bandwidth, the eddy lag's delay) on a "
        "design; time each (median of repeats) and compare it with the quantity's reference. "
        "Writes "
        "DIR/fidelity.png, DIR/fidelity.csv and DIR/fidelity.json; progress (each method, a "
        "bar of the methods done, then the files, with its estimate) on stderr.",
    )
    add_design_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument(
        "--repeats", type=int, default=5, help="at most this many timed repeats per method (5)"
    )
    p.add_argument("--json", action="store_true", help="print the rows as JSON (stdout)")
    p.set_defaults(func=run)


def rows_csv(rows: Any) -> str:
    """The table as CSV (quantity, method, setting, time_s, value, unit, error_rel)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["quantity", "method", "setting", "time_s", "value", "unit", "error_rel"])
    for r in rows:
        j = r.as_json()
        w.writerow([j["quantity"], j["method"], j["setting"], f"{r.time_s:.6g}",
                    f"{r.value:.8g}", j["unit"], f"{r.error_rel:.4g}"])  # fmt: skip
    return buf.getvalue()


def run(args: argparse.Namespace) -> int:
    if args.repeats < 1:
        raise CLIError(f"--repeats = {args.repeats}: must be >= 1")
    design = load_design_args(args)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CLIError(f"--out {out}: exists and is not a directory")
    methods = registry()
    # the methods, then the files (the chart's drawing: seconds, silent after the bar before)
    with bar(len(methods) + 1, "fidelity", "step") as done:
        count = [0]

        def said(what: str) -> None:
            done(count[0], f"fidelity: {what}")

        def finished(n: int, _total: int) -> None:
            count[0] = n
            done(n)

        rows = measure(design, repeats=args.repeats, methods=methods, progress=said,
                       finished=finished)  # fmt: skip
        done(len(methods), "fidelity: writing fidelity.csv, fidelity.json, fidelity.png")
        with atomic_path(out / "fidelity.csv") as tmp:
            tmp.write_text(rows_csv(rows))
        doc = {"design": design.name, "rows": [r.as_json() for r in rows]}
        with atomic_path(out / "fidelity.json") as tmp:
            tmp.write_text(json.dumps(to_jsonable(doc), indent=2) + "\n")
        title = f"speed against accuracy — {design.name}"
        plot_fidelity(rows, out / "fidelity.png", title=title)
        done(len(methods) + 1)
    if args.json:
        print_json(doc)
        return 0
    print(f"{'quantity':<12}{'method':<20}{'setting':<20}{'time (s)':>11}{'error':>11}")
    for r in rows:
        print(f"{r.quantity:<12}{r.method:<20}{r.setting:<20}{r.time_s:>11.3g}"
              f"{r.error_rel:>11.2e}" + ("  (reference)" if r.reference else ""))  # fmt: skip
        for w in r.warnings:
            print(f"    warning: {w}")
    print(f"wrote {out / 'fidelity.png'}, fidelity.csv, fidelity.json")
    return 0
