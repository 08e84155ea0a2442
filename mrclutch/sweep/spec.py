"""What a sweep computes: the spec file (``load_spec``), its swept parameters
(``ParamRange``, ranges in mm in the file, SI here), the user's material files it names
(``MaterialFile``) and the designs of each chunk (``SweepSpec.chunk``).

Designs are numbered 0..N−1; chunk k holds designs [k·C, (k+1)·C). A chunk's designs
depend only on the spec and k (random chunks draw from a generator seeded with (seed, k)),
so an interrupted sweep resumed later writes exactly the rows an uninterrupted one would.
"""

from __future__ import annotations

import hashlib
import json
import math
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from geometry.atomic import write_bytes
from geometry.materials import SLOTS, MaterialChoice
from geometry.params import INT_RANGES, INTEGER_FIELDS, LENGTH_FIELDS, DrumClutch, preset
from geometry.validation import ParameterError, check_int
from magnetics.materials import load_fluid
from mrclutch.inputs import read_toml
from mrclutch.render import render_from_mapping

DEFAULT_CHUNK = 20_000
#: Most designs one spec may ask for: 10⁸ rows are ~20 GB of CSV and hours of the fast
#: path; a larger spec is almost always a typo in a count (4·10¹⁰ was accepted before).
MAX_DESIGNS = 10**8


@dataclass(frozen=True)
class ParamRange:
    """One swept DrumClutch field (SI). Either explicit ``values`` or [lo, hi] with a count;
    or a categorical axis, a part's material (``categories``: registry names; ``chunk``
    gives indices into them, ``design_fields`` and the output the names themselves)."""

    name: str
    lo: float
    hi: float
    count: int
    values: tuple[float, ...] = ()
    categories: tuple[str, ...] = ()

    @property
    def integer(self) -> bool:
        return self.name in INTEGER_FIELDS or bool(self.categories)

    @property
    def column(self) -> str:
        """CSV column: lengths in mm with the unit in the name, integers as they are, a
        material under the part's name (``fluid``), its values the registry names."""
        if self.categories:
            return self.name
        return self.name if self.integer else f"{self.name}_mm"

    def named(self, values: np.ndarray) -> np.ndarray:
        """A categorical axis' indices as its registry names (an object array)."""
        return np.asarray(self.categories, dtype=object)[np.asarray(values, dtype=np.int64)]

    def grid(self) -> np.ndarray:
        if self.categories:
            return np.arange(len(self.categories), dtype=float)
        if self.values:
            return np.asarray(self.values, dtype=float)
        if self.integer:
            return np.arange(int(self.lo), int(self.hi) + 1, dtype=float)
        return np.linspace(self.lo, self.hi, self.count)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        if self.categories:
            return rng.integers(0, len(self.categories), size=n).astype(float)
        if self.values:
            return rng.choice(np.asarray(self.values, dtype=float), size=n)
        if self.integer:
            return rng.integers(int(self.lo), int(self.hi) + 1, size=n).astype(float)
        return rng.uniform(self.lo, self.hi, size=n)


#: Material files loaded in this process from their bytes (``MaterialFile.ensure``):
#: registry name → SHA-256 of the bytes.
_LOADED: dict[str, str] = {}


@dataclass(frozen=True)
class MaterialFile:
    """A user's material file a spec names (``[materials] fluid_file``, or a ``.toml``
    value of a fluid axis): the path as the spec writes it, the registry name it loads as
    and its bytes. The bytes travel with the spec to every worker (a Dask worker never read
    the file: ``ensure``) and into the resume fingerprint (``SweepSpec.input_digests``)."""

    written: str
    name: str
    data: bytes = field(repr=False)

    @property
    def digest(self) -> str:
        return hashlib.sha256(self.data).hexdigest()

    def ensure(self) -> None:
        """The file's fluid registered in this process from the bytes, unless these very
        bytes already were (a long-lived worker may hold an older version of the file)."""
        if _LOADED.get(self.name) == self.digest:
            return
        with tempfile.TemporaryDirectory() as folder:
            copy = Path(folder) / Path(self.written).name  # messages name the user's file
            write_bytes(copy, self.data)
            load_fluid(copy)
        _LOADED[self.name] = self.digest


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep: the base design, the ranges, grid or random, and the chunk size;
    ``inputs``: (what, SHA-256) of every other input the spec file gives (its sections:
    ``load_spec``), ``material_files``: the user's material files it names. Both enter the
    fingerprint a resume checks."""

    params: tuple[ParamRange, ...]
    mode: str = "grid"
    samples: int = 0
    seed: int = 0
    base: DrumClutch = field(default_factory=DrumClutch)
    chunk_size: int = DEFAULT_CHUNK
    inputs: tuple[tuple[str, str], ...] = ()
    material_files: tuple[MaterialFile, ...] = ()

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

    def input_digests(self) -> dict[str, str]:
        """What → SHA-256 of each input beyond the parameters: the spec's sections
        (``inputs``) and the contents of each material file it names."""
        files = {f"material file {m.written}": m.digest for m in self.material_files}
        return {**dict(self.inputs), **files}

    def fingerprint(self) -> str:
        """A hash of everything in the spec that decides the rows: the sweep, its ranges and
        base, every section of the spec file and the material files it names (the model's
        version is recorded beside it: ``model_version``)."""
        desc = {
            "params": [(p.name, p.lo, p.hi, p.count, p.values, *p.categories) for p in self.params],
            "mode": self.mode,
            "samples": self.samples,
            "seed": self.seed,
            "base": self.base.to_mm(),
            "chunk_size": self.chunk_size,
            "inputs": self.input_digests(),
        }
        return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:16]

    def ensure_materials(self) -> None:
        """The user's material files registered in this process (a worker's first chunk)."""
        for m in self.material_files:
            m.ensure()

    def design_fields(self, k: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """``chunk(k)`` as an evaluator takes it: a material axis as its registry names (an
        object array), the other fields SI."""
        ids, fields = self.chunk(k)
        named = {p.name: p.named(fields[p.name]) for p in self.params if p.categories}
        return ids, {**fields, **named}

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
        if key in SLOTS:  # a part's material: a categorical axis over registry names
            vals = spec.get("values") if isinstance(spec, dict) else None
            if not isinstance(vals, list) or not vals or set(spec) != {"values"}:
                raise ParameterError(f'{where}: {key}: a material axis is {{values = ["name", …]}}')
            names = []
            for v in vals:
                if not isinstance(v, str):
                    raise ParameterError(f"{where}: {key}.values: {v!r} is not a material name")
                names.append(getattr(MaterialChoice(**{key: v}), key))  # checked, canonical
            out.append(ParamRange(key, 0.0, len(names) - 1.0, len(names), (), tuple(names)))
            continue
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


#: Spec sections the sweep has no use for, refused (never silently ignored) with the reason.
UNUSED_SECTIONS = {
    "measured": "a bench's figures belong to one built device, and a sweep varies the design "
    "(its rows are the model's); evaluate the built design's file to compare or use them",
    "process": "the sweep does not apply the builder's limits (the smallest gap and wall); "
    "mrclutch optimize does",
}


#: Why a sweep takes ``[render]`` only as what its rows are: each design at its own K_max.
RENDER_WHY = (
    "a sweep's rows render each design at its own K_max = F_max/d (its K_N_per_m column) "
    "and give no verdict; the worst case's K is --with max_stable_K_worst_N_per_m and "
    "max_passive_K_worst_N_per_m, a typed K and the verdict are evaluate's"
)


def _check_render(table: Any, p: Path) -> None:
    """``[render]`` applied or refused, never ignored: the rule the rows follow (K_max) is
    accepted, another rule or a verdict (which no row holds) refused, naming the key."""
    if table is None:
        return
    if not isinstance(table, dict):
        raise ParameterError(f"{p}: render = {table!r}: must be a table ([render])")
    render = render_from_mapping(table, f"{p}: render")
    if render.rule != "K_max":
        raise ParameterError(f"{p}: render.rule = {render.rule!r}: not used by a sweep "
                             f"({RENDER_WHY}); remove [render] or give rule = 'K_max'")  # fmt: skip
    if "verdict" in table:
        raise ParameterError(f"{p}: render.verdict = {render.verdict!r}: not used by a sweep "
                             f"({RENDER_WHY}); remove it")  # fmt: skip


def _digest_of(value: Any) -> str:
    """SHA-256 of a parsed TOML value (its canonical JSON: keys sorted; dates as text)."""
    text = json.dumps(value, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _material_file(spec_path: Path, written: str, where: str) -> MaterialFile:
    """A fluid file the spec names (relative to the spec's folder), read and registered."""
    path = Path(written) if Path(written).is_absolute() else spec_path.parent / written
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ParameterError(f"{where} = {written!r}: cannot read it ({exc.strerror})") from None
    name = load_fluid(path)
    m = MaterialFile(written, name, data)
    _LOADED[name] = m.digest
    return m


def _material_files(data: dict[str, Any], p: Path) -> list[MaterialFile]:
    """The user's material files of a spec: ``[materials] fluid_file`` and the ``.toml``
    values of a fluid axis (each replaced in ``data`` by the name it registers)."""
    files: list[MaterialFile] = []
    mats = data.get("materials")
    if isinstance(mats, dict) and isinstance(mats.get("fluid_file"), str):
        files.append(_material_file(p, mats["fluid_file"], f"{p}: materials.fluid_file"))
    axis = data["parameters"].get("fluid")
    if isinstance(axis, dict) and isinstance(axis.get("values"), list):
        values = []
        for v in axis["values"]:
            if isinstance(v, str) and v.lower().endswith(".toml"):
                files.append(_material_file(p, v, f"{p}: fluid.values"))
                v = files[-1].name
            values.append(v)
        data["parameters"] = {**data["parameters"], "fluid": {**axis, "values": values}}
    names: dict[str, MaterialFile] = {}
    for m in files:
        if m.name in names and names[m.name].data != m.data:
            raise ParameterError(f"{p}: {names[m.name].written} and {m.written} both define "
                                 f"the fluid {m.name!r} differently; rename one")  # fmt: skip
        names[m.name] = m
    return files


def load_spec(path: str | Path) -> tuple[SweepSpec, dict[str, Any]]:
    """Read a sweep spec file: ``[sweep]`` (mode, samples, seed, base, chunk_size),
    ``[parameters]``, ``[clutch]`` (fixed dimensions over the base preset); the other
    tables (``[operating]``, ``[transmission]``, ``[materials]`` …) are returned for the
    design layer to read. Every section enters the spec's fingerprint (``inputs``), with
    the contents of the material files it names; a section the sweep cannot use
    (``UNUSED_SECTIONS``) is refused, and ``[render]`` unless it is the rule the rows
    follow (``_check_render``)."""
    p = Path(path)
    data = read_toml(p, "sweep spec")
    for table in ("sweep", "parameters"):
        if table not in data or not isinstance(data[table], dict):
            raise ParameterError(f"sweep spec {p}: missing the [{table}] table")
    for table, why in UNUSED_SECTIONS.items():
        if table in data:
            raise ParameterError(f"{p}: [{table}]: not used by a sweep ({why}); remove it")
    _check_render(data.get("render"), p)
    inputs = {f"[{k}]": _digest_of(v) for k, v in data.items() if isinstance(v, dict)}
    top = {k: v for k, v in data.items() if not isinstance(v, dict)}
    if top:
        inputs["top-level keys"] = _digest_of(top)
    files = _material_files(data, p)
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
    if "clutch" in data:  # fixed dimensions over the base preset
        table = data["clutch"]
        if not isinstance(table, dict) or "base" in table:
            raise ParameterError(f"{p}: [clutch]: dimensions (in mm) over the base preset; "
                                 "the preset itself is [sweep] base")  # fmt: skip
        base = DrumClutch.from_mm(dict(table), base=base, where=f"{p}: clutch")
    params = parse_parameters(data["parameters"], mode, str(p))
    spec = SweepSpec(params, mode=mode, base=base, **sw, inputs=tuple(sorted(inputs.items())),
                     material_files=tuple(files))  # fmt: skip
    rest = {k: v for k, v in data.items() if k not in ("sweep", "parameters", "clutch")}
    return spec, rest
