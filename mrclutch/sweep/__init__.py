"""Vectorised design sweeps: a spec, chunks of designs, CSV streamed as it comes, resume.

A sweep is a grid or a random sample over DrumClutch parameters (ranges in mm in the spec
file). Designs are numbered 0..N−1; chunk k holds designs [k·C, (k+1)·C). A chunk's
designs depend only on the spec and k (random chunks draw from a generator seeded with
(seed, k)), so an interrupted sweep resumed later writes exactly the rows an
uninterrupted one would.

Each finished chunk is appended to the CSV in order with one write and a flush; a
sidecar ``<out>.meta.json`` records the spec's fingerprint (``resume`` refuses a different
spec) and, as they are written, every chunk's row range, byte range and SHA-256. A resume
verifies every recorded chunk (sizes, then checksums) and refuses, naming the first bad
chunk, a file that does not match; ``repair=True`` recomputes just the damaged chunks and
restores the file an uninterrupted run writes, byte for byte. An advisory lock
(``<out>.lock``, flock) keeps a second writer out while one runs; the kernel drops the lock
of a killed run, so its lock file is taken over. Every file goes through the output layer
(``geometry.atomic``): a full disk ends in one line and leaves whole chunks only. Any
``concurrent.futures.Executor`` (a process pool, or a Dask ``Client.get_executor()``) may
evaluate the chunks.
"""

from __future__ import annotations

import csv
import json
import math
import mmap
import os
import re
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

from geometry.atomic import OutputError, atomic_path, output_error, write_bytes
from geometry.materials import SLOTS
from geometry.params import INTEGER_FIELDS
from geometry.validation import ParameterError
from magnetics.network import use_compiled
from mrclutch.outputs import OUTPUTS, describe
from mrclutch.sweep.front import pareto_front
from mrclutch.sweep.lock import output_lock
from mrclutch.sweep.record import (
    META_INTERVAL,
    _chunk_rows_range,
    _digest,
    _meta,
    _meta_path,
    _recorded,
    _write_meta,
    model_version,
)
from mrclutch.sweep.spec import (
    DEFAULT_CHUNK,
    MAX_DESIGNS,
    UNUSED_SECTIONS,
    MaterialFile,
    ParamRange,
    SweepSpec,
    load_spec,
    parse_parameters,
)

__all__ = [
    "CHUNKS_PER_WORKER",
    "DEFAULT_CHUNK",
    "MAX_DESIGNS",
    "MAX_ROWS_IN_FLIGHT",
    "META_INTERVAL",
    "UNUSED_SECTIONS",
    "Evaluator",
    "MaterialFile",
    "ParamRange",
    "SweepResult",
    "SweepSpec",
    "chunk_rows",
    "chunks_in_flight",
    "csv_text",
    "executor_workers",
    "is_parquet",
    "load_spec",
    "model_version",
    "output_lock",
    "pareto_front",
    "parse_parameters",
    "read_results",
    "run_sweep",
    "sigterm_as_interrupt",
]

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


def is_parquet(out: str | Path) -> bool:
    """Parquet output is chosen by the name: ``results.parquet`` (a folder of parts)."""
    return Path(out).suffix.lower() == ".parquet"


def read_results(path: str | Path) -> dict[str, np.ndarray]:
    """A sweep's CSV (or Parquet dataset, a folder ending in .parquet) as columns of floats
    (empty cells → NaN); a material column (named by its part: ``fluid``, ``SLOTS``) as its
    names, an object array."""
    if is_parquet(path):
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        out = {}
        for name in table.column_names:
            col = table[name]
            if pa.types.is_dictionary(col.type) or pa.types.is_string(col.type):
                out[name] = np.asarray(col.to_pylist(), dtype=object)
            else:
                out[name] = col.to_numpy().astype(float)
        return out
    with open(path, newline="", encoding="utf-8") as f:
        header = next(csv.reader(f), [])
    text = {*SLOTS, *_recorded_categories(Path(path))}  # the columns of names
    if not any(h in text for h in header):
        data = np.genfromtxt(path, delimiter=",", names=True, dtype=float, ndmin=1)
        return {name: np.atleast_1d(data[name]) for name in data.dtype.names}
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))[1:]
    cols = list(zip(*rows, strict=True)) if rows else [()] * len(header)
    return {h: np.asarray(c, dtype=object) if h in text else
            np.array([float(x) if x else math.nan for x in c], dtype=float)
            for h, c in zip(header, cols, strict=True)}  # fmt: skip


def _recorded_categories(out: Path) -> list[str]:
    """The categorical columns the sidecar of ``out`` lists (none when it has none)."""
    try:
        cats = json.loads(_meta_path(out).read_text(encoding="utf-8")).get("categories", {})
    except (OSError, ValueError, AttributeError):
        return []
    return [str(k) for k in cats] if isinstance(cats, dict) else []


class _CsvSink:
    """One CSV file; each chunk appended with one write and a flush, recorded as its byte
    range and checksum."""

    def __init__(self, out: Path, spec: SweepSpec, columns: Sequence[str]) -> None:
        self.out, self.spec = out, spec
        self.header = (",".join(columns) + "\n").encode()
        self.file: Any = None
        self.end = len(self.header)  # where the next chunk goes

    def create(self) -> None:
        write_bytes(self.out, self.header)
        self.end = len(self.header)

    def record(self, k: int, payload: bytes, digest: str) -> dict[str, Any]:
        return {"chunk": k, "rows": _chunk_rows_range(self.spec, k), "offset": self.end,
                "bytes": len(payload), "sha256": digest}  # fmt: skip

    def well_formed(self, r: dict[str, Any], k: int, prev: dict[str, Any] | None) -> bool:
        at = prev["offset"] + prev["bytes"] if prev else len(self.header)
        return r.get("offset") == at

    def bad_chunks(self, records: list[dict[str, Any]], first_only: bool
                   ) -> list[tuple[int, str]]:  # fmt: skip
        """(chunk, why) of every recorded chunk the file does not hold (chunk -1: the
        header row); sizes first, then checksums."""
        bad: list[tuple[int, str]] = []
        try:
            with self.out.open("rb") as f:
                size = os.fstat(f.fileno()).st_size
                if f.read(len(self.header)) != self.header:
                    bad.append((-1, "its header row differs from this sweep's columns"))
                for r in records:
                    if first_only and bad:
                        break
                    if r["offset"] + r["bytes"] > size:
                        bad.append((r["chunk"], "is missing or cut short (the file ends at "
                                    f"byte {size}, before the chunk's end)"))  # fmt: skip
                        continue
                    f.seek(r["offset"])
                    if _digest(f.read(r["bytes"])) != r["sha256"]:
                        bad.append((r["chunk"], "does not match its checksum"))
        except OSError as exc:
            raise ParameterError(f"{self.out}: unreadable ({exc.strerror}); cannot resume"
                                 ) from None  # fmt: skip
        return bad

    def cut(self, records: list[dict[str, Any]]) -> None:
        """Drop what follows the last recorded chunk (a chunk written but not recorded)."""
        self.end = records[-1]["offset"] + records[-1]["bytes"] if records else len(self.header)
        try:
            with self.out.open("rb+") as f:
                f.truncate(self.end)
        except OSError as exc:
            raise output_error(self.out, exc) from None

    def repair(self, records: list[dict[str, Any]], recompute: Callable[[int], bytes]
               ) -> list[int]:  # fmt: skip
        """Rewrite the file with every recorded chunk: found in the damaged file by its first
        design id when its bytes match their checksum, recomputed otherwise."""
        fixed = []
        with self.out.open("rb") as f:
            size = os.fstat(f.fileno()).st_size
            mm: Any = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) if size else b""
            try:
                with atomic_path(self.out) as tmp, tmp.open("wb") as g:
                    g.write(self.header)
                    pos = 0
                    for r in records:
                        data, pos = self._find(mm, r, pos)
                        if data is None or _digest(data) != r["sha256"]:
                            data = _recomputed(self.out, r, recompute)
                            fixed.append(r["chunk"])
                        g.write(data)
            finally:
                if size:
                    mm.close()
        return fixed

    @staticmethod
    def _find(mm: Any, r: dict[str, Any], pos: int) -> tuple[bytes | None, int]:
        at, n = r["offset"], r["bytes"]
        if _digest(mm[at : at + n]) == r["sha256"]:
            return bytes(mm[at : at + n]), at
        hit = mm.find(b"\n%d," % r["rows"][0], pos)  # the chunk's first row, moved
        if hit < 0:
            return None, pos
        return bytes(mm[hit + 1 : hit + 1 + n]), hit

    def __enter__(self) -> _CsvSink:
        try:
            self.file = self.out.open("ab")
        except OSError as exc:
            raise output_error(self.out, exc) from None
        return self

    def write(self, k: int, payload: bytes, digest: str) -> dict[str, Any]:
        rec = self.record(k, payload, digest)
        self.file.write(payload)
        self.file.flush()
        self.end += len(payload)
        return rec

    def sync(self) -> None:
        """The chunks written so far on the disk before the ``.meta.json`` records them."""
        if self.file is not None and not self.file.closed:
            self.file.flush()
            os.fsync(self.file.fileno())

    def remove(self) -> None:
        self.out.unlink(missing_ok=True)

    def __exit__(self, *exc: object) -> None:
        try:
            self.sync()  # on the disk before the final record names it
        except OSError:  # the disk filled: the error that matters is already raised
            pass
        finally:
            try:
                self.file.close()
            except OSError:
                pass


def _recomputed(out: Path, r: dict[str, Any], recompute: Callable[[int], bytes]) -> bytes:
    data = recompute(r["chunk"])
    if _digest(data) != r["sha256"]:
        raise ParameterError(
            f"{out}: chunk {r['chunk']} recomputed does not match its recorded checksum (a "
            "different mrclutch version or machine?); cannot repair; pass --overwrite"
        )
    return data


class _ParquetSink:
    """A Parquet dataset: the folder ``out`` holds ``part-<chunk>.parquet``, one file a chunk
    in chunk order, each written through the output layer (a hidden temporary name in the
    folder, fsync, rename). A kill at any moment (SIGKILL and a power cut included) leaves
    only complete parts, which pandas, pyarrow, polars and DuckDB read as one table in
    design order; the ``.meta.json`` records each part's size and checksum."""

    def __init__(self, out: Path, spec: SweepSpec, columns: Sequence[str]) -> None:
        self.out, self.spec, self.columns = out, spec, list(columns)
        self.width = max(6, len(str(spec.n_chunks - 1)))  # names sort in chunk order

    def part(self, k: int) -> Path:
        return self.out / f"part-{k:0{self.width}d}.parquet"

    def _listing(self) -> tuple[list[int], list[Path], list[Path]]:
        """Chunk numbers of the parts, leftover temporaries, and anything else."""
        parts, temps, other = [], [], []
        for p in self.out.iterdir():
            m = re.fullmatch(r"part-(\d+)\.parquet", p.name)
            if m and len(m.group(1)) == self.width:
                parts.append(int(m.group(1)))
            elif re.fullmatch(r"\.part-\d+(\.parquet\.tmp|-\w+\.parquet)", p.name):
                temps.append(p)
            else:
                other.append(p)
        return sorted(parts), temps, other

    def create(self) -> None:
        if self.out.is_dir():  # --overwrite: only a sweep's own parts are removed
            parts, temps, other = self._listing()
            if other:
                raise ParameterError(
                    f"{self.out}: holds {other[0].name}, not a sweep's part; not replaced"
                )
            for p in [*map(self.part, parts), *temps]:
                p.unlink()
        elif self.out.exists():
            self.out.unlink()
        try:
            self.out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise output_error(self.out, exc) from None

    def record(self, k: int, payload: bytes, digest: str) -> dict[str, Any]:
        return {"chunk": k, "rows": _chunk_rows_range(self.spec, k),
                "part": self.part(k).name, "bytes": len(payload), "sha256": digest}  # fmt: skip

    def well_formed(self, r: dict[str, Any], k: int, prev: dict[str, Any] | None) -> bool:
        return r.get("part") == self.part(k).name

    def bad_chunks(self, records: list[dict[str, Any]], first_only: bool
                   ) -> list[tuple[int, str]]:  # fmt: skip
        if not self.out.is_dir():
            raise ParameterError(f"{self.out}: not a folder of Parquet parts; cannot resume")
        bad: list[tuple[int, str]] = []
        for r in records:
            if first_only and bad:
                break
            p = self.out / r["part"]
            try:
                size = p.stat().st_size
                if size != r["bytes"]:
                    bad.append((r["chunk"], f"({p.name}) holds {size} bytes, not the "
                                f"{r['bytes']} written (truncated or altered)"))  # fmt: skip
                elif _digest(p.read_bytes()) != r["sha256"]:
                    bad.append((r["chunk"], f"({p.name}) does not match its checksum"))
            except FileNotFoundError:
                bad.append((r["chunk"], f"({p.name}) is missing"))
            except OSError as exc:
                bad.append((r["chunk"], f"({p.name}) is unreadable ({exc.strerror})"))
        return bad

    def cut(self, records: list[dict[str, Any]]) -> None:
        """Remove leftover temporaries and the parts written but not recorded."""
        parts, temps, _ = self._listing()
        for p in temps:
            p.unlink()
        for k in parts:
            if k >= len(records):
                self.part(k).unlink()

    def repair(self, records: list[dict[str, Any]], recompute: Callable[[int], bytes]
               ) -> list[int]:  # fmt: skip
        fixed = []
        for k, _ in self.bad_chunks(records, first_only=False):
            write_bytes(self.part(k), _recomputed(self.out, records[k], recompute))
            fixed.append(k)
        return fixed

    def __enter__(self) -> _ParquetSink:
        return self

    def write(self, k: int, payload: bytes, digest: str) -> dict[str, Any]:
        write_bytes(self.part(k), payload)  # atomic: a part is whole or absent
        return self.record(k, payload, digest)

    def sync(self) -> None:
        pass  # each part is flushed as it is renamed into place

    def remove(self) -> None:
        if self.out.is_dir():
            parts, temps, other = self._listing()
            for p in [*map(self.part, parts), *temps]:
                p.unlink()
            if not other:
                self.out.rmdir()

    def __exit__(self, *exc: object) -> None:
        pass


def _parquet_part(
    spec: SweepSpec, outputs: Sequence[str], ids: np.ndarray, cols: Sequence[np.ndarray]
) -> bytes:
    """One chunk as a Parquet file: lengths in mm, integers as int64, outputs float64; each
    column's unit and meaning in its field metadata, the sweep's ``.meta.json`` record in the
    schema metadata (``mrclutch.sweep``)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    units = describe([k for k in outputs if k in OUTPUTS])
    fields = [
        pa.field(
            "design_id",
            pa.int64(),
            metadata={"unit": "1", "description": "design number in the sweep spec (0..N-1)"},
        )
    ]
    for p in spec.params:
        meaning = f"swept DrumClutch.{p.name}"
        if p.categories:  # a dictionary column: the names once, an index a row
            meaning = f"swept material of the {p.name} (registry name)"
            kind = pa.dictionary(pa.int32(), pa.string())
            fields.append(pa.field(p.column, kind, metadata={"unit": "", "description": meaning}))
        elif p.integer:
            fields.append(
                pa.field(p.column, pa.int64(), metadata={"unit": "1", "description": meaning})
            )
        else:
            fields.append(
                pa.field(p.column, pa.float64(), metadata={"unit": "mm", "description": meaning})
            )
    for name in outputs:
        fields.append(pa.field(name, pa.float64(), metadata=units.get(name)))
    schema = pa.schema(fields, metadata={"mrclutch.sweep": json.dumps(_meta(spec, outputs))})
    arrays = []
    for a, f, p in zip([ids, *cols], fields, [None, *spec.params, *[None] * len(outputs)],
                       strict=True):  # fmt: skip
        if p is not None and p.categories:
            index = {name: i for i, name in enumerate(p.categories)}
            codes = np.fromiter((index[x] for x in a), dtype=np.int32, count=len(a))
            arrays.append(pa.DictionaryArray.from_arrays(codes, pa.array(p.categories)))
        else:
            arrays.append(pa.array(np.asarray(a, dtype=f.type.to_pandas_dtype())))
    table = pa.Table.from_arrays(arrays, schema=schema)
    buf = pa.BufferOutputStream()
    pq.write_table(table, buf)
    return buf.getvalue().to_pybytes()


def _format_chunk(ids: np.ndarray, cols: Sequence[np.ndarray]) -> str:
    """CSV rows of a chunk (NaN written as ``nan``, a material column's names as text),
    formatted in one C-level operation."""
    text = [np.asarray(c).dtype == object for c in cols]
    if not any(text):
        table = np.column_stack([ids.astype(float), *[np.asarray(c, dtype=float) for c in cols]])
    else:
        table = np.empty((ids.size, len(cols) + 1), dtype=object)
        table[:, 0] = ids
        for j, (c, t) in enumerate(zip(cols, text, strict=True), start=1):
            table[:, j] = [csv_text(x) for x in c] if t else np.asarray(c, dtype=float)
    row = ",".join(["%d"] + ["%s" if t else "%.9g" for t in text]) + "\n"
    return (row * ids.size) % tuple(table.ravel().tolist())


def csv_text(name: str) -> str:
    """A name as one CSV cell (RFC 4180: quoted where it holds a comma, quote or newline)."""
    if any(c in name for c in ',"\r\n'):
        return '"' + name.replace('"', '""') + '"'
    return name


def _display(name: str, values: np.ndarray) -> np.ndarray:
    return values if name in INTEGER_FIELDS else values * 1e3


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
