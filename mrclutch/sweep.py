"""Vectorised design sweeps: a spec, chunks of designs, CSV streamed as it comes, resume.

A sweep is a grid or a random sample over DrumClutch parameters (ranges in mm in the spec
file). Designs are numbered 0..N−1; chunk k holds designs [k·C, (k+1)·C). A chunk's
designs depend only on the spec and k (random chunks draw from a generator seeded with
(seed, k)), so an interrupted sweep resumed later writes exactly the rows an
uninterrupted one would.

Each finished chunk is appended to the CSV in order with one write and a flush; a
sidecar ``<out>.meta.json`` records the spec's fingerprint so ``resume`` refuses a
different spec. Any ``concurrent.futures.Executor`` (a process pool, or a Dask
``Client.get_executor()``) may evaluate the chunks.
"""

from __future__ import annotations

import hashlib
import json
import math
import signal
import tomllib
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, Future
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from geometry.params import INT_RANGES, INTEGER_FIELDS, LENGTH_FIELDS, DrumClutch, preset
from geometry.validation import ParameterError, check_int
from mrclutch.outputs import OUTPUTS, describe

Evaluator = Callable[[dict[str, np.ndarray]], dict[str, np.ndarray]]

DEFAULT_CHUNK = 20_000
#: Most designs one spec may ask for: 10⁸ rows are ~20 GB of CSV and hours of the fast
#: path; a larger spec is almost always a typo in a count (4·10¹⁰ was accepted before).
MAX_DESIGNS = 10**8


@dataclass(frozen=True)
class ParamRange:
    """One swept DrumClutch field (SI). Either explicit ``values`` or [lo, hi] with a count."""

    name: str
    lo: float
    hi: float
    count: int
    values: tuple[float, ...] = ()

    @property
    def integer(self) -> bool:
        return self.name in INTEGER_FIELDS

    @property
    def column(self) -> str:
        """CSV column: lengths in mm with the unit in the name, integers as they are."""
        return self.name if self.integer else f"{self.name}_mm"

    def grid(self) -> np.ndarray:
        if self.values:
            return np.asarray(self.values, dtype=float)
        if self.integer:
            return np.arange(int(self.lo), int(self.hi) + 1, dtype=float)
        return np.linspace(self.lo, self.hi, self.count)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        if self.values:
            return rng.choice(np.asarray(self.values, dtype=float), size=n)
        if self.integer:
            return rng.integers(int(self.lo), int(self.hi) + 1, size=n).astype(float)
        return rng.uniform(self.lo, self.hi, size=n)


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep: the base design, the ranges, grid or random, and the chunk size."""

    params: tuple[ParamRange, ...]
    mode: str = "grid"
    samples: int = 0
    seed: int = 0
    base: DrumClutch = field(default_factory=DrumClutch)
    chunk_size: int = DEFAULT_CHUNK

    def __post_init__(self) -> None:
        if self.mode not in ("grid", "random"):
            raise ParameterError(f"mode = {self.mode!r}: must be one of grid, random")
        if not self.params:
            raise ParameterError("parameters: at least one swept parameter is needed")
        check_int("chunk_size", self.chunk_size, 1, 10_000_000)
        check_int("seed", self.seed, 0, 2**63 - 1)  # numpy's SeedSequence takes >= 0 only
        if self.mode == "random":
            check_int("samples", self.samples, 1, MAX_DESIGNS)
        elif self.n_designs > MAX_DESIGNS:
            counts = " × ".join(f"{len(p.grid())} ({p.column})" for p in self.params)
            raise ParameterError(
                f"parameters: the grid has {counts} = {self.n_designs:.3g} designs: must be "
                f"<= {MAX_DESIGNS:.0e} (mrclutch.sweep.MAX_DESIGNS); lower the counts"
            )

    @property
    def n_designs(self) -> int:
        if self.mode == "random":
            return self.samples
        return math.prod(len(p.grid()) for p in self.params)

    @property
    def n_chunks(self) -> int:
        return -(-self.n_designs // self.chunk_size)

    @property
    def columns(self) -> tuple[str, ...]:
        return tuple(p.column for p in self.params)

    def fingerprint(self) -> str:
        """A hash of everything that decides the rows (not the chunk size's effect on order)."""
        desc = {
            "params": [(p.name, p.lo, p.hi, p.count, p.values) for p in self.params],
            "mode": self.mode,
            "samples": self.samples,
            "seed": self.seed,
            "base": self.base.to_mm(),
            "chunk_size": self.chunk_size,
        }
        return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:16]

    def chunk(self, k: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Design ids and DrumClutch field arrays (SI) of chunk k."""
        start = k * self.chunk_size
        stop = min(start + self.chunk_size, self.n_designs)
        ids = np.arange(start, stop, dtype=np.int64)
        out: dict[str, np.ndarray] = {}
        if self.mode == "grid":
            grids = [p.grid() for p in self.params]
            digits = np.unravel_index(ids, tuple(len(g) for g in grids))
            for p, g, d in zip(self.params, grids, digits, strict=True):
                out[p.name] = g[d]
        else:
            rng = np.random.default_rng([self.seed, k])
            for p in self.params:
                out[p.name] = p.sample(rng, ids.size)
        for p in self.params:
            if p.integer:
                out[p.name] = out[p.name].astype(np.int64)
        return ids, out


def parse_parameters(table: Mapping[str, Any], mode: str, where: str) -> tuple[ParamRange, ...]:
    """``[parameters]`` table: ``gap_mm = {min = 0.2, max = 0.5, count = 4}`` or
    ``{values = [...]}``; integers (``n_drums``) take ``{min, max}`` inclusive."""
    out = []
    for key, spec in table.items():
        if key in INTEGER_FIELDS:
            name, scale = key, 1.0
        elif key.endswith("_mm") and key[:-3] in LENGTH_FIELDS:
            name, scale = key[:-3], 1e-3
        elif key in LENGTH_FIELDS:
            raise ParameterError(f"{where}: {key}: lengths need their unit in the key ({key}_mm)")
        else:
            raise ParameterError(f"{where}: {key}: unknown sweep parameter")
        if not isinstance(spec, dict):
            raise ParameterError(
                f"{where}: {key}: give a table such as {{min = 0.2, max = 0.5, count = 4}}"
            )
        allowed = {"min", "max", "count", "values"}
        bad = sorted(set(spec) - allowed)
        if bad:
            raise ParameterError(f"{where}: {key}.{bad[0]}: unknown key (min, max, count, values)")
        if "values" in spec:
            vals = spec["values"]
            if not isinstance(vals, list) or not vals:
                raise ParameterError(f"{where}: {key}.values: must be a non-empty list")
            if name in INTEGER_FIELDS:
                values = tuple(
                    float(check_int(f"{where}: {key}.values", v, *_INT_RANGE[name])) for v in vals
                )
            else:
                values = tuple(_number(f"{where}: {key}.values", v) * scale for v in vals)
            out.append(ParamRange(name, min(values), max(values), len(values), values))
            continue
        for k in ("min", "max"):
            if k not in spec:
                raise ParameterError(f"{where}: {key}.{k}: missing")
        if name in INTEGER_FIELDS:  # the field's own range (DrumClutch's INT_RANGES)
            lo = check_int(f"{where}: {key}.min", spec["min"], *_INT_RANGE[name])
            hi = check_int(f"{where}: {key}.max", spec["max"], *_INT_RANGE[name])
        else:
            lo = _number(f"{where}: {key}.min", spec["min"]) * scale
            hi = _number(f"{where}: {key}.max", spec["max"]) * scale
        if hi < lo:
            raise ParameterError(
                f"{where}: {key}: max = {spec['max']} is below min = {spec['min']}"
            )
        count = 0
        if name not in INTEGER_FIELDS and mode == "grid":
            if "count" not in spec:
                raise ParameterError(f"{where}: {key}.count: missing (grid sweeps need a count)")
            count = check_int(f"{where}: {key}.count", spec["count"], 1, 10**7)
        out.append(ParamRange(name, lo, hi, count))
    return tuple(out)


_INT_RANGE = {name: (lo, hi) for name, lo, hi in INT_RANGES}


def _number(name: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ParameterError(f"{name} = {v!r}: must be a finite number")
    return float(v)


def load_spec(path: str | Path) -> tuple[SweepSpec, dict[str, Any]]:
    """Read a sweep spec file: ``[sweep]`` (mode, samples, seed, base, chunk_size),
    ``[parameters]``; the other tables (``[operating]``, ``[transmission]``) are returned
    for the design layer to read."""
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParameterError(f"sweep spec {p}: not found") from None
    except IsADirectoryError:
        raise ParameterError(f"sweep spec {p}: is a directory") from None
    except UnicodeDecodeError as exc:
        raise ParameterError(f"sweep spec {p}: not UTF-8 text ({exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"sweep spec {p}: not valid TOML ({exc})") from None
    for table in ("sweep", "parameters"):
        if table not in data or not isinstance(data[table], dict):
            raise ParameterError(f"sweep spec {p}: missing the [{table}] table")
    sw = dict(data["sweep"])
    known = {"mode", "samples", "seed", "base", "chunk_size"}
    bad = sorted(set(sw) - known)
    if bad:
        raise ParameterError(f"{p}: sweep.{bad[0]}: unknown key ({', '.join(sorted(known))})")
    mode = sw.pop("mode", "grid")
    base_name = sw.pop("base", "paper")
    if not isinstance(base_name, str):
        raise ParameterError(f"{p}: sweep.base = {base_name!r}: must be a preset name")
    base = preset(base_name)
    params = parse_parameters(data["parameters"], mode, str(p))
    spec = SweepSpec(params, mode=mode, base=base, **sw)
    rest = {k: v for k, v in data.items() if k not in ("sweep", "parameters")}
    return spec, rest


@dataclass(frozen=True)
class SweepResult:
    path: Path
    rows: int
    complete: bool
    resumed_from: int = 0


def _meta_path(out: Path) -> Path:
    return out.with_name(out.name + ".meta.json")


def _read_or_refuse(path: Path, parse: Callable[[str], Any]) -> Any:
    """``parse`` of a file left by an earlier run; a corrupt one refuses the resume in one line."""
    try:
        return parse(path.read_text(encoding="utf-8"))
    except (ValueError, OSError) as exc:  # JSONDecodeError and UnicodeDecodeError too
        raise ParameterError(
            f"{path}: unreadable ({type(exc).__name__}); cannot resume; pass --overwrite "
            "to start again"
        ) from None


def _rows_on_disk(out: Path, spec: SweepSpec) -> int:
    """Rows of whole chunks already in ``out``; trims any partial chunk or line."""
    with out.open("rb+") as f:
        lines = f.read().split(b"\n")
        header, body = lines[0], lines[1:]
        complete = [ln for ln in body[:-1]]  # the last element follows the final newline
        whole = (len(complete) // spec.chunk_size) * spec.chunk_size
        if len(complete) == spec.n_designs:
            whole = len(complete)
        keep = header + b"\n" + b"".join(ln + b"\n" for ln in complete[:whole])
        f.seek(0)
        f.write(keep)
        f.truncate()
    for i, ln in enumerate(complete[:whole]):
        head = ln.split(b",", 1)[0]
        if not head.isdigit() or int(head) != i:
            raise ParameterError(f"{out}: row {i} has design_id {head!r}; cannot resume")
    return whole


def _format_chunk(ids: np.ndarray, cols: Sequence[np.ndarray]) -> str:
    """CSV rows of a chunk (NaN written as ``nan``), formatted in one C-level operation."""
    table = np.column_stack([ids.astype(float), *[np.asarray(c, dtype=float) for c in cols]])
    row = ",".join(["%d"] + ["%.9g"] * len(cols)) + "\n"
    return (row * ids.size) % tuple(table.ravel().tolist())


def _display(name: str, values: np.ndarray) -> np.ndarray:
    return values if name in INTEGER_FIELDS else values * 1e3


@contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """``kill`` (SIGTERM) stops a sweep as Ctrl-C does: after the current chunk is safe."""

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    evaluate: Evaluator,
    outputs: Sequence[str],
    *,
    executor: Executor | None = None,
    resume: bool = False,
    overwrite: bool = False,
    progress: bool = True,
    max_pending: int = 4,
) -> SweepResult:
    """Evaluate every chunk of ``spec`` with ``evaluate`` and stream rows to ``out`` (CSV).

    ``evaluate(fields) -> {output: array}`` must be picklable when an executor is given.
    On Ctrl-C or SIGTERM the finished chunks stay on disk; ``resume=True`` continues.
    """
    out = Path(out)
    meta = {
        "fingerprint": spec.fingerprint(),
        "n_designs": spec.n_designs,
        "columns": describe([k for k in outputs if k in OUTPUTS]),  # units and meanings
    }
    header = ",".join(["design_id", *spec.columns, *outputs])
    start_rows = 0
    if out.exists() and resume:
        mp = _meta_path(out)
        old = _read_or_refuse(mp, json.loads) if mp.exists() else {}
        first = _read_or_refuse(out, lambda text: text.split("\n", 1)[0])
        if old != meta:
            raise ParameterError(f"{out}: written by a different sweep spec; cannot resume")
        if first != header:
            raise ParameterError(f"{out}: its columns differ from this sweep's; cannot resume")
        start_rows = _rows_on_disk(out, spec)
    elif out.exists() and not overwrite:
        raise ParameterError(f"{out}: exists; pass --resume to continue it or --overwrite")
    else:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(header + "\n")
        _meta_path(out).write_text(json.dumps(meta))

    first_chunk = start_rows // spec.chunk_size if start_rows < spec.n_designs else spec.n_chunks
    rows = start_rows
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=spec.n_designs, initial=start_rows, unit="design", desc="sweep")
    try:
        with _sigterm_as_interrupt(), out.open("a") as f:
            for n, text in _results(spec, evaluate, outputs, first_chunk, executor, max_pending):
                f.write(text)
                f.flush()
                rows += n
                if bar is not None:
                    bar.update(n)
    except KeyboardInterrupt:
        return SweepResult(out, rows, False, start_rows)
    finally:
        if bar is not None:
            bar.close()
    return SweepResult(out, rows, True, start_rows)


def chunk_rows(
    spec: SweepSpec, evaluate: Evaluator, outputs: Sequence[str], k: int
) -> tuple[int, str]:
    """Chunk k evaluated and formatted as CSV rows (runs in a worker: only text returns)."""
    ids, fields = spec.chunk(k)
    res = evaluate(fields)
    cols = [_display(p.name, fields[p.name]) for p in spec.params]
    cols += [res[name] for name in outputs]
    return ids.size, _format_chunk(ids, cols)


def _results(
    spec: SweepSpec,
    evaluate: Evaluator,
    outputs: Sequence[str],
    first: int,
    executor: Executor | None,
    max_pending: int,
) -> Iterator[tuple[int, str]]:
    """(rows, CSV text) of every chunk from ``first`` on, in chunk order, evaluated
    in-process or on ``executor``."""
    if executor is None:
        for k in range(first, spec.n_chunks):
            yield chunk_rows(spec, evaluate, outputs, k)
        return
    pending: dict[int, Future] = {}
    nxt = first
    try:
        for k in range(first, spec.n_chunks):
            pending[k] = executor.submit(chunk_rows, spec, evaluate, tuple(outputs), k)
            while pending and (len(pending) >= max_pending or k == spec.n_chunks - 1):
                yield pending.pop(nxt).result()
                nxt += 1
    finally:  # interrupted: drop the work not yet written
        for fut in pending.values():
            fut.cancel()


def pareto_front(objectives: np.ndarray, maximize: Sequence[bool]) -> np.ndarray:
    """Boolean mask of the non-dominated rows of ``objectives`` (n × k); NaN rows excluded.

    A row is dominated when another is at least as good in every objective and better in
    one. Sorted sweep on the first objective, each candidate checked against the front.
    """
    obj = np.asarray(objectives, dtype=float)
    sign = np.where(np.asarray(maximize), 1.0, -1.0)
    x = obj * sign  # now maximise everything
    ok = np.all(np.isfinite(x), axis=1)
    idx = np.flatnonzero(ok)
    order = idx[np.lexsort(tuple(-x[idx, j] for j in reversed(range(x.shape[1]))))]
    front: list[int] = []
    fx = np.empty((0, x.shape[1]))
    for i in order:
        xi = x[i]
        if fx.shape[0] and np.any(np.all(fx >= xi, axis=1)):
            continue
        front.append(i)
        fx = np.vstack([fx, xi])
    mask = np.zeros(obj.shape[0], dtype=bool)
    mask[front] = True
    return mask
