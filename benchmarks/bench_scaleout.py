"""Sweep throughput in this process, on a process pool and on a Dask LocalCluster (issue 16).

    python benchmarks/bench_scaleout.py [--workers N] [--designs 1000000] [--format csv|parquet]

Runs ``run_sweep`` over the ranges of ``examples/random_sweep.toml`` (``--designs`` random
designs, 10⁶ by default) three ways, each writing the same rows to its own file:

* in this process;
* a ``ProcessPoolExecutor`` of N processes;
* a Dask ``LocalCluster`` of N worker processes with one thread each, through
  ``Client.get_executor()``: ``mrclutch.cli.executors.local_cluster``, what ``mrclutch
  sweep --dask-local N`` starts (``--dask-default-env`` keeps Dask's default worker
  environment, ``MALLOC_TRIM_THRESHOLD_=65536``, to show what it costs).

Prints designs per second of each and the ratio to the in-process rate, and checks that the
outputs hold identical rows. The clock runs from the first chunk submitted to the last
row written; starting the pool or the cluster (and importing mrclutch in its workers) is
timed apart and printed beside it. The issue's acceptance target: Dask at ≥ 0.7·N × the
in-process rate.
"""

from __future__ import annotations

import argparse
import dataclasses
import filecmp
import os
import sys
import tempfile
import time
from concurrent.futures import Executor, ProcessPoolExecutor
from pathlib import Path

from mrclutch.cli.executors import local_cluster
from mrclutch.design import design_from_mapping
from mrclutch.pipeline import BatchEvaluator
from mrclutch.sweep import SweepSpec, chunk_rows, load_spec, run_sweep

SPEC = Path(__file__).resolve().parents[1] / "examples" / "random_sweep.toml"


def _warm(executor: Executor, spec: SweepSpec, evaluate: BatchEvaluator, n: int) -> None:
    """One tiny chunk on every worker: imports mrclutch there before the clock starts."""
    tiny = dataclasses.replace(spec, samples=8, chunk_size=8)
    futs = [executor.submit(chunk_rows, tiny, evaluate, evaluate.columns, 0) for _ in range(n)]
    for f in futs:
        f.result()


def _timed(spec, out, evaluate, executor=None, workers=None, fmt="csv") -> float:
    t = time.perf_counter()
    res = run_sweep(
        spec, out, evaluate, evaluate.columns, executor=executor, workers=workers, progress=False
    )
    assert res.complete and res.rows == spec.n_designs
    return time.perf_counter() - t


def _same(a: Path, b: Path) -> bool:
    if a.is_dir():
        names = sorted(p.name for p in a.iterdir())
        return names == sorted(p.name for p in b.iterdir()) and all(
            filecmp.cmp(a / n, b / n, shallow=False) for n in names
        )
    return filecmp.cmp(a, b, shallow=False)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2, help="N: pool processes, Dask workers")
    ap.add_argument("--designs", type=int, default=10**6, help="random designs (10⁶)")
    ap.add_argument("--format", choices=("csv", "parquet"), default="csv")
    ap.add_argument(
        "--dask-default-env",
        action="store_true",
        help="also time a LocalCluster with Dask's default worker environment",
    )
    args = ap.parse_args()
    n = args.workers

    spec, rest = load_spec(SPEC)
    spec = dataclasses.replace(spec, samples=args.designs)
    evaluate = BatchEvaluator(design_from_mapping({"clutch": spec.base.to_mm(), **rest}, "x"))
    ext = ".parquet" if args.format == "parquet" else ".csv"
    py = sys.version.split()[0]
    print(
        f"{spec.n_designs} designs of {SPEC.name} in chunks of {spec.chunk_size}, "
        f"{args.format}, N = {n}, {os.cpu_count()} CPUs, Python {py}"
    )

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        rates, starts = {}, {}
        rates["in-process"] = spec.n_designs / _timed(spec, d / f"one{ext}", evaluate)
        starts["in-process"] = 0.0

        t = time.perf_counter()
        with ProcessPoolExecutor(n) as pool:
            _warm(pool, spec, evaluate, n)
            starts[f"process pool of {n}"] = time.perf_counter() - t
            dt = _timed(spec, d / f"pool{ext}", evaluate, pool, n)
            rates[f"process pool of {n}"] = spec.n_designs / dt

        import distributed

        clusters = [(f"Dask LocalCluster of {n}", "dask", local_cluster)]
        if args.dask_default_env:  # last: it leaves MALLOC_TRIM_THRESHOLD_ in os.environ
            clusters.append(
                (
                    f"Dask LocalCluster of {n}, Dask's default env",
                    "dask0",
                    lambda n: distributed.LocalCluster(
                        n_workers=n, threads_per_worker=1, dashboard_address=None
                    ),
                )
            )
        for name, stem, start in clusters:
            t = time.perf_counter()
            with start(n) as cluster, distributed.Client(cluster) as client:
                ex = client.get_executor()
                _warm(ex, spec, evaluate, n)
                starts[name] = time.perf_counter() - t
                rates[name] = spec.n_designs / _timed(spec, d / f"{stem}{ext}", evaluate, ex, n)

        stems = ["pool"] + [stem for _, stem, _ in clusters]
        same = all(_same(d / f"one{ext}", d / f"{stem}{ext}") for stem in stems)

    base = rates["in-process"]
    print("\n| executor | designs/s | × in-process | start-up (s) |")
    print("|---|---:|---:|---:|")
    for name, r in rates.items():
        print(f"| {name} | {r:,.0f} | {r / base:.2f} | {starts[name]:.1f} |")
    target = 0.7 * n
    dask = rates[f"Dask LocalCluster of {n}"] / base
    print(f"\nrows identical in every run: {'yes' if same else 'NO'}")
    verdict = "met" if dask >= target else "missed"
    print(f"Dask target ≥ 0.7·N = {target:.2f}× in-process: {verdict} ({dask:.2f}×)")


if __name__ == "__main__":
    main()
