"""What a three-fluid axis costs a sweep, on a process pool and on a Dask cluster (issue 45).

    python benchmarks/bench_material_axis.py [--designs 100000] [--workers 2] [--format csv]

Runs ``run_sweep`` over the ranges of ``examples/random_sweep.toml`` (``--designs`` random
designs) twice on each executor: as it is, and with one more axis,
``fluid = {values = ["MRF-122EG", "MRF-132DG", "MRF-140CG"]}``. The executors are a
``ProcessPoolExecutor`` of N processes and a Dask ``LocalCluster`` of N worker processes
(``mrclutch.cli.executors.local_cluster``: what ``mrclutch sweep --dask-local N`` starts),
each started and warmed (mrclutch imported, the kernels loaded) before its clock starts.
Then ``--sample`` random valid rows of the three-fluid file are compared with the single
``evaluate`` of each row's design (max torque, mass, off-state torque, bandwidth).
The two specs alternate for ``--rounds`` rounds on each executor (the fastest run of
each counts), so a change in the machine's load hits both. Checks that the pool and the
cluster wrote the same rows for each spec, and prints each run's time and the ratio with
the axis / without it on the same executor, with each one's rows/s (the fastest run).
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from bench_scaleout import _same  # the same files, byte for byte (folders part by part)

from mrclutch.cli.executors import local_cluster
from mrclutch.design import design_from_mapping
from mrclutch.pipeline import BatchEvaluator, evaluate
from mrclutch.sweep import SweepSpec, chunk_rows, load_spec, read_results, run_sweep
from mrclutch.verify import design_of

SPEC = Path(__file__).resolve().parents[1] / "examples" / "random_sweep.toml"
FLUIDS = 'fluid = {values = ["MRF-122EG", "MRF-132DG", "MRF-140CG"]}'


def _specs(folder: Path, designs: int) -> dict[str, tuple[SweepSpec, BatchEvaluator]]:
    """The example's sweep at ``designs`` designs, without and with the fluid axis."""
    text = SPEC.read_text().replace("samples = 100000", f"samples = {designs}")
    out = {}
    for label, body in (("without", text), ("three fluids", text.replace(
            "[parameters]\n", f"[parameters]\n{FLUIDS}\n")),):  # fmt: skip
        path = folder / f"{label.replace(' ', '_')}.toml"
        path.write_text(body)
        spec, rest = load_spec(path)
        base = design_from_mapping({"clutch": spec.base.to_mm(), **rest}, where=str(path))
        out[label] = (spec, BatchEvaluator(base))
    return out


def _warm(executor: Executor, spec: SweepSpec, evaluate: BatchEvaluator, n: int) -> None:
    """Tiny chunks, several a worker (an idle worker takes a second task before a busy one
    finishes): mrclutch imported and its compiled kernels loaded before the clock starts."""
    tiny = dataclasses.replace(spec, samples=64, chunk_size=64)
    futs = [executor.submit(chunk_rows, tiny, evaluate, evaluate.columns, 0)
            for _ in range(4 * n)]  # fmt: skip
    for f in futs:
        f.result()


def _timed(spec: SweepSpec, out: Path, evaluate: BatchEvaluator, executor: Executor,
           workers: int) -> float:  # fmt: skip
    t = time.perf_counter()
    res = run_sweep(spec, out, evaluate, evaluate.columns, executor=executor, workers=workers,
                    progress=False)  # fmt: skip
    assert res.complete and res.rows == spec.n_designs
    return time.perf_counter() - t


@contextmanager
def _executor(where: str, n: int) -> Iterator[Executor]:
    """A process pool of n, or a Dask LocalCluster of n workers (one thread each)."""
    if where == "process pool":
        with ProcessPoolExecutor(n) as pool:
            yield pool
        return
    import distributed

    cluster = local_cluster(n)
    client = distributed.Client(cluster)
    try:
        yield client.get_executor()
    finally:
        client.close()
        cluster.close()


#: (results column, the same figure of ``evaluate(design)``) compared on the sampled rows
SINGLE = (
    ("max_torque_N_m", lambda e: e.clutch.max_torque),
    ("clutch_mass_kg", lambda e: e.clutch.clutch_mass),
    ("off_state_torque_N_m", lambda e: e.clutch.drag.torque),
    ("bandwidth_hz", lambda e: e.haptic["bandwidth_hz"]),
)


def _against_single(spec: SweepSpec, ev: BatchEvaluator, out: Path, n: int
                    ) -> tuple[float, list[str]]:  # fmt: skip
    """The largest relative difference between ``n`` random valid rows of ``out`` and the
    single ``evaluate`` of each row's design (rebuilt from its id: ``verify.design_of``),
    and the fluids the sample holds."""
    res = read_results(out)
    valid = np.flatnonzero(res["valid"] == 1)
    rows = np.random.default_rng(0).choice(valid, size=min(n, valid.size), replace=False)
    worst = 0.0
    for i in rows:
        e = evaluate(design_of(spec, ev.base, int(res["design_id"][i])))
        assert e.design.materials.fluid == res["fluid"][i]
        for col, single in SINGLE:
            want = float(single(e))
            worst = max(worst, abs(res[col][i] / want - 1))
    return worst, sorted(set(res["fluid"][rows].tolist()))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=100_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--format", choices=("csv", "parquet"), default="csv")
    ap.add_argument("--rounds", type=int, default=2, help="runs of each; the fastest counts")
    ap.add_argument("--sample", type=int, default=30,
                    help="rows of the three-fluid sweep checked against evaluate")  # fmt: skip
    args = ap.parse_args(argv)
    n = args.workers
    times: dict[tuple[str, str], float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        specs = _specs(folder, args.designs)
        for where in ("process pool", "dask-local"):
            with _executor(where, n) as ex:
                for spec, ev in specs.values():
                    _warm(ex, spec, ev, n)
                for r in range(args.rounds):  # alternating: a drift in load hits both
                    for label, (spec, ev) in specs.items():
                        out = folder / f"{where}-{label}.{args.format}".replace(" ", "_")
                        if out.is_dir():
                            shutil.rmtree(out)
                        out.unlink(missing_ok=True)
                        Path(f"{out}.meta.json").unlink(missing_ok=True)
                        t = _timed(spec, out, ev, ex, n)
                        times[where, label] = min(t, times.get((where, label), t))
                        print(f"{where:>12} {label:>13} round {r + 1}: {args.designs} designs "
                              f"in {t:.2f} s ({args.designs / t:.0f} rows/s)",
                              flush=True)  # fmt: skip
        for label in specs:
            a, b = (folder / f"{w}-{label}.{args.format}".replace(" ", "_")
                    for w in ("process pool", "dask-local"))  # fmt: skip
            if not _same(a, b):
                print(f"{label}: the pool and the cluster wrote different rows", file=sys.stderr)
                return 1
        spec, ev = specs["three fluids"]
        out = folder / f"process_pool-three_fluids.{args.format}"
        worst, fluids = _against_single(spec, ev, out, args.sample)
        print(
            f"{args.sample} sampled rows of the three-fluid sweep ({', '.join(fluids)}) "
            f"against single evaluate calls: largest relative difference {worst:.1e}"
        )
        if not worst <= 1e-6:
            print("rows differ from single evaluate calls", file=sys.stderr)
            return 1
    print(f"rows identical on both executors; {n} workers, {args.format}")
    for where in ("process pool", "dask-local"):
        best = {label: args.designs / times[where, label] for label in specs}
        ratio = times[where, "three fluids"] / times[where, "without"]
        print(
            f"{where}: without {best['without']:.0f} rows/s, three fluids "
            f"{best['three fluids']:.0f} rows/s (fastest of {args.rounds}); "
            f"three-fluid axis / without = {ratio:.2f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
