"""``mrclutch optimize`` without ``--objective``: the Pareto set (``mrclutch.optimize.pareto``),
its members judged as their files say (``mrclutch.members``), written, drawn and printed."""

from __future__ import annotations

import argparse
import multiprocessing
import os
import signal
import sys
import time
from collections.abc import Iterator
from concurrent.futures import BrokenExecutor, Executor, ProcessPoolExecutor
from contextlib import contextmanager, suppress
from dataclasses import replace
from pathlib import Path

from geometry.validation import check_choice, check_int
from mrclutch.cli.commands._common import atomic_path, check_writable, print_json
from mrclutch.cli.errors import EXIT_REQUIREMENT_VIOLATED, CLIError
from mrclutch.cli.executors import sweep_executor
from mrclutch.cli.formatting import explain, explain_json, format_verified, limits_line
from mrclutch.cli.plots.design import pareto_set_plot
from mrclutch.cli.progress import bar as progress_bar
from mrclutch.design import ClutchDesign, design_to_toml
from mrclutch.members import (
    helper_start,
    judge_members,
    limits_record,
    paper_beside,
    reference_fem_size,
    shipped_members,
    verify_members,
)
from mrclutch.optimize import (
    DEFAULT_GENERATIONS,
    RENDERING,
    Constraints,
    ParetoSet,
    WorstCase,
    pareto,
    parse_bounds,
    robust_verdict,
)
from mrclutch.pipeline import null_notes


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


def run_pareto(args: argparse.Namespace, base: ClutchDesign, drums: tuple[int, ...],
            cons: Constraints) -> int:  # fmt: skip
    check_choice("--rendering", args.rendering, tuple(RENDERING))
    check_int("--members", args.members, 1, 200)
    for opt, path, folder in (("--plot", args.plot, False), ("--designs", args.designs, True)):
        if path:
            check_writable(opt, path, folder=folder)
    old_members = _old_members(args)
    wc = None if args.nominal else robust_verdict(base)
    fidelity = "fast" if args.no_verify else "reference"
    # the helper pays for itself at reference fidelity (an FEM and a B-rep a member), not on
    # the fast path (--no-verify: a member's judgement ≈ its start-up's imports)
    with _helper(args.workers is None and fidelity == "reference") as helper:
        return _run(args, base, drums, cons, old_members, wc, fidelity, helper)


@contextmanager
def _helper(wanted: bool) -> Iterator[Executor | None]:
    """One helper process beside this one (``wanted``: ``--workers`` not given, reference
    fidelity): it judges the paper preset while this one searches, then shares the
    members' judgements (``members.judge_beside``; issue 40). Stopped on the way out, its
    work done or not."""
    if not wanted:
        yield None
        return
    # a fresh interpreter (spawn), not a fork: a process that has run OpenCascade before
    # (the suite, a caller of main()) forks its thread pool's held locks, and the fork's
    # first B-rep fuse waits on them for ever. (A script calling main() unguarded by
    # `if __name__ == "__main__"` breaks the spawn: all is then judged here.) Ctrl-C is
    # this process's to handle (one line), the helper's to ignore until stopped; the
    # helper's exit skips its interpreter's teardown (members.helper_start)
    pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                               initializer=helper_start)  # fmt: skip
    try:
        yield pool
    except BaseException:  # an error or Ctrl-C: no judgement left running after the exit
        for pid in list(getattr(pool, "_processes", None) or {}):
            with suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def _run(args: argparse.Namespace, base: ClutchDesign, drums: tuple[int, ...],
         cons: Constraints, old_members: set[Path], wc: WorstCase | None, fidelity: str,
         helper: Executor | None) -> int:  # fmt: skip
    paper_side = None if helper is None else helper.submit(paper_beside, base, fidelity, wc)
    t0 = time.perf_counter()
    gens = DEFAULT_GENERATIONS  # pareto's default
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
          sweep_executor(args.workers or 0) as (executor, _)):  # fmt: skip
        rows = judge_members(ps, shipped, cons, fidelity, executor, done, helper)
    t_ref = 0.0 if args.no_verify else time.perf_counter() - t1
    kept = [r for r in rows if not r["violations"]]
    verified = None
    if args.verify_top is not None and kept:
        t2 = time.perf_counter()
        with sweep_executor(args.workers or 0) as (executor, _):
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
    paper = None
    if paper_side is not None:
        with suppress(BrokenExecutor):  # the helper died or could not start: judged here
            paper = paper_side.result()
    if paper is None:
        paper = paper_beside(base, fidelity, wc)
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
        "paper_preset": explain_json(paper),
    }
    if verified is not None:
        data["verified"] = [vars(v) | {"error": v.error} for v in verified]
    if args.json:
        print_json({**data, "nulls": null_notes(data)})  # every null with its reason
    else:
        _print_pareto(args, ps, rows, kept, t_fast, t_ref, base, cons, paper, wc)
        if verified is not None:
            print()
            print(format_verified(verified, ps.objectives[0][1],
                                  reference_fem_size(), max(args.workers or 0, 1),
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
    print("  " + limits_line(base, cons, wc))
    rend = "BW Hz" if args.rendering == "bandwidth" else "Z-width"
    print(f"\n{'#':>3} {'drums':>5} {'gap':>6} {'wall':>6} {'d_in':>6} {'zone':>6} "
          f"{rend:>8} {'backdr N':>8} {'cont mNm':>8} {'mass g':>7} {'K N/m':>7} "
          f"{'Ks':>7} {'Kp':>7} {'verdict':>8}  active limits")  # fmt: skip
    for r in rows:
        m = ps.members[r["member"] - 1]
        c = m.design.clutch
        src = r["reference"]  # the member's judged evaluation (members.judge_members)
        h, cl = src["haptic"], src["clutch"]
        rv = h["bandwidth_hz"] if args.rendering == "bandwidth" else m.row[ps.objectives[0][1]]
        vals = (rv, src["hand"]["mr"]["backdrive_force_N"],
                (cl["continuous_torque_N_m"] - cl["off_state_torque_N_m"]) * 1e3,
                cl["clutch_mass_kg"] * 1e3, h["K_N_per_m"], h["max_stable_K_N_per_m"],
                h["max_passive_K_N_per_m"])  # fmt: skip
        mark = " DROPPED" if r["violations"] else ""
        status = src["verdict"]["status"] if "verdict" in src else "—"
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
