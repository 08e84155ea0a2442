"""Running a sweep: every chunk evaluated in-process or on any
``concurrent.futures.Executor`` (a process pool, a Dask ``Client.get_executor()``), rows
written in chunk order under the output's lock, stopped safely by Ctrl-C or SIGTERM
(whole chunks only), resumed and repaired from the sidecar's record.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from geometry.atomic import OutputError, output_error
from geometry.validation import ParameterError
from magnetics.network import use_compiled
from mrclutch.sweep.lock import output_lock
from mrclutch.sweep.record import (
    META_INTERVAL,
    _digest,
    _meta,
    _meta_path,
    _recorded,
    _write_meta,
)
from mrclutch.sweep.spec import SweepSpec
from mrclutch.sweep.store import (
    _CsvSink,
    _display,
    _format_chunk,
    _parquet_part,
    _ParquetSink,
    is_parquet,
)

Evaluator = Callable[[dict[str, np.ndarray]], dict[str, np.ndarray]]


@dataclass(frozen=True)
class SweepResult:
    path: Path
    rows: int
    complete: bool
    resumed_from: int = 0
    repaired: tuple[int, ...] = ()  # chunks recomputed by ``repair=True``


#: Chunks kept in flight for each worker of the executor: enough that no worker waits while
#: the writer takes the chunks in order (4 per worker reached 405 k designs/s on 16
#: processes where a fixed 4 in flight gave 132 k/s; issue 16).
CHUNKS_PER_WORKER = 4
#: Most rows evaluated but not yet written at once, whatever the executor's size: a CSV
#: row is ~300 bytes, so the chunks in flight hold ≈ 0.5 GB at worst (Parquet ~1/3).
MAX_ROWS_IN_FLIGHT = 1_500_000


def executor_workers(executor: Executor | None) -> int:
    """How many chunks ``executor`` evaluates at once: a process or thread pool's worker
    count, a Dask ``Client.get_executor()``'s total worker threads; 1 when it cannot tell."""
    if executor is None:
        return 1
    n = getattr(executor, "_max_workers", None)  # ProcessPoolExecutor, ThreadPoolExecutor
    if isinstance(n, int) and n > 0:
        return n
    client = getattr(executor, "_client", None)  # distributed.cfexecutor.ClientExecutor
    if client is not None:
        return max(1, sum(client.nthreads().values()))
    return 1


def chunks_in_flight(workers: int, chunk_size: int) -> int:
    """``CHUNKS_PER_WORKER`` × workers, at least 2, and no more than ``MAX_ROWS_IN_FLIGHT``
    rows (but never fewer than 2 chunks)."""
    by_memory = max(2, MAX_ROWS_IN_FLIGHT // chunk_size)
    return max(2, min(CHUNKS_PER_WORKER * workers, by_memory))


@contextmanager
def sigterm_as_interrupt(*, deferred: bool = False) -> Iterator[threading.Event]:
    """``kill`` (SIGTERM) stops the work as Ctrl-C does (KeyboardInterrupt), so ``finally``
    clauses run: a sweep after the current chunk is safe, a report removing its staging
    folder (mrclutch.cli.report). Yields an event set by the signal: a KeyboardInterrupt
    raised inside a C extension's callback can be swallowed there, so long work checks the
    event between its steps too.

    ``deferred=True`` (work that runs C++ extensions: OpenCascade, VTK, manifold3d): the
    first SIGTERM or Ctrl-C only sets the event and the work raises KeyboardInterrupt at its
    next check. An exception raised asynchronously in Python code that C++ runs (a
    nanobind or pybind11 module's import, a callback) cannot unwind through it: the process
    aborts (``terminate called after throwing an instance of 'nanobind::python_error'``,
    SIGABRT, seen when a report was killed while ``trimesh`` imported ``manifold3d``). A
    second signal raises at once.
    """
    terminated = threading.Event()

    def handler(signum: int, frame: Any) -> None:
        again = terminated.is_set()
        terminated.set()
        if not deferred or again:
            raise KeyboardInterrupt

    signals = (signal.SIGTERM, signal.SIGINT) if deferred else (signal.SIGTERM,)
    try:
        old = {s: signal.signal(s, handler) for s in signals}
    except ValueError:  # not the main thread
        yield terminated
        return
    try:
        yield terminated
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    evaluate: Evaluator,
    outputs: Sequence[str],
    *,
    executor: Executor | None = None,
    resume: bool = False,
    overwrite: bool = False,
    repair: bool = False,
    progress: bool = True,
    max_pending: int | None = None,
    workers: int | None = None,
) -> SweepResult:
    """Evaluate every chunk of ``spec`` with ``evaluate`` and stream rows to ``out``: a CSV
    file, or a Parquet dataset (a folder of one part a chunk) when ``out`` ends in
    ``.parquet``.

    ``evaluate(fields) -> {output: array}`` must be picklable when an executor is given.
    Up to ``max_pending`` chunks are in flight (default: ``chunks_in_flight`` of the
    executor's ``workers``, read from it when not given); rows are written in chunk order
    whatever the executor. On Ctrl-C or SIGTERM the finished chunks stay on disk;
    ``resume=True`` verifies them and continues, ``repair=True`` (a resume too) first
    recomputes the chunks that do not verify. The output is locked while this runs
    (``output_lock``); a second writer is refused.
    """
    out = Path(out)
    with output_lock(out):
        return _run_locked(spec, out, evaluate, outputs, executor, resume or repair,
                           overwrite, repair, progress, max_pending, workers)  # fmt: skip


def _run_locked(spec: SweepSpec, out: Path, evaluate: Evaluator, outputs: Sequence[str],
                executor: Executor | None, resume: bool, overwrite: bool, repair: bool,
                progress: bool, max_pending: int | None, workers: int | None
                ) -> SweepResult:  # fmt: skip
    meta = _meta(spec, outputs)
    columns = ["design_id", *spec.columns, *outputs]
    fmt = "parquet" if is_parquet(out) else "csv"
    sink = (_ParquetSink if fmt == "parquet" else _CsvSink)(out, spec, columns)
    records: list[dict[str, Any]] = []
    fixed: list[int] = []
    fresh = False
    if out.exists() and resume:
        records = _recorded(out, meta, spec, sink)
        if repair:
            fixed = sink.repair(records, lambda k: chunk_rows(spec, evaluate, outputs, k,
                                                              fmt)[1])  # fmt: skip
        else:
            bad = sink.bad_chunks(records, first_only=True)
            if bad:
                k, why = bad[0]
                what = (
                    "its header row"
                    if k < 0
                    else (f"chunk {k} (rows {records[k]['rows'][0]}–{records[k]['rows'][1] - 1})")
                )
                raise ParameterError(f"{out}: {what} {why}; cannot resume; run again with "
                                     "--repair to recompute the damaged chunks")  # fmt: skip
        sink.cut(records)
    elif out.exists() and not overwrite:
        raise ParameterError(f"{out}: exists; pass --resume to continue it or --overwrite")
    else:
        fresh = True
        try:
            sink.create()
            _write_meta(out, meta, records)
        except OutputError:
            sink.remove()
            raise
    start_rows = records[-1]["rows"][1] if records else 0

    if max_pending is None:
        n = workers if workers is not None else executor_workers(executor)
        max_pending = chunks_in_flight(n, spec.chunk_size)
    first_chunk = len(records)
    rows = start_rows
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=spec.n_designs, initial=start_rows, unit="design", desc="sweep")
    complete = False
    failed: BaseException | None = None
    last = time.monotonic()
    try:
        with sigterm_as_interrupt(), sink:
            chunks = _results(spec, evaluate, outputs, first_chunk, executor, max_pending, fmt)
            for k, (n, payload, digest) in enumerate(chunks, start=first_chunk):
                records.append(sink.write(k, payload, digest))
                rows += n
                if time.monotonic() - last >= META_INTERVAL:
                    sink.sync()
                    _write_meta(out, meta, records)
                    last = time.monotonic()
                if bar is not None:
                    bar.update(n)
            sink.sync()
        complete = True
    except KeyboardInterrupt:
        pass
    except (OSError, OutputError) as exc:
        failed = exc
    except Exception:  # the evaluator refused a chunk: whole chunks only, or nothing
        _abandon(out, sink, meta, records, fresh)
        raise
    finally:
        if bar is not None:
            bar.close()
    if failed is not None:
        return _fail(out, sink, meta, records, fresh, failed, start_rows)
    _write_meta(out, meta, records)
    return SweepResult(out, rows, complete, start_rows, tuple(fixed))


def _abandon(out: Path, sink: Any, meta: dict[str, Any], records: list[dict[str, Any]],
             fresh: bool) -> None:  # fmt: skip
    """The work failed (not the disk): a new output that recorded no chunk is removed (no
    header-only file left behind); otherwise it is cut back to its recorded chunks."""
    try:
        if fresh and not records:
            sink.remove()
            _meta_path(out).unlink(missing_ok=True)
        else:
            sink.cut(records)
            _write_meta(out, meta, records)
    except (OSError, OutputError):  # the error that matters is the one being raised
        pass


def _fail(out: Path, sink: Any, meta: dict[str, Any], records: list[dict[str, Any]],
          fresh: bool, exc: BaseException, start_rows: int) -> SweepResult:  # fmt: skip
    """A write failed (disk full, read-only): keep the whole, recorded chunks, or nothing
    when this run recorded none of a new output; one OutputError line either way."""
    err = exc if isinstance(exc, OutputError) else output_error(out, exc)  # type: ignore[arg-type]
    if fresh and not records:
        sink.remove()
        _meta_path(out).unlink(missing_ok=True)
        raise err
    try:
        sink.cut(records)
        _write_meta(out, meta, records)
    except (OSError, OutputError):  # the older record stays: fewer chunks, still true
        pass
    rows = records[-1]["rows"][1] if records else start_rows
    raise OutputError(f"{err}; the {rows} rows of whole chunks are kept: free space, then "
                      "run again with --resume")  # fmt: skip


def chunk_rows(
    spec: SweepSpec, evaluate: Evaluator, outputs: Sequence[str], k: int, fmt: str = "csv"
) -> tuple[int, bytes, str]:
    """Chunk k evaluated and encoded, as CSV rows or a Parquet file, with its SHA-256 (runs
    in a worker: only the encoded chunk and its checksum return)."""
    spec.ensure_materials()  # a worker that never read the user's material files
    use_compiled()  # every chunk on the same kernels, whatever ran before it in the process
    ids, fields = spec.design_fields(k)
    res = evaluate(fields)
    cols = [fields[p.name] if p.integer else _display(p.name, fields[p.name])
            for p in spec.params]  # fmt: skip
    cols += [res[name] for name in outputs]
    if fmt == "parquet":
        payload = _parquet_part(spec, outputs, ids, cols)
    else:
        payload = _format_chunk(ids, cols).encode("ascii")
    return ids.size, payload, _digest(payload)


def _results(
    spec: SweepSpec,
    evaluate: Evaluator,
    outputs: Sequence[str],
    first: int,
    executor: Executor | None,
    max_pending: int,
    fmt: str = "csv",
) -> Iterator[tuple[int, bytes, str]]:
    """(rows, encoded chunk, checksum) of every chunk from ``first`` on, in chunk order, evaluated
    in-process or on ``executor`` with at most ``max_pending`` chunks submitted and not yet
    handed on."""
    if executor is None:
        for k in range(first, spec.n_chunks):
            yield chunk_rows(spec, evaluate, outputs, k, fmt)
        return
    pending: dict[int, Future] = {}
    nxt = first
    try:
        for k in range(first, spec.n_chunks):
            pending[k] = executor.submit(chunk_rows, spec, evaluate, tuple(outputs), k, fmt)
            while pending and (len(pending) >= max_pending or k == spec.n_chunks - 1):
                yield pending.pop(nxt).result()
                nxt += 1
    finally:  # interrupted: drop the work not yet written
        for fut in pending.values():
            fut.cancel()
