"""``mrclutch evaluate | sweep | optimize | report``: from the drums to the hand."""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from statistics import median
from typing import Any

from geometry.validation import ParameterError, check_choice, check_int
from mrclutch.cli.commands._common import (
    add_design_args,
    atomic_path,
    check_writable,
    load_design_args,
    print_json,
)
from mrclutch.cli.duty_format import duty_lines
from mrclutch.cli.errors import CLIError
from mrclutch.cli.executors import sweep_executor
from mrclutch.cli.feel_format import feel_lines
from mrclutch.cli.longjobs import announce
from mrclutch.cli.plots.design import PLOT_STEPS, pareto_plot, pareto_set_plot
from mrclutch.cli.progress import bar as progress_bar
from mrclutch.cli.report import write_report
from mrclutch.design import ClutchDesign, design_from_mapping, design_to_toml
from mrclutch.duty import parse_duty
from mrclutch.estimates import check_fem_size, chunk_write_s, fem_solve_seconds, sweep_rate
from mrclutch.members import (
    first_meeting,
    judge_members,
    limits_record,
    optimum_limits,
    paper_beside,
    ranges,
    reference_fem_size,
    shipped_members,
    verify_candidates,
    verify_members,
)
from mrclutch.optimize import (
    CONTINUOUS,
    DEFAULT_MEMBERS,
    MAX_CANDIDATES,
    MAX_ECCENTRICITY,
    MINIMISED,
    OBJECTIVES,
    PAPER_CONTINUOUS_ABOVE_DRAG,
    RENDERING,
    Candidate,
    Constraints,
    Optimum,
    ParetoSet,
    WorstCase,
    optimize,
    pareto,
    parse_bounds,
    robust_verdict,
)
from mrclutch.outputs import (
    CLUTCH_ROWS,
    HAND_ROWS,
    SWEEP_OPTIONAL,
    format_kmax,
    output,
    row_label,
)
from mrclutch.pipeline import (
    FAST_BANDWIDTH_ERROR,
    FIDELITIES,
    BatchEvaluator,
    null_notes,
)
from mrclutch.robust import ROBUST_COLUMNS, RobustBatchEvaluator
from mrclutch.sweep import is_parquet, load_spec, run_sweep
from mrclutch.verdict import for_workshop, judge, verdict_lines
from mrclutch.verify import TORQUE, verified_path, verify_top, write_verified


def register(sub: argparse._SubParsersAction) -> None:
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

    p = sub.add_parser(
        "sweep",
        help="evaluate a grid or random sample of designs on the fast path (CSV or Parquet)",
        description="Sweep DrumClutch parameters given in SPEC.toml (ranges in mm); rows are "
        "written as they come, so an interrupted sweep loses nothing and --resume carries on.",
    )
    p.add_argument("spec", metavar="SPEC.toml", help="sweep spec (see examples/*.toml)")
    p.add_argument(  # dest "results": a .parquet output is a folder, checked in _sweep
        "--out",
        dest="results",
        required=True,
        metavar="RESULTS.csv|RESULTS.parquet",
        help="CSV file to write, or a Parquet dataset (a folder of one part file a chunk) "
        "when the name ends in .parquet; beside it RESULTS.csv.meta.json records the spec's "
        "fingerprint (for --resume) and each column's unit and meaning",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue an interrupted sweep (every chunk on disk is verified first against "
        "the sizes and checksums in RESULTS.meta.json)",
    )
    p.add_argument(
        "--repair",
        action="store_true",
        help="like --resume, but recompute the chunks that do not verify (a row lost, "
        "altered or duplicated, a part cut short) instead of refusing",
    )
    p.add_argument(
        "--yes",
        action="store_true",
        help="run a sweep of more than 1e7 designs, a --verify-top of more than 1e4 FEM "
        "solves, or any sweep estimated above 10 min (refused without it; above 30 s the "
        "estimate is said first: mrclutch/cli/longjobs.py)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing results file")
    p.add_argument("--workers", type=int, default=0, help="processes (0: in this process)")
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the chunks on a running dask.distributed scheduler (tcp://host:8786); "
        "its workers need mrclutch installed",
    )
    p.add_argument(
        "--dask-local",
        type=int,
        metavar="N",
        help="run the chunks on a local Dask cluster of N worker processes (1 thread each)",
    )
    p.add_argument(
        "--connect-timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="seconds to wait for the --scheduler and its first worker (default 10)",
    )
    p.add_argument(
        "--with",
        dest="optional",
        action="append",
        default=[],
        choices=SWEEP_OPTIONAL,
        metavar="COLUMN",
        help="also compute this column (repeatable): max_passive_K_N_per_m (about ×1.7 the "
        "cost), max_stable_K_N_per_m (×8), zwidth_area_N2_s_per_m2 (×7); the worst case over "
        "the design's [uncertainty] ranges (docs/verdicts.md; benchmarks/bench_robust.py): "
        "max_stable_K_worst_N_per_m, max_passive_K_worst_N_per_m, bandwidth_worst_hz",
    )
    p.add_argument("--pareto", metavar="FILE.png", help="also draw the Pareto front")
    p.add_argument(
        "--verify-top",
        type=int,
        metavar="N",
        help="after the sweep, re-solve the N best rows (by --objective) with the FEM at the "
        "error map's reference size, on the same workers, print the network's and the "
        "single-loop circuit's error on each and write them to RESULTS.csv.verified.csv",
    )
    p.add_argument(
        "--objective",
        metavar="COLUMN",
        help=f"the results column that ranks the rows for --verify-top (default {TORQUE})",
    )
    side = p.add_mutually_exclusive_group()
    side.add_argument("--maximize", dest="minimize", action="store_false",
                      help="best = largest --objective (the default)")  # fmt: skip
    side.add_argument("--minimize", dest="minimize", action="store_true",
                      help="best = smallest --objective")  # fmt: skip
    p.add_argument(
        "--verify-fem-size-mm",
        type=float,
        metavar="MM",
        help="FEM element size for --verify-top (default: the error map's reference, "
        "0.25 mm; a coarser one is quicker and less accurate)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_sweep, minimize=False)

    p = sub.add_parser(
        "optimize",
        help="the trade-offs (a Pareto set: rendering bandwidth, transparency, continuous "
        "torque, mass) or one objective, under the builder's limits",
        description="By default a Pareto set (pymoo's NSGA-II on the vectorised fast path) "
        "over rendering bandwidth (or Z-width), backdrive force in free motion, continuous "
        "torque above the off-state drag and clutch mass; --objective NAME gives the single "
        "best design (differential evolution) instead. Every limit is enforced: torque, "
        "mass, envelope, continuous torque, coil power, time at peak, an optional duty "
        "cycle, the process's smallest gap and wall ([process] in the design file), and a "
        "closed loop stable and passive at the design's own K = K_max (Eq. 4). Each design "
        "is then re-evaluated at reference fidelity (exact B-rep inertia, FEM torque); "
        "those failing a limit there are dropped (Pareto) or the next candidate is tried.",
        epilog="exit status: 0 the reported design(s) meet every requirement (at reference "
        "fidelity unless --no-verify); 2 bad input, or no design meets the limits on the "
        "fast path; 3 no design meets the requirements at reference fidelity (named on "
        "stderr; --out still writes the design).",
    )
    add_design_args(p)
    p.add_argument(
        "--objective",
        default=None,
        help="one objective instead of the Pareto set: bandwidth (rendering bandwidth at "
        "K_max, Hz), area (rendering area, dB·decade), zwidth (Z-width area, N²·s/m²; about "
        "×7 slower) or transparency (least backdrive force in free motion, 10 mm at 2 Hz)",
    )
    p.add_argument(
        "--rendering",
        default="bandwidth",
        help="the Pareto set's rendering objective: bandwidth (default) or zwidth",
    )
    p.add_argument("--min-torque", type=float, default=0.4, help="N·m (default 0.4)")
    p.add_argument("--max-mass-g", type=float, default=100.0, help="clutch mass, g (default 100)")
    p.add_argument("--max-diameter-mm", type=float, default=30.0, help="default 30")
    p.add_argument("--max-length-mm", type=float, default=40.0, help="default 40")
    p.add_argument(
        "--min-continuous-torque",
        type=float,
        default=PAPER_CONTINUOUS_ABOVE_DRAG,
        metavar="NM",
        help="N·m held forever above the off-state drag while slipping at the input speed "
        f"(default {PAPER_CONTINUOUS_ABOVE_DRAG:g}, the paper clutch's; 0: no limit)",
    )
    p.add_argument(
        "--max-power-w",
        type=float,
        default=None,
        metavar="W",
        help="coil heat at the current limit (default: the amplifier's supply voltage × "
        "the current limit, 24 V × 7 A)",
    )
    p.add_argument(
        "--peak-time-s",
        type=float,
        default=None,
        metavar="S",
        help="seconds at the peak current (holding the peak torque, slipping) before the "
        "wire or fluid limit (default: the design's peak_duration_s, 1 s; 0: no limit)",
    )
    p.add_argument(
        "--duty",
        default=None,
        metavar="NM:S",
        help="a duty cycle: hold NM N·m (yield + drag, slipping) for S seconds before the "
        "wire or fluid limit (default: none)",
    )
    p.add_argument("--max-residual-torque-mNm", type=float, default=None, metavar="MNM",
                   help="the largest residual torque at 0 A after the peak current (the "
                   "steel's remanence, docs/hysteresis.md; default: none)")  # fmt: skip
    p.add_argument("--max-ripple-force-mN", type=float, default=None, metavar="MN",
                   help="the largest runout ripple force at the hand ([process] runout, "
                   "docs/hysteresis.md; default: none)")  # fmt: skip
    p.add_argument(
        "--min-life-h",
        type=float,
        default=None,
        metavar="H",
        help="hours of fluid life at the duty (--duty's torque, else the design's [duty]; "
        "the lifetime dissipated energy is unverified per fluid, docs/hot.md; default: none)",
    )
    for key, what in (("runout", "drums' runout, TIR"), ("tolerance", "diameters' tolerance"),
                      ("min-wall", "thinnest drum wall")):  # fmt: skip
        p.add_argument(f"--{key}-mm", type=float, default=None, metavar="MM",
                       help=f"the process's {what} (default: the design's [process]; "
                       "docs/optimize.md)")  # fmt: skip
    p.add_argument(
        "--allow-active",
        action="store_true",
        help="do not require a passive closed loop at K_max (required by default)",
    )
    p.add_argument(
        "--allow-unstable",
        action="store_true",
        help="do not require a stable closed loop at K_max (required by default)",
    )
    p.add_argument("--drums", default="1,2,3,4", help="drum counts to try (default 1,2,3,4)")
    p.add_argument(
        "--material",
        action="append",
        default=[],
        metavar="PART=NAME,NAME",
        help="a part's material as a search axis, e.g. fluid=MRF-122EG,MRF-132DG,MRF-140CG "
        "(repeatable; the Pareto set only; parts and names: docs/materials.md)",
    )
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="NAME_mm=LO:HI",
        help="a dimension and its range (repeatable; default gap, drum thickness, drum "
        "inner diameter and zone length)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--members",
        type=int,
        default=DEFAULT_MEMBERS,
        metavar="N",
        help=f"Pareto members to keep, spread over the front (default {DEFAULT_MEMBERS})",
    )
    p.add_argument("--plot", metavar="FILE.png", help="draw the Pareto set (Pareto mode)")
    p.add_argument(
        "--designs",
        metavar="DIR",
        help="write each Pareto member as a design file DIR/member_NN.toml (Pareto mode); "
        "a folder holding member files of an earlier run needs --overwrite",
    )
    p.add_argument("--overwrite", action="store_true",
                   help="with --designs: replace the member files of an earlier run")  # fmt: skip
    p.add_argument("--no-verify", action="store_true", help="skip the reference-fidelity check")
    p.add_argument(
        "--nominal",
        action="store_true",
        help="take the nominal haptic verdict at K = K_max instead of the worst case over "
        "the uncertainty ranges (by default each design renders the largest K it keeps "
        "stable and passive over them, and its files say so in [render]: docs/optimize.md)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=0,
        help="processes for the reference checks and --verify-top (0: in this process)",
    )
    p.add_argument(
        "--verify-top",
        type=int,
        metavar="N",
        help="re-solve the torque of the N best designs (Pareto: the first N members; one "
        "objective: the first N candidates) with the FEM at the error map's reference size "
        "on the same workers, and print the network's error on each",
    )
    p.add_argument(
        "--tries",
        type=int,
        default=3,
        metavar="N",
        help="one objective: candidates checked at reference fidelity, best first, until "
        f"one meets every requirement (1..{MAX_CANDIDATES}, default 3)",
    )
    p.add_argument("--out", metavar="DESIGN.toml",
                   help="one objective: write the optimum as a design file")  # fmt: skip
    p.add_argument("--json", action="store_true")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar (the Pareto set's generations, its checks)")  # fmt: skip
    p.set_defaults(func=_optimize)


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
        lines.append(f"  {label:<38}" + "".join(f"{v[c] * sc:>10.4g}" for c in
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
        f"  largest stable K: {r['max_stable_K_typed_delay_N_per_m']:.4g} N/m with the typed "
        f"delay, {_g(r['max_stable_K_torque_delay_N_per_m'])} with Σ T, "
        f"{_g(r['max_stable_K_lags_N_per_m'])} with the lags themselves",
    ]
    return lines


def _g(v: float | None, spec: str = ".4g") -> str:
    """A figure, or — where it is unavailable (None; the output says why)."""
    return "—" if v is None else format(v, spec)


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


def _report(args: argparse.Namespace) -> int:
    design = load_design_args(args)
    check_choice("fidelity", args.fidelity, FIDELITIES)
    steps = 9  # the tick() calls of mrclutch.cli.report._build
    if args.no_progress:
        rep = write_report(design, args.out, fidelity=args.fidelity)
    else:
        from tqdm import tqdm

        with tqdm(total=steps, unit="step", desc="report") as bar:

            def tick(msg: str) -> None:
                bar.set_postfix_str(msg)
                bar.update(1)

            rep = write_report(design, args.out, fidelity=args.fidelity, progress=tick)
    print(rep.metrics["verdict"]["line"])  # the one verdict, as the page's badge says it
    print(f"report written to {rep.out_dir}/report.html ({len(rep.files)} files)")
    return 0


#: A sweep of more designs than this runs only with --yes: above ~40 min on one core at
#: the fast path's ~4e3 designs/s (specs stop at 1e8 designs, mrclutch.sweep.MAX_DESIGNS).
MAX_DESIGNS_UNASKED = 10**7
#: --verify-top beyond this many FEM solves runs only with --yes.
MAX_FEM_UNASKED = 10**4


def _say_estimate(spec: Any, evaluator: BatchEvaluator, workers: int, yes: bool = True,
                  out: str | None = None) -> float | None:  # fmt: skip
    """Time the first designs of the spec (``estimates.sweep_rate``) and one chunk's synced
    write beside ``out`` (``estimates.chunk_write_s``); the whole sweep
    (designs at the measured rate + chunks × the write) goes to ``longjobs.announce``:
    said on stderr above 30 s, refused without ``yes`` above 10 min. Returns the
    estimate (s), None when skipped."""
    n = spec.n_designs
    if n <= 1000 and spec.n_chunks <= 100:  # under 30 s at any rate the fast path has
        return None
    per_chunk = chunk_write_s(out)
    rate, done = sweep_rate(spec, evaluator, workers)
    seconds = n / rate + spec.n_chunks * per_chunk
    announce("sweep", f"{n:.3g} designs", seconds,
             f"{rate:.3g} designs/s measured on the first {done}, {max(1, workers)} worker(s); "
             f"{spec.n_chunks} chunks of {spec.chunk_size} at {per_chunk * 1e3:.2g} ms per "
             "chunk written", yes)  # fmt: skip
    return seconds


def _verify_options(args: argparse.Namespace, columns: tuple[str, ...],
                    base: ClutchDesign | None = None) -> float | None:  # fmt: skip
    """The FEM size (m) for --verify-top, None without it; bad options refused before the
    sweep runs."""
    if args.verify_top is None:
        for opt, given in (("--objective", args.objective is not None),
                           ("--verify-fem-size-mm", args.verify_fem_size_mm is not None),
                           ("--minimize", args.minimize)):  # fmt: skip
            if given:
                raise CLIError(f"{opt}: only with --verify-top N")
        return None
    if args.verify_top < 1:
        raise CLIError(f"--verify-top = {args.verify_top}: must be >= 1")
    key = args.objective or TORQUE
    if key not in columns:
        raise CLIError(f"--objective {key}: not a column of this sweep ({', '.join(columns)})")
    if args.verify_fem_size_mm is None:
        size = reference_fem_size()
        if base is not None:
            _check_fem_work(args, base, size)
        return size
    mm = args.verify_fem_size_mm
    if not (math.isfinite(mm) and 0.02 <= mm <= 5.0):
        raise CLIError(f"--verify-fem-size-mm = {mm:g}: must be in [0.02, 5] mm")
    if base is not None:  # before the sweep: a size whose solves cannot fit is refused now
        _check_fem_work(args, base, mm * 1e-3)
    return mm * 1e-3


def _check_fem_work(args: argparse.Namespace, base: ClutchDesign, size: float) -> None:
    """--verify-top's FEM solves: memory checked, more than MAX_FEM_UNASKED need --yes,
    above a minute (at the FEM's measured rate per node) said on stderr."""
    try:
        check_fem_size(base, size)
    except ParameterError as exc:
        raise CLIError(f"--verify-fem-size-mm: {exc}") from None
    n = args.verify_top
    if n > MAX_FEM_UNASKED and not args.yes:
        raise CLIError(f"--verify-top {n}: more than {MAX_FEM_UNASKED} FEM solves; add --yes")
    seconds = fem_solve_seconds(base, size, n)
    announce("sweep", f"--verify-top {n}: {n} FEM solves at {size * 1e3:g} mm", seconds,
             "one worker at the FEM's measured rate per grid node", args.yes)  # fmt: skip


def _sweep(args: argparse.Namespace) -> int:
    spec, rest = load_spec(args.spec)
    base = design_from_mapping({"clutch": spec.base.to_mm(), **rest}, where=args.spec)
    check_writable("--out", args.results, folder=is_parquet(args.results))
    robust = any(k in ROBUST_COLUMNS for k in args.optional)
    evaluator = (RobustBatchEvaluator if robust else BatchEvaluator)(base, tuple(args.optional))
    fem_size = _verify_options(args, evaluator.columns, base)
    if spec.n_designs > MAX_DESIGNS_UNASKED and not args.yes:
        raise CLIError(f"{spec.n_designs:.3g} designs: more than {MAX_DESIGNS_UNASKED:.0e} "
                       "(hours to days of work); add --yes to run it")  # fmt: skip
    where = (args.workers, args.scheduler, args.dask_local, args.connect_timeout)
    with sweep_executor(*where) as (executor, workers):
        if not (args.resume or args.repair):
            _say_estimate(spec, evaluator, workers, args.yes, args.results)
        res = run_sweep(
            spec,
            args.results,
            evaluator,
            evaluator.columns,
            executor=executor,
            workers=workers,
            resume=args.resume,
            overwrite=args.overwrite,
            repair=args.repair,
            progress=not args.no_progress,
        )
        verified = None
        if res.complete and fem_size is not None:
            t0 = time.perf_counter()
            key = args.objective or TORQUE
            verified = verify_top(spec, base, res.path, args.verify_top, key,
                                  not args.minimize, fem_size, executor)  # fmt: skip
            t_verify = time.perf_counter() - t0
    if not res.complete:
        print(
            f"mrclutch sweep: interrupted after {res.rows} of {spec.n_designs} designs; "
            f"rows kept in {res.path}; run again with --resume to carry on",
            file=sys.stderr,
        )
        return 130
    if res.repaired:
        print(f"repaired chunk(s) {', '.join(map(str, res.repaired))} of {res.path} "
              "(recomputed; checksums match the record)")  # fmt: skip
    print(
        f"{res.rows} designs in {res.path}"
        + (f" (resumed at {res.resumed_from})" if res.resumed_from else "")
    )
    if verified is not None and fem_size is not None:
        side = write_verified(verified_path(res.path), verified, args.objective or TORQUE,
                              fem_size)  # fmt: skip
        print(format_verified(verified, args.objective or TORQUE, fem_size, workers, t_verify))
        print(f"verified rows: {side}")
    if args.pareto:
        with progress_bar(PLOT_STEPS, "sweep plot", "step", not args.no_progress) as done:
            pareto_plot(res.path, args.pareto, progress=done)
        print(f"Pareto front: {args.pareto}")
    return 0


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
        lines.append(f"network vs FEM: max |error| {max(err):.2%}, median {median(err):.2%}; "
                     f"{inside} of {len(rows)} within the map's bound")  # fmt: skip
        circ = [abs(r.circuit_error) for r in rows]
        inside = sum(r.circuit_within_bound for r in rows)
        lines.append(f"circuit vs FEM: max |error| {max(circ):.2%}, median {median(circ):.2%}; "
                     f"{inside} of {len(rows)} within its map's bound")  # fmt: skip
    return "\n".join(lines)


#: The largest --seed (numpy's legacy seeds and scipy's take 32 bits).
MAX_SEED = 2**32 - 1

#: exit status of ``optimize`` when the reference re-check violates a requirement.
EXIT_REQUIREMENT_VIOLATED = 3


def _optimize_inputs(args: argparse.Namespace) -> tuple[ClutchDesign, tuple[int, ...],
                                                       Constraints]:  # fmt: skip
    """The base design (with --runout-mm etc. over its ``[process]``), the drum counts and the
    limits, every option checked."""
    base = load_design_args(args)
    proc = {name: getattr(args, f"{name}_mm") * 1e-3 for name in ("runout", "tolerance",
            "min_wall") if getattr(args, f"{name}_mm") is not None}  # fmt: skip
    if proc:
        base = replace(base, process=replace(base.process, **proc))
    try:
        drums = tuple(int(x) for x in args.drums.split(","))
    except ValueError:
        raise CLIError(f"--drums {args.drums!r}: give drum counts such as 1,2,3") from None
    duty = (0.0, 0.0)
    if args.duty is not None:
        torque, _, seconds = args.duty.partition(":")
        try:
            duty = (float(torque), float(seconds))
        except ValueError:
            raise CLIError(f"--duty {args.duty!r}: give NM:S, e.g. 0.2:60") from None
        if not (duty[0] > 0 and duty[1] > 0):
            raise CLIError(f"--duty {args.duty!r}: torque and seconds must be > 0")
        base = replace(base, duty=replace(base.duty, torque=duty[0], time=duty[1]))  # issue 41
    for opt, v in (("--max-residual-torque-mNm", args.max_residual_torque_mNm),
                   ("--max-ripple-force-mN", args.max_ripple_force_mN),
                   ("--min-life-h", args.min_life_h)):  # fmt: skip
        if v is not None and not (math.isfinite(v) and v > 0):
            raise CLIError(f"{opt} = {v:g}: must be finite and > 0")
    cons = Constraints(
        min_torque=args.min_torque,
        max_mass=args.max_mass_g * 1e-3,
        max_diameter=args.max_diameter_mm * 1e-3,
        max_length=args.max_length_mm * 1e-3,
        passive=not args.allow_active,
        stable=not args.allow_unstable,
        min_continuous_torque=args.min_continuous_torque,
        max_power=args.max_power_w,
        peak_time=args.peak_time_s,
        duty_torque=duty[0],
        duty_time=duty[1],
        min_life=args.min_life_h,
        max_residual_torque=None
        if args.max_residual_torque_mNm is None
        else args.max_residual_torque_mNm * 1e-3,
        max_ripple_force=None
        if args.max_ripple_force_mN is None
        else args.max_ripple_force_mN * 1e-3,
    ).resolved(base)
    if args.verify_top is not None and args.verify_top < 1:
        raise CLIError(f"--verify-top = {args.verify_top}: must be >= 1")
    check_int("--seed", args.seed, 0, MAX_SEED)
    if args.vary:
        parse_bounds(args.vary)  # bad bounds refused before any work
    return base, drums, cons


def _optimize(args: argparse.Namespace) -> int:
    base, drums, cons = _optimize_inputs(args)
    if args.objective is None:
        for opt, given in (("--out", args.out), ("--tries", args.tries != 3)):
            if given:
                raise CLIError(f"{opt}: only with --objective (the Pareto set: --designs DIR)")
        return _pareto(args, base, drums, cons)
    for opt, given in (("--plot", args.plot), ("--designs", args.designs),
                       ("--material", args.material)):  # fmt: skip
        if given:
            raise CLIError(f"{opt}: only for the Pareto set (without --objective)")
    check_int("--tries", args.tries, 1, MAX_CANDIDATES)
    if args.out:
        check_writable("--out", args.out, folder=False)
    wc = None if args.nominal else robust_verdict(base)
    t0 = time.perf_counter()
    opt = optimize(
        base,
        objective=args.objective,
        constraints=cons,
        bounds=parse_bounds(args.vary) if args.vary else None,
        drum_counts=drums,
        seed=args.seed,
        robust=wc,
    )
    t_fast = time.perf_counter() - t0
    if not opt.feasible:
        raise CLIError("no design meets the constraints in the search box; relax a limit")
    key = OBJECTIVES[args.objective]
    cand, data, tried = first_meeting(opt, args.tries, wc, cons, verify=not args.no_verify)
    bounds = parse_bounds(args.vary) if args.vary else None
    data = {
        **optimum_limits(base, cons, cand, drums, bounds),
        "objective": args.objective,
        "objective_column": key,
        "objective_value": cand.value,
        "evaluations": opt.evaluations,
        "optimisation_time_s": t_fast,
        "best_per_drum_count": {str(k): v for k, v in opt.per_drum_count.items()},
        "varied": [f"{n}_mm" for n in opt.varied],
        **data,
        "tried": tried,
    }
    shipped, notes = for_workshop(cand.design, ranges(wc))
    data["notes"] = notes
    if args.out:
        with atomic_path(args.out) as tmp:
            tmp.write_text(design_to_toml(shipped))
    verified = None
    if args.verify_top is not None:
        t2 = time.perf_counter()
        top = list(opt.candidates[: args.verify_top])
        fem_size = reference_fem_size()
        with sweep_executor(args.workers) as (executor, _):
            verified = verify_candidates(top, base, cons, bounds, executor)
        data["verified"] = [vars(v) | {"error": v.error} for v in verified]
        t_verify = time.perf_counter() - t2
    if args.json:
        print_json(data)
    else:
        _print_optimum(args, opt, cand, t_fast, data, wc)
        if verified is not None:
            print()
            print(format_verified(verified, key, fem_size, max(args.workers, 1), t_verify)
                  .replace("rows", "candidates"))  # fmt: skip
    violations = data["violations"]
    if violations:
        fid = data["verdict"]["fidelity"]
        each = "; ".join(
            f"#{t['rank']} ({t['n_drums']} drums): {', '.join(t['violations'])}" for t in tried
        )
        print(
            f"mrclutch optimize: none of the {len(tried)} best candidate(s) meets the "
            f"requirements at {fid} fidelity: {each}",
            file=sys.stderr,
        )
        return EXIT_REQUIREMENT_VIOLATED
    return 0


def _limits_line(base: ClutchDesign, cons: Constraints, wc: WorstCase | None) -> str:
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


def _old_members(args: argparse.Namespace) -> set[Path]:
    """The member files an earlier run left in ``--designs``: refused without
    ``--overwrite`` (a folder of two runs' members would mix them), else to be removed."""
    if not args.designs or not Path(args.designs).is_dir():
        return set()
    old = set(Path(args.designs).glob("member_*.toml"))
    if old and not args.overwrite:
        raise CLIError(
            f"--designs {args.designs}: holds {len(old)} member file(s) of an "
            "earlier run; give --overwrite to replace them, or another folder"
        )
    return old


def _material_axes(specs: list[str]) -> dict[str, list[str]]:
    """``--material PART=NAME,NAME`` options as the Pareto search's categorical axes."""
    out: dict[str, list[str]] = {}
    for spec in specs:
        part, eq, names = spec.partition("=")
        if not eq or not names.strip():
            raise CLIError(f"--material {spec!r}: give PART=NAME,NAME (e.g. fluid=MRF-122EG,"
                           "MRF-140CG)")  # fmt: skip
        out[part.strip()] = [n.strip() for n in names.split(",") if n.strip()]
    return out


def _pareto(args: argparse.Namespace, base: ClutchDesign, drums: tuple[int, ...],
            cons: Constraints) -> int:  # fmt: skip
    check_choice("--rendering", args.rendering, tuple(RENDERING))
    check_int("--members", args.members, 1, 200)
    for opt, path, folder in (("--plot", args.plot, False), ("--designs", args.designs, True)):
        if path:
            check_writable(opt, path, folder=folder)
    old_members = _old_members(args)
    wc = None if args.nominal else robust_verdict(base)
    t0 = time.perf_counter()
    gens = 100  # pareto's default generations
    with progress_bar(gens, "optimize: generations", "gen", not args.no_progress) as done:
        ps = pareto(base, rendering=args.rendering, constraints=cons,
                    bounds=parse_bounds(args.vary) if args.vary else None, drum_counts=drums,
                    seed=args.seed, members=args.members, robust=wc,
                    materials=_material_axes(args.material), generations=gens,
                    progress=lambda n, _total: done(n))  # fmt: skip
    t_fast = time.perf_counter() - t0
    if not ps.members and ps.dropped_robust:
        raise CLIError(f"no design of the front is stable and passive at its K over the "
                       f"uncertainty ranges ({ps.dropped_robust} checked, all failed); "
                       "declare narrower ranges ([uncertainty]) or give --nominal")  # fmt: skip
    if not ps.members:
        raise CLIError("no design meets the constraints in the search box; relax a limit")
    # each member as its file says (its `[render]` rule, its ranges, no bench), judged by the
    # one verdict every command uses, at reference fidelity (or the fast path: --no-verify)
    shipped = shipped_members(ps, wc)
    t1 = time.perf_counter()
    desc = "optimize: members checked"
    with (progress_bar(len(shipped), desc, "design", not args.no_progress) as done,
          sweep_executor(args.workers) as (executor, _)):  # fmt: skip
        rows = judge_members(ps, shipped, cons, "fast" if args.no_verify else "reference",
                             executor, done)  # fmt: skip
    t_ref = 0.0 if args.no_verify else time.perf_counter() - t1
    kept = [r for r in rows if not r["violations"]]
    verified = None
    if args.verify_top is not None and kept:
        t2 = time.perf_counter()
        with sweep_executor(args.workers) as (executor, _):
            verified = verify_members(ps, kept, args.verify_top, executor)
        t_verify = time.perf_counter() - t2
    written = []
    if args.designs and kept:
        folder = Path(args.designs)
        folder.mkdir(parents=True, exist_ok=True)
        for r in kept:
            path = folder / f"member_{r['member']:02d}.toml"
            design = shipped[r["member"] - 1][0]
            with atomic_path(path) as tmp:
                tmp.write_text(design_to_toml(replace(design, name=path.stem)))
            written.append(str(path))
        for path in old_members - {Path(w) for w in written}:  # --overwrite: none left over
            path.unlink(missing_ok=True)
    notes = shipped[0][1] if shipped else []
    paper = paper_beside(base, "fast" if args.no_verify else "reference", wc)
    if args.plot:
        pareto_set_plot(ps, [r["member"] for r in kept], paper, args.plot)
    data = {
        "mode": "pareto",
        "objectives": [
            {"name": n, "column": c, "sense": "max" if sg > 0 else "min"}
            for n, c, sg in ps.objectives
        ],
        "evaluations": ps.evaluations,
        "optimisation_time_s": t_fast,
        "reference_time_s": t_ref,
        "front_size": ps.front_size,
        "dropped_unstable_fast": ps.dropped_unstable,
        "dropped_robust_fast": ps.dropped_robust,
        "haptic_verdict": ps.robust,
        "fidelity": "fast" if args.no_verify else "reference",
        "members": rows,
        "kept": [r["member"] for r in kept],
        "dropped_at_reference": [r["member"] for r in rows if r["violations"]],
        "limits": limits_record(base, cons),
        "box_mm": {f"{k}_mm": [lo * 1e3, hi * 1e3] for k, (lo, hi) in ps.box.items()},
        "box_source": {f"{k}_mm": v for k, v in ps.box_source.items()},
        "designs_written": written,
        "notes": notes,
        "paper_preset": _explain_json(paper),
    }
    if verified is not None:
        data["verified"] = [vars(v) | {"error": v.error} for v in verified]
    if args.json:
        print_json(data)
    else:
        _print_pareto(args, ps, rows, kept, t_fast, t_ref, base, cons, paper, wc)
        if verified is not None:
            print()
            print(format_verified(verified, ps.objectives[0][1],
                                  reference_fem_size(), max(args.workers, 1),
                                  t_verify).replace("rows", "members"))  # fmt: skip
        if written:
            print(
                f"\n{len(written)} design files in {args.designs} (each renders by its "
                "[render] rule: evaluate, report and compare give the verdict above)"
            )
        for note in notes:
            print(f"note: {note}")
        if args.plot:
            print(f"Pareto plot: {args.plot}")
    if not kept:
        print(f"mrclutch optimize: none of the {len(rows)} Pareto members meets the "
              f"requirements at reference fidelity", file=sys.stderr)  # fmt: skip
        return EXIT_REQUIREMENT_VIOLATED
    return 0


def _explain_json(ev: dict) -> dict:
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


def explain(ev: dict, paper: dict, label: str) -> str:
    """How a design's bandwidth and resonance relate, where its damping comes from (the
    b1 budget) and its thermal rating, beside the paper preset's."""
    a, p = _explain_json(ev), _explain_json(paper)

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


def _print_pareto(args: argparse.Namespace, ps: ParetoSet, rows: list[dict], kept: list[dict],
                  t_fast: float, t_ref: float, base: ClutchDesign, cons: Constraints,
                  paper: dict, wc: WorstCase | None) -> None:  # fmt: skip
    dropped = [r for r in rows if r["violations"]]
    fid = "fast path (--no-verify)" if args.no_verify else "reference fidelity"
    print(f"Pareto set: {len(kept)} members meet every limit at {fid}"
          + (f"; {len(dropped)} of {len(rows)} dropped there" if dropped else ""))  # fmt: skip
    print(f"  NSGA-II: {ps.evaluations} designs in {t_fast:.1f} s; front of {ps.front_size} "
          f"designs meeting every limit on the fast path ({ps.dropped_unstable} dropped as "
          f"unstable at their K, {ps.dropped_robust} by the worst case)"
          + (f"; reference checks {t_ref:.1f} s" if t_ref else ""))  # fmt: skip
    print(f"  haptic verdict: {ps.robust}")
    print("  " + _limits_line(base, cons, wc))
    rend = "BW Hz" if args.rendering == "bandwidth" else "Z-width"
    print(f"\n{'#':>3} {'drums':>5} {'gap':>6} {'wall':>6} {'d_in':>6} {'zone':>6} "
          f"{rend:>8} {'backdr N':>8} {'cont mNm':>8} {'mass g':>7} {'K N/m':>7} "
          f"{'Ks':>7} {'Kp':>7} {'verdict':>8}  active limits")  # fmt: skip
    for r in rows:
        m = ps.members[r["member"] - 1]
        c = m.design.clutch
        src = r["reference"] if r["reference"] is not None else None
        if src is not None:
            h, cl = src["haptic"], src["clutch"]
            rv = h["bandwidth_hz"] if args.rendering == "bandwidth" else m.row[ps.objectives[0][1]]
            vals = (rv, src["hand"]["mr"]["backdrive_force_N"],
                    (cl["continuous_torque_N_m"] - cl["off_state_torque_N_m"]) * 1e3,
                    cl["clutch_mass_kg"] * 1e3, h["K_N_per_m"], h["max_stable_K_N_per_m"],
                    h["max_passive_K_N_per_m"])  # fmt: skip
        else:
            f = m.row
            vals = (f[ps.objectives[0][1]], f["backdrive_force_N"], f[CONTINUOUS] * 1e3,
                    f["clutch_mass_kg"] * 1e3, f["K_N_per_m"], f["max_stable_K_N_per_m"],
                    f["max_passive_K_N_per_m"])  # fmt: skip
        mark = " DROPPED" if r["violations"] else ""
        status = src["verdict"]["status"] if src is not None and "verdict" in src else "—"
        print(f"{r['member']:>3} {c.n_drums:>5} {c.gap * 1e3:>6.3f} {c.drum_thickness * 1e3:>6.3f} "
              f"{c.drum_inner_diameter * 1e3:>6.2f} {c.zone_length * 1e3:>6.2f} "
              f"{vals[0]:>8.4g} {vals[1]:>8.3g} {vals[2]:>8.3g} {vals[3]:>7.4g} {vals[4]:>7.4g} "
              f"{vals[5]:>7.4g} {vals[6]:>7.4g} {status:>8}  {', '.join(m.active) or '—'}"
              f"{mark}")  # fmt: skip
    print("  (lengths in mm: gap, drum wall, drum inner diameter, zone length; values at "
          f"{'the fast path' if args.no_verify else 'reference fidelity'}; Ks, Kp: largest "
          "stable and passive K at nominal values; verdict: the one verdict of the member's "
          "file, as evaluate prints it)")  # fmt: skip
    for r in rows:
        for e in r["edges"]:
            print(f"  #{r['member']}: {e}")
    for r in dropped:
        print(f"  #{r['member']} dropped at reference fidelity: {'; '.join(r['violations'])}")
    if kept:
        first = kept[0]
        ev = first["reference"]
        print(explain(ev, paper, f"member #{first['member']}"))


def _print_optimum(
    args: argparse.Namespace,
    opt: Optimum,
    cand: Candidate,
    t_fast: float,
    data: dict,
    wc: WorstCase | None,
) -> None:
    c = cand.design.clutch
    print(f"{data['verdict']['line']}  [the design written, at {data['verdict']['fidelity']} "
          "fidelity]")  # fmt: skip
    key = data["objective_column"]
    varied = ", ".join(f"{n}_mm {getattr(c, n) * 1e3:.4g}" for n in opt.varied)
    print(f"optimum ({opt.evaluations} designs in {t_fast:.2f} s): n_drums {c.n_drums}, {varied}")
    sense = "minimised" if args.objective in MINIMISED else "maximised"
    print(f"objective {args.objective} ({key}, {sense}): {cand.value:.4g} on the fast path")
    for k, v in opt.per_drum_count.items():
        print(f"  best with {k} drum(s): {key} {v:.4g}")
    for t in data["tried"]:
        if t["violations"]:
            print(f"  candidate #{t['rank']} ({t['n_drums']} drums, {key} "
                  f"{t['objective_value']:.4g}) fails at {t['fidelity']} fidelity: "
                  f"{'; '.join(t['violations'])}")  # fmt: skip
    print(f"\nfast path:\n{format_evaluation(data['fast'], lead=False)}")
    if "reference" in data:
        change = data["bandwidth_change_reference_vs_fast"]
        print(f"\nreference fidelity:\n{format_evaluation(data['reference'], lead=False)}")
        within = "within" if abs(change) <= FAST_BANDWIDTH_ERROR else "OUTSIDE"
        print(
            f"\nbandwidth, reference vs fast: {change * 100:+.2f} % ({within} the fast "
            f"path's stated error of {FAST_BANDWIDTH_ERROR * 100:.1f} %)"
        )
    print(format_verdict(data))
    print("  active limits (fast path): " + (", ".join(data["active_limits"]) or "none"))
    for e in data["edges"]:
        print(f"  {e}")
    if "reference" in data:
        paper = paper_beside(cand.design, "reference", wc)
        print(explain(data["reference"], paper, "optimum"))
    for note in data.get("notes", ()):
        print(f"note: {note}")
    if args.out:
        print(f"design written to {args.out} (its [render] rule renders the K above: evaluate, "
              "report and compare give the same verdict)")  # fmt: skip


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
