"""``mrclutch sweep``: a grid or random sample of designs on the fast path, its estimate
said first (``mrclutch.estimates``), --verify-top's FEM check and the Pareto plot."""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any

from geometry.validation import ParameterError
from mrclutch.cli.commands._common import check_writable
from mrclutch.cli.errors import CLIError
from mrclutch.cli.executors import sweep_executor
from mrclutch.cli.formatting import format_verified
from mrclutch.cli.longjobs import announce
from mrclutch.cli.plots.design import PLOT_STEPS, pareto_plot
from mrclutch.cli.progress import bar as progress_bar
from mrclutch.design import ClutchDesign, design_from_mapping
from mrclutch.estimates import check_fem_size, chunk_write_s, fem_solve_seconds, sweep_rate
from mrclutch.members import reference_fem_size
from mrclutch.outputs import SWEEP_OPTIONAL
from mrclutch.pipeline import BatchEvaluator
from mrclutch.robust import ROBUST_COLUMNS, RobustBatchEvaluator
from mrclutch.sweep import is_parquet, load_spec, run_sweep
from mrclutch.verify import TORQUE, verified_path, verify_top, write_verified


def register(sub: argparse._SubParsersAction) -> None:
    """``mrclutch sweep``: its arguments (``mrclutch sweep --help``)."""
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
    if args.pareto:  # said before drawing: the sweep's bar has ended (issue 40)
        print(f"drawing the plot of {res.rows} designs …", file=sys.stderr, flush=True)
        with progress_bar(PLOT_STEPS, "sweep plot", "step", not args.no_progress) as done:
            pareto_plot(res.path, args.pareto, progress=done)
        print(f"Pareto front: {args.pareto}")
    return 0
