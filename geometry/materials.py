"""The clutch's materials: one registry of data files, their names, kinds and densities.

Every material is one TOML file in ``geometry/data/materials/`` (the registry): its name,
kind (``steel``: a magnetic steel; ``nonmagnetic``: μr = 1; ``fluid``: an MR fluid), label,
display colour, density, electrical conductivity, thermal data and, by kind, its B–H
table or its rheology, each number with its source (docs/references.md) and a list of the
values that could not be read in a source (``unverified``). This module reads what the
geometry needs (names, kinds, densities, labels, colours); ``magnetics.materials`` reads
the B–H curves, the yield stress and the viscosity from the same files.

A design chooses a material per part (``MaterialChoice``: the fluid and the materials of
the core, drums, shell, bands, housing and hub); the region table writes the chosen names
on its regions (``geometry.regions.table``) and every model reads them from there.
"""

from __future__ import annotations

import marshal
import math
import re
import sys
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from geometry.atomic import OutputError, user_cache, write_bytes
from geometry.reading import decode_text, parse_toml, read_bytes
from geometry.validation import ParameterError

STEEL = "steel_1018"  # the default magnetic yoke and the drums' active zones
STAINLESS = "stainless_304"  # the default hub, shaft, end caps, sleeve and drum bands
COIL = "coil"  # copper wire smeared with its bonding epoxy over the coil window
MRF = "mrf_132dg"  # the default MR fluid

#: The folder of the registry's data files.
DATA = Path(__file__).parent / "data" / "materials"
#: Kinds of material, and what each part may be made of.
KINDS: tuple[str, ...] = ("steel", "nonmagnetic", "fluid")

_RECORDS: dict[str, Mapping[str, Any]] = {}
_DENSITY: dict[str, float] = {}
_LABEL: dict[str, str] = {COIL: "coil (Cu + epoxy)"}
_COLOUR: dict[str, tuple[float, float, float]] = {COIL: (0.85, 0.45, 0.15)}
_KIND: dict[str, str] = {}
_BUILTIN: set[str] = set()

#: Every material's data file, parsed (name -> its TOML table; read-only views).
RECORDS: Mapping[str, Mapping[str, Any]] = MappingProxyType(_RECORDS)
#: kg/m³. The coil's density depends on its fill: see ``coil_density``.
DENSITY: Mapping[str, float] = MappingProxyType(_DENSITY)
#: How a person reads each material's name, and its display colour (RGB 0..1): the STEP
#: assembly, the 3-D view and the section plot share them.
LABEL: Mapping[str, str] = MappingProxyType(_LABEL)
COLOUR: Mapping[str, tuple[float, float, float]] = MappingProxyType(_COLOUR)
#: The kind of every registered material (``KINDS``).
KIND: Mapping[str, str] = MappingProxyType(_KIND)
#: kg/m³ a material's density may take (our plausibility bound: above every element's
#: density, below any solid's); a material file, a sidecar or --density outside is refused
DENSITY_RANGE = (1.0, 3e4)
DENSITY_COPPER = 8960.0  # [materials]
DENSITY_EPOXY = 1200.0  # bonding epoxy of an epoxy-bonded coil (typical 1.1–1.3 g/cm³)


def canonical(name: str) -> str:
    """The registry key of a material name as people write it: lower case, runs of spaces,
    dashes and dots as one underscore ("MRF-140CG" -> "mrf_140cg", "Hiperco 50" ->
    "hiperco_50")."""
    return re.sub(r"[\s\-.]+", "_", str(name).strip().lower())


def _number(where: str, key: str, value: Any, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ParameterError(f"{where}: {key} = {value!r}: must be a finite number")
    if not lo <= value <= hi:
        raise ParameterError(f"{where}: {key} = {value!r}: must be in [{lo:g}, {hi:g}]")
    return float(value)


def check_record(rec: Mapping[str, Any], where: str) -> dict[str, Any]:
    """The geometry's fields of one material record, checked (name, kind, label, colour,
    density, conductivity, thermal data); ParameterError names the field."""
    name = rec.get("name")
    if not isinstance(name, str) or canonical(name) != name or not name:
        raise ParameterError(f"{where}: name = {name!r}: must be lower case, '_' for spaces")
    kind = rec.get("kind")
    if kind not in KINDS:
        raise ParameterError(f"{where}: kind = {kind!r}: must be one of {', '.join(KINDS)}")
    out = dict(rec)
    out["density"] = _number(where, "density", rec.get("density"), *DENSITY_RANGE)
    out["conductivity"] = _number(where, "conductivity", rec.get("conductivity"), 0.0, 1e9)
    out["specific_heat"] = _number(where, "specific_heat", rec.get("specific_heat"), 1.0, 1e5)
    out["thermal_conductivity"] = _number(
        where, "thermal_conductivity", rec.get("thermal_conductivity"), 1e-3, 1e4
    )
    col = rec.get("colour", (0.5, 0.5, 0.5))
    if not (isinstance(col, list | tuple) and len(col) == 3
            and all(isinstance(c, int | float) and 0 <= c <= 1 for c in col)):  # fmt: skip
        raise ParameterError(f"{where}: colour = {col!r}: must be three numbers in [0, 1]")
    out["colour"] = tuple(float(c) for c in col)
    out["label"] = str(rec.get("label", name))
    unv = rec.get("unverified", [])
    if not isinstance(unv, list) or not all(isinstance(u, str) for u in unv):
        raise ParameterError(f"{where}: unverified = {unv!r}: must be a list of field names")
    return out


def register(rec: Mapping[str, Any], where: str, builtin: bool = False) -> str:
    """Add one checked material record to the registry; a user's material may not take a
    built-in name (nor its label's). Returns its name."""
    out = check_record(rec, where)
    name = out["name"]
    if not builtin and name in _BUILTIN:
        raise ParameterError(f"{where}: name = {name!r}: a built-in material has this name")
    _RECORDS[name] = MappingProxyType(out)
    _DENSITY[name] = out["density"]
    _LABEL[name] = out["label"]
    _COLOUR[name] = out["colour"]
    _KIND[name] = out["kind"]
    if builtin:
        _BUILTIN.add(name)
    return name


def is_builtin(name: str) -> bool:
    """Whether ``name`` is one of the library's own materials (geometry/data/materials),
    not a user's file registered at run time."""
    return name in _BUILTIN


#: The parsed registry's cache: a file per content (``_parsed``), in the user's cache folder.
CACHE = user_cache("materials")
#: Changes when what the cache holds changes shape (the cache holds it, and checks it).
_CACHE_FORMAT = "mrclutch materials 1 " + sys.version


def _parsed(paths: list[Path]) -> list[tuple[str, dict[str, Any]]]:
    """(file name, parsed TOML) of each registry file, as ``read_toml`` gives it. Parsing the
    files costs every command that reads a design more than the rest of this module
    (tomllib is pure Python), so the parse is cached across processes in ``CACHE``, beside
    the files' names and bytes it came from: it is used only where the format, the Python
    version and every file's name and bytes are equal to the cached ones (compared, not
    hashed: hashlib's import alone costs a good part of a parse), so any change to any file,
    or a new or removed one, reads the files afresh. The file is named by the CRC-32 of the
    same, so two contents keep two files. A cache that cannot be read, is not this shape or
    cannot be written is passed over: the files are parsed, as without it."""
    blobs = [read_bytes(p, "material file") for p in paths]
    source = [_CACHE_FORMAT, [p.name for p in paths], blobs]
    key = marshal.dumps(source)
    cache = CACHE / f"{zlib.crc32(key):08x}.marshal"
    try:  # the bounded reader: a FIFO or a device there is refused, not read
        cached = marshal.loads(read_bytes(cache, "materials cache"))
    except (ParameterError, ValueError, EOFError, TypeError):
        cached = None
    if (isinstance(cached, list) and len(cached) == 2 and cached[0] == source
            and isinstance(cached[1], list) and len(cached[1]) == len(paths)
            and all(isinstance(rec, dict) for rec in cached[1])):  # fmt: skip
        return list(zip(source[1], cached[1], strict=True))
    parsed = [parse_toml(decode_text(raw, p, "material file"), p, "material file")
              for p, raw in zip(paths, blobs, strict=True)]  # fmt: skip
    try:
        data = marshal.dumps([source, parsed])
        CACHE.mkdir(parents=True, exist_ok=True)
        write_bytes(cache, data)
    except (OSError, OutputError, ValueError):  # no cache folder, or a value marshal refuses
        pass
    return list(zip(source[1], parsed, strict=True))


def _load_builtin() -> None:
    paths = sorted(DATA.glob("*.toml"))
    for path, (_, rec) in zip(paths, _parsed(paths), strict=True):
        if rec.get("name") != path.stem:
            raise ParameterError(
                f"{path.name}: name = {rec.get('name')!r}: must be the file's stem"
            )
        register(rec, path.name, builtin=True)


_load_builtin()


def known(kind: str) -> tuple[str, ...]:
    """The registered materials of one kind, sorted."""
    return tuple(sorted(n for n, k in _KIND.items() if k == kind))


def conductivity(name: str) -> float:
    """S/m at 20 °C of a registered material (0 for the coil: its eddy currents are the
    amplifier's business)."""
    return 0.0 if name == COIL else float(_RECORDS[name]["conductivity"])


#: The parts a design chooses a material for, and the kind each must be.
SLOTS: Mapping[str, str] = MappingProxyType(
    {
        "fluid": "fluid",
        "core": "steel",
        "drums": "steel",  # the drums' steel in the active zones
        "shell": "steel",  # the poles and the back iron
        "bands": "nonmagnetic",  # the drums' non-magnetic bands
        "housing": "nonmagnetic",  # end caps and the coil's sleeve
        "hub": "nonmagnetic",  # the output hub and shaft
    }
)


@dataclass(frozen=True)
class MaterialChoice:
    """The material of each part (registry names; ``SLOTS`` says which kind each takes).
    Names are accepted as people write them (``canonical``); an unknown name, or one of the
    wrong kind, is refused with the list of the known ones."""

    fluid: str = MRF
    core: str = STEEL
    drums: str = STEEL
    shell: str = STEEL
    bands: str = STAINLESS
    housing: str = STAINLESS
    hub: str = STAINLESS

    def __post_init__(self) -> None:
        for f in fields(self):
            raw = getattr(self, f.name)
            name = canonical(raw) if isinstance(raw, str) else raw
            kind = SLOTS[f.name]
            if name not in _KIND or _KIND[name] != kind:
                raise ParameterError(
                    f"materials.{f.name} = {raw!r}: unknown {kind}; known: {', '.join(known(kind))}"
                )
            object.__setattr__(self, f.name, name)

    @classmethod
    def from_mapping(cls, table: Mapping[str, Any], where: str = "materials") -> MaterialChoice:
        """From a design file's ``[materials]`` table (unknown keys refused)."""
        bad = sorted(set(table) - set(SLOTS))
        if bad:
            raise ParameterError(f"{where}.{bad[0]}: unknown key ({', '.join(SLOTS)})")
        for k, v in table.items():
            if not isinstance(v, str):
                raise ParameterError(f"{where}.{k} = {v!r}: must be a material name (a string)")
        return cls(**dict(table))

    def as_dict(self) -> dict[str, str]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @property
    def default(self) -> bool:
        """True for the materials every figure was measured with (1018, 304, MRF-132DG)."""
        return self == DEFAULT_CHOICE

    @property
    def magnetic(self) -> tuple[str, str, str, str]:
        """(fluid, core, drums, shell): what the magnetic models depend on."""
        return self.fluid, self.core, self.drums, self.shell


DEFAULT_CHOICE = MaterialChoice()


def copper_fraction(turns: Any, wire_diameter: Any, window_area: Any) -> Any:
    """Fraction of the coil window that is copper (floats or arrays)."""
    return turns * (math.pi * wire_diameter**2 / 4) / window_area


def coil_density(turns: Any, wire_diameter: Any, window_area: Any) -> Any:
    """Smeared density of the epoxy-bonded coil: copper fraction of the window, rest epoxy
    (floats or arrays)."""
    frac = copper_fraction(turns, wire_diameter, window_area)
    return frac * DENSITY_COPPER + (1 - frac) * DENSITY_EPOXY
