"""``mrclutch optimize``: its options, the limits they set, and the single-objective run
(``--objective``): the optimiser (``mrclutch.optimize``), its candidates checked best
first (``mrclutch.members``), printed. The Pareto set (the default) is
``mrclutch.cli.commands.optimize_pareto``."""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace

from geometry.validation import check_int
from mrclutch.cli.commands._common import (
    add_design_args,
    atomic_path,
    check_writable,
    load_design_args,
    print_json,
)
from mrclutch.cli.commands.optimize_pareto import run_pareto
from mrclutch.cli.errors import EXIT_REQUIREMENT_VIOLATED, CLIError
from mrclutch.cli.executors import sweep_executor
from mrclutch.cli.formatting import explain, format_evaluation, format_verdict, format_verified
from mrclutch.cli.progress import bar as progress_bar
from mrclutch.design import ClutchDesign, design_to_toml
from mrclutch.members import (
    first_meeting,
    optimum_limits,
    paper_beside,
    ranges,
    reference_fem_size,
    verify_candidates,
)
from mrclutch.optimize import (
    DEFAULT_MEMBERS,
    MAX_CANDIDATES,
    MINIMISED,
    OBJECTIVES,
    PAPER_CONTINUOUS_ABOVE_DRAG,
    Candidate,
    Constraints,
    Optimum,
    WorstCase,
    optimize,
    parse_bounds,
    robust_verdict,
)
from mrclutch.pipeline import FAST_BANDWIDTH_ERROR, null_notes
from mrclutch.verdict import for_workshop


def register(sub: argparse._SubParsersAction) -> None:
    """``mrclutch optimize``: its arguments (``mrclutch optimize --help``)."""
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
        "closed loop stable and passive at the K each design renders: by default the largest "
        "K that stays so over the uncertainty ranges (at most K_max = F_max/d, Eq. 4), with "
        "--nominal K_max itself at nominal values. Each design "
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
        "the K the design renders, Hz), area (rendering area, dB·decade), zwidth (Z-width "
        "area, N²·s/m²; about ×7 slower) or transparency (least backdrive force in free "
        "motion, 10 mm at 2 Hz)",
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
        help="do not require a passive closed loop at the K each design renders (required "
        "by default)",
    )
    p.add_argument(
        "--allow-unstable",
        action="store_true",
        help="do not require a stable closed loop at the K each design renders (required "
        "by default)",
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
        default=None,
        help="processes for the reference checks and --verify-top (0: in this process; "
        "not given: this one, and for the Pareto set's reference checks one helper "
        "process beside it)",
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


#: The largest --seed (numpy's legacy seeds and scipy's take 32 bits).
MAX_SEED = 2**32 - 1


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
        return run_pareto(args, base, drums, cons)
    for opt, given in (("--plot", args.plot), ("--designs", args.designs),
                       ("--material", args.material)):  # fmt: skip
        if given:
            raise CLIError(f"{opt}: only for the Pareto set (without --objective)")
    check_int("--tries", args.tries, 1, MAX_CANDIDATES)
    if args.out:
        check_writable("--out", args.out, folder=False)
    wc = None if args.nominal else robust_verdict(base)
    t0 = time.perf_counter()
    gens = 60 * len(drums)  # optimize's default generations (maxiter) a drum count
    with progress_bar(gens, "optimize: generations", "gen", not args.no_progress) as done:
        opt = optimize(
            base,
            objective=args.objective,
            constraints=cons,
            bounds=parse_bounds(args.vary) if args.vary else None,
            drum_counts=drums,
            seed=args.seed,
            robust=wc,
            progress=lambda n, total: done(n * gens // max(total, 1)),
        )
    t_fast = time.perf_counter() - t0
    if not opt.feasible:
        raise CLIError("no design meets the constraints in the search box; relax a limit")
    key = OBJECTIVES[args.objective]
    checks = min(args.tries, len(opt.candidates)) or 1
    desc = f"optimize: candidates checked at {'fast' if args.no_verify else 'reference'} fidelity"
    with progress_bar(checks, desc, "design", not args.no_progress) as done:
        cand, data, tried = first_meeting(opt, args.tries, wc, cons, not args.no_verify, done)
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
        with sweep_executor(args.workers or 0) as (executor, _):
            verified = verify_candidates(top, base, cons, bounds, executor)
        data["verified"] = [vars(v) | {"error": v.error} for v in verified]
        t_verify = time.perf_counter() - t2
    if args.json:
        print_json({**data, "nulls": null_notes(data)})  # every null with its reason
    else:
        _print_optimum(args, opt, cand, t_fast, data, wc)
        if verified is not None:
            print()
            print(format_verified(verified, key, fem_size, max(args.workers or 0, 1), t_verify)
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
