"""A sweep's rows on disk: a CSV file (each chunk appended with one write) or a Parquet
dataset (a folder of one part a chunk, each written through the output layer), checked
against the sidecar's record on a resume and repaired chunk by chunk; ``read_results``
reads either back as columns.
"""

from __future__ import annotations

import csv
import json
import math
import mmap
import os
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from geometry.atomic import atomic_path, output_error, write_bytes
from geometry.materials import SLOTS
from geometry.params import INTEGER_FIELDS
from geometry.validation import ParameterError
from mrclutch.outputs import OUTPUTS, describe
from mrclutch.sweep.record import _chunk_rows_range, _digest, _meta, _meta_path
from mrclutch.sweep.spec import SweepSpec


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
