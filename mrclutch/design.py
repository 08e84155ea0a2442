"""`ClutchDesign`: the clutch geometry, its operating limits and the transmission it drives.

A design file (TOML) has three tables; lengths in mm with ``_mm`` keys, other units in
the key name too::

    [clutch]                 # DrumClutch dimensions (geometry/params.py)
    base = "paper"           # start from a preset; every key below overrides it
    gap_mm = 0.3
    n_drums = 2

    [operating]              # optional, defaults in `Operating`
    max_current_A = 7.0
    max_current_density_A_per_mm2 = 30.0   # default: IEC 60949 adiabatic for peak_duration_s
    input_speed_rpm = 530
    delay_ms = 1.0
    delay_source = "fixed"   # or "geometry": the delay from magnetics.dynamics
    coil_temperature_C = 20
    fluid_temperature_C = 20
    ambient_temperature_C = 20
    wire_temperature_limit_C = 155
    peak_duration_s = 1.0

    [support]                # optional, defaults in `magnetics.drag.Support`
    bearing = "618"          # SKF series, or "none"
    bearings = 2
    bearing_load_N = 10
    grease_viscosity_mm2_per_s = 110
    seal_torque_mN_m = 0

    [amplifier]              # optional, defaults in `magnetics.amplifier.Amplifier`
    supply_voltage_V = 24
    current_bandwidth_Hz = 2000

    [laminations]            # optional: laminated/slotted steel (0 = solid)
    core_mm = 0
    shell_mm = 0

    [materials]              # optional: per part, from the registry (geometry/materials.py)
    fluid = "MRF-140CG"      # MRF-122EG, MRF-132DG (default), MRF-140CG
    # fluid_file = "my_fluid.toml"   # or a user's fluid (the fields of a registry file)
    core = "Hiperco 50"      # steels: steel_1018 (default), steel_1010, pure_iron,
    drums = "steel 1018"     #   steel_1117, hiperco_50, stainless_430
    shell = "Hiperco 50"
    bands = "stainless 304"  # non-magnetic: stainless_304 (default), aluminium_6061, pla
    housing = "stainless 304"
    hub = "stainless 304"

    [transmission]           # optional, defaults: the paper's MR bench (170 mm lever)
    lever_mm = 170
    gearing = 1.0
    workspace_mm = 50

    [uncertainty]            # optional: ranges of the least certain inputs (defaults and
    gap_tolerance_mm = 0.02  # sources in mrclutch/uncertainty.py, docs/verdicts.md)

    [measured]               # optional: what a bench measured (mrclutch/uncertainty.py)
    m1_g = 1.5

    [render]                 # optional: the K rendered and what the verdict is over
    rule = "K_max"           # K_max (default) | worst_case | typed (mrclutch/render.py)
    verdict = "robust"       # robust (over the ranges, default) | nominal

    [duty]                   # optional, defaults in `mrclutch.duty.Duty` (issue 41)
    torque_N_m = 0.2         # held slipping for time_s (0: none); --duty NM:S
    time_s = 60
    peak_time_s = 30         # the current limit held (hot peak figures)
    on_fraction = 0.25       # share of the fluid's life at the duty torque

    [process]                # optional, defaults in `mrclutch.process.Process`
    runout_mm = 0.03         # TIR of the drums: sets the smallest gap (optimize)
    tolerance_mm = 0.02
    min_wall_mm = 0.25       # the thinnest drum wall

Every key is checked: unknown keys, unit-less keys and wrong types are refused with a
message naming the key.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from geometry import regions
from geometry.materials import MaterialChoice
from geometry.params import DrumClutch, preset
from geometry.section import Section, build_section
from geometry.validation import ParameterError, check_range
from magnetics.amplifier import Amplifier, supply_current
from magnetics.drag import Support
from magnetics.laminations import Laminations
from magnetics.materials import FLUIDS, load_fluid
from mrclutch.duty_spec import DUTY_KEYS, Duty
from mrclutch.haptics.actuator import MR_170, Transmission
from mrclutch.inputs import read_toml
from mrclutch.inputs import toml_value as _toml
from mrclutch.operating import (
    DELAY_SOURCES,
    MAX_DELAY,
    MIN_INPUT_SPEED,
    Operating,
    current_limit,
)
from mrclutch.process import PROCESS_KEYS, Process
from mrclutch.render import Render, render_from_mapping, render_to_toml
from mrclutch.uncertainty import (
    PAPER_BENCH,
    Measured,
    Uncertainty,
    check_consistent,
    default_uncertainty,
    measured_from_mapping,
    measured_to_toml,
    uncertainty_from_mapping,
    uncertainty_to_toml,
)

#: The design and its file; ``Operating`` and ``current_limit`` (mrclutch.operating) are
#: re-exported for the commands that import them from here.
__all__ = [
    "DELAY_SOURCES", "DESIGNS", "MAX_DELAY", "MIN_INPUT_SPEED", "ClutchDesign",
    "Operating", "current_limit", "current_notes", "design_from_mapping", "design_preset",
    "design_to_toml", "load_design",
]  # fmt: skip


@dataclass(frozen=True)
class ClutchDesign:
    """One MR clutch design: geometry + operating limits + the transmission to the hand."""

    clutch: DrumClutch = field(default_factory=DrumClutch)
    operating: Operating = field(default_factory=Operating)
    transmission: Transmission = MR_170
    name: str = "design"
    support: Support = field(default_factory=Support)
    amplifier: Amplifier = field(default_factory=Amplifier)
    laminations: Laminations = field(default_factory=Laminations)
    #: the ranges of the least certain inputs (None: ``default_uncertainty(design)``)
    uncertainty: Uncertainty | None = None
    #: what a bench measured (None: nothing)
    measured: Measured | None = None
    process: Process = field(default_factory=Process)  # what the workshop holds (optimize)
    #: the material of each part (the fluid's range bounds ``operating.fluid_temperature``)
    materials: MaterialChoice = field(default_factory=MaterialChoice)
    #: how it is used: a torque held, the peak hold, the life's duty (``[duty]``, issue 41)
    duty: Duty = field(default_factory=Duty)
    #: the K it renders and what its verdict is over (``[render]``, mrclutch/render.py)
    render: Render = field(default_factory=Render)

    def __post_init__(self) -> None:
        lo, hi = FLUIDS[self.materials.fluid].temperature_range
        check_range("fluid_temperature", self.operating.fluid_temperature, lo, hi,
                    f" °C ({self.materials.fluid}'s range)")  # fmt: skip

    def section(self) -> Section:
        """The clutch's r–z section with the design's materials (what the solvers read
        and the section drawing shows)."""
        return build_section(self.clutch, self.materials)

    @property
    def current_limit(self) -> float:
        """The largest current allowed: max_current, capped by the current-density limit
        and by what the amplifier's supply holds through the coil (``supply_current``)."""
        return float(current_limit(self.operating, self.clutch.wire_diameter,
                                   self.supply_current))  # fmt: skip

    @property
    def supply_current(self) -> float:
        """A: V/R, the most the amplifier holds through the coil at the coil temperature."""
        c = self.clutch
        st = regions.stations(vars(c), c.n_drums)
        return float(supply_current(vars(c), st, self.amplifier, self.operating.coil_temperature))


def _density_notes(design: ClutchDesign) -> tuple[str, ...]:
    """Say when the current-density limit, not max_current, sets the current limit (the
    design is evaluated at a current the user did not type)."""
    op = design.operating
    area = math.pi * design.clutch.wire_diameter**2 / 4
    cap = op.current_density_limit * area  # A = (A/m²)·m²
    if cap >= op.max_current or design.supply_current < cap:  # not the binding limit
        return ()
    source = ("max_current_density_A_per_mm2" if op.max_current_density is not None
              else f"IEC 60949 adiabatic limit for {op.peak_duration:g} s")  # fmt: skip
    return (f"the current-density limit caps the current at {cap:.4g} A, below "
            f"max_current_A = {op.max_current:g}: {op.current_density_limit * 1e-6:.4g} A/mm² "
            f"({source}) in the {design.clutch.wire_diameter * 1e3:.3g} mm wire; every "
            f"figure is at {cap:.4g} A",)  # fmt: skip


def _supply_notes(design: ClutchDesign) -> tuple[str, ...]:
    """Say when the amplifier's supply, not max_current, sets the current limit."""
    op, supply = design.operating, design.supply_current
    if supply >= current_limit(op, design.clutch.wire_diameter):  # capped without the supply
        return ()
    volts = design.amplifier.supply_voltage
    return (f"the amplifier's {volts:g} V supply holds at most {supply:.3g} A through the "
            f"coil ({volts / supply:.3g} Ω at {op.coil_temperature:g} °C): the current "
            f"limit is {supply:.3g} A, below max_current_A = {op.max_current:g}; raise "
            "[amplifier] supply_voltage_V to reach it",)  # fmt: skip


def current_notes(design: ClutchDesign) -> tuple[str, ...]:
    """Why the design's current limit is below its typed max_current_A (the current
    density in the wire, the amplifier's supply), as ``evaluate`` and ``torque`` print it;
    () if it is not. Beside the limit, so ``torque`` reads it without mrclutch.clutch."""
    return _density_notes(design) + _supply_notes(design)


#: Named designs. "paper": the paper's clutch on the paper's MR bench (170 mm lever).
DESIGNS: dict[str, ClutchDesign] = {
    "paper": ClutchDesign(clutch=preset("paper"), name="paper", measured=PAPER_BENCH),
}


def design_preset(name: str) -> ClutchDesign:
    """A named design; geometry presets without a design of their own get the defaults."""
    if name in DESIGNS:
        return DESIGNS[name]
    return ClutchDesign(clutch=preset(name), name=name)


# ---- design files ----------------------------------------------------------------------

# key in the file -> (field, factor to SI)
_OPERATING_KEYS: dict[str, tuple[str, float]] = {
    "max_current_A": ("max_current", 1.0),
    "max_current_density_A_per_mm2": ("max_current_density", 1e6),
    "input_speed_rpm": ("input_speed", 2 * math.pi / 60),
    "delay_ms": ("delay", 1e-3),
    "coil_temperature_C": ("coil_temperature", 1.0),
    "fluid_temperature_C": ("fluid_temperature", 1.0),
    "ambient_temperature_C": ("ambient_temperature", 1.0),
    "wire_temperature_limit_C": ("wire_temperature_limit", 1.0),
    "peak_duration_s": ("peak_duration", 1.0),
}
_SUPPORT_KEYS: dict[str, tuple[str, float]] = {
    "bearings": ("bearings", 1.0),
    "bearing_load_N": ("bearing_load", 1.0),
    "grease_viscosity_mm2_per_s": ("grease_viscosity", 1e-6),
    "seal_torque_mN_m": ("seal_torque", 1e-3),
}
_AMPLIFIER_KEYS: dict[str, tuple[str, float]] = {
    "supply_voltage_V": ("supply_voltage", 1.0),
    "current_bandwidth_Hz": ("current_bandwidth_hz", 1.0),
}
_LAMINATION_KEYS: dict[str, tuple[str, float]] = {
    "core_mm": ("core", 1e-3),
    "shell_mm": ("shell", 1e-3),
}
_TRANSMISSION_KEYS: dict[str, tuple[str, float]] = {
    "ratio": ("ratio", 1.0),
    "lever_mm": ("lever", 1e-3),
    "gearing": ("gearing", 1.0),
    "k_N_per_m": ("k", 1.0),
    "b_N_s_per_m": ("b", 1.0),
    "m2_g": ("m2", 1e-3),
    "workspace_mm": ("workspace", 1e-3),
}


def _read_table(
    table: Mapping[str, Any], keys: Mapping[str, tuple[str, float]], where: str
) -> dict[str, float]:
    out: dict[str, float] = {}
    for key, value in table.items():
        if key not in keys:
            bare = {k.rsplit("_", 1)[0]: k for k in keys if "_" in k}
            hint = f"; write {bare[key]}" if key in bare else ""
            raise ParameterError(
                f"{where}.{key}: unknown key{hint} (known: {', '.join(sorted(keys))})"
            )
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{where}.{key} = {value!r}: must be a number")
        name, factor = keys[key]
        inv = round(1.0 / factor)
        # a decimal prefix (mm, mN) divides: 110 mm²/s / 1e6 is the float 1.1e-4, × 1e-6 is not
        exact = factor < 1 and inv * factor == 1
        out[name] = float(value) / inv if exact else float(value) * factor
    return out


@contextmanager
def _file_key(
    table: Mapping[str, Any], keys: Mapping[str, tuple[str, float]], where: str
) -> Iterator[None]:
    """A ParameterError on an SI field (``lever = 1e-12 m: …``) is told with the file's key
    and value first (``transmission.lever_mm = 1e-09: lever = 1e-12 m: …``)."""
    try:
        yield
    except ParameterError as exc:
        name = str(exc).split(" ", 1)[0]
        key = next((k for k, (n, _) in keys.items() if n == name and k in table), None)
        if key is None:
            raise
        raise ParameterError(f"{where}.{key} = {table[key]!r}: {exc}") from None


def _short(v: Any) -> str:
    """A value as the file gave it, cut to one short line."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def design_from_mapping(data: Mapping[str, Any], where: str = "design") -> ClutchDesign:
    """Build a design from a parsed design file (see the module docstring)."""
    known = {"clutch", "operating", "transmission", "support", "amplifier", "laminations",
             "uncertainty", "measured", "process", "materials", "render", "duty",
             "name"}  # fmt: skip
    for key in data:
        if key not in known and not isinstance(data[key], dict):
            raise ParameterError(f"{where}: {key}: not in a table; dimensions go under [clutch]")
        if key not in known:
            raise ParameterError(
                f"{where}: {key}: unknown table (known: {', '.join(sorted(known))})"
            )
    if "clutch" not in data or not isinstance(data["clutch"], dict):
        raise ParameterError(f"{where}: missing the [clutch] table of dimensions")
    for name in known - {"name"}:
        if name in data and not isinstance(data[name], dict):
            raise ParameterError(f"{where}: {name} = {_short(data[name])}: must be a table "
                                 f"([{name}] with keys under it)")  # fmt: skip
    if "name" in data and not isinstance(data["name"], str):
        raise ParameterError(f"{where}: name = {_short(data['name'])}: must be a string")
    table = dict(data["clutch"])
    base_name = table.pop("base", None)
    if base_name is not None and not isinstance(base_name, str):
        raise ParameterError(f"{where}: clutch.base = {_short(base_name)}: must be a preset "
                             "name (a string)")  # fmt: skip
    base = preset(base_name) if base_name is not None else None
    clutch = DrumClutch.from_mm(table, base=base, where=f"{where}: clutch")
    op_table = dict(data["operating"]) if "operating" in data else {}
    amp_table = data["amplifier"] if "amplifier" in data else {}
    lam_table = data["laminations"] if "laminations" in data else {}
    tr_table = data["transmission"] if "transmission" in data else {}
    sup_table = dict(data["support"]) if "support" in data else {}
    proc_table = data["process"] if "process" in data else {}
    mat_table = data["materials"] if "materials" in data else {}
    for name, t in (("operating", op_table), ("transmission", tr_table), ("support", sup_table),
                    ("amplifier", amp_table), ("laminations", lam_table),
                    ("process", proc_table), ("materials", mat_table)):  # fmt: skip
        if not isinstance(t, dict):
            raise ParameterError(f"{where}: [{name}] must be a table")
    source = op_table.pop("delay_source", "fixed")
    if not isinstance(source, str) or source not in DELAY_SOURCES:
        raise ParameterError(f"{where}: operating.delay_source = {source!r}: must be one of "
                             f"{', '.join(repr(x) for x in DELAY_SOURCES)}")  # fmt: skip
    with _file_key(op_table, _OPERATING_KEYS, f"{where}: operating"):
        operating = Operating(**_read_table(op_table, _OPERATING_KEYS, f"{where}: operating"),
                              delay_source=source)  # fmt: skip
    with _file_key(amp_table, _AMPLIFIER_KEYS, f"{where}: amplifier"):
        amplifier = Amplifier(**_read_table(amp_table, _AMPLIFIER_KEYS, f"{where}: amplifier"))
    with _file_key(lam_table, _LAMINATION_KEYS, f"{where}: laminations"):
        laminations = Laminations(
            **_read_table(lam_table, _LAMINATION_KEYS, f"{where}: laminations")
        )
    with _file_key(tr_table, _TRANSMISSION_KEYS, f"{where}: transmission"):
        transmission = replace(
            MR_170, **_read_table(tr_table, _TRANSMISSION_KEYS, f"{where}: transmission")
        )
    bearing = sup_table.pop("bearing", Support.bearing)
    if not isinstance(bearing, str):
        raise ParameterError(f"{where}: support.bearing = {bearing!r}: must be a string")
    sup = _read_table(sup_table, _SUPPORT_KEYS, f"{where}: support")
    if "bearings" in sup:
        if not math.isfinite(sup["bearings"]) or sup["bearings"] != int(sup["bearings"]):
            raise ParameterError(f"{where}: support.bearings = {sup['bearings']:g}: whole number")
        sup["bearings"] = int(sup["bearings"])
    with _file_key(sup_table, _SUPPORT_KEYS, f"{where}: support"):
        support = Support(bearing=bearing, **sup)  # type: ignore[arg-type]
    with _file_key(proc_table, PROCESS_KEYS, f"{where}: process"):
        process = Process(**_read_table(proc_table, PROCESS_KEYS, f"{where}: process"))
    materials = _materials(dict(mat_table), where)
    name = data["name"] if "name" in data else Path(where).stem
    design = ClutchDesign(clutch, operating, transmission, str(name), support, amplifier,
                          laminations, process=process, materials=materials)  # fmt: skip
    if "uncertainty" in data:
        unc = uncertainty_from_mapping(data["uncertainty"], f"{where}: uncertainty",
                                       base=default_uncertainty(design))  # fmt: skip
        design = replace(design, uncertainty=unc)
    if "render" in data:
        design = replace(design, render=render_from_mapping(data["render"], f"{where}: render"))
    if "duty" in data:
        duty_table = data["duty"]
        with _file_key(duty_table, DUTY_KEYS, f"{where}: duty"):
            duty = Duty(**_read_table(duty_table, DUTY_KEYS, f"{where}: duty"))
        design = replace(design, duty=duty)
    if "measured" in data:
        meas = measured_from_mapping(data["measured"], f"{where}: measured", source=str(where))
        design = replace(design, measured=meas)
    check_consistent(design, where)  # ranges against the gap and their nominal values
    return design


def _materials(table: dict[str, Any], where: str) -> MaterialChoice:
    """The ``[materials]`` table: registry names per part; ``fluid_file`` (a path relative
    to the design file) reads a user's fluid (``magnetics.materials.load_fluid``)."""
    if "fluid_file" in table:
        file = table.pop("fluid_file")
        if not isinstance(file, str):
            raise ParameterError(f"{where}: materials.fluid_file = {file!r}: must be a path")
        if "fluid" in table:
            raise ParameterError(f"{where}: materials: give fluid or fluid_file, not both")
        path = Path(file) if Path(file).is_absolute() else Path(where).parent / file
        table["fluid"] = load_fluid(path)
    return MaterialChoice.from_mapping(table, f"{where}: materials")


def load_design(path: str | Path) -> ClutchDesign:
    """Read a design file; every error names the key and the file."""
    p = Path(path)
    data = read_toml(p, "design file")
    return design_from_mapping(data, str(p))


def design_to_toml(design: ClutchDesign) -> str:
    """A design file that ``load_design`` reads back to the same design: every number is
    written as the decimal that converts back to the same float where one exists (else
    the nearest, within 1 ulp), ``inf`` as TOML's inf, the name with its control
    characters escaped."""
    op, tr = design.operating, design.transmission
    lines = [f"name = {_toml(design.name)}", "", "[clutch]"]
    mm = design.clutch.to_mm()
    for key, v in mm.items():
        if isinstance(v, int):
            lines.append(f"{key} = {v}")
        else:  # the file's mm back to metres is value / 1000 (DrumClutch.from_mm)
            si = getattr(design.clutch, key[:-3])
            lines.append(f"{key} = {_toml(_exact(si, si * 1000.0, lambda m: m / 1000.0))}")
    lines += ["", "[operating]"]
    for key, (name, factor) in _OPERATING_KEYS.items():
        raw = getattr(op, name)
        if raw is not None:  # None: the default (computed) limit, written as no key
            lines.append(f"{key} = {_toml(_si(raw, factor))}")
    lines.append(f"delay_source = {_toml(op.delay_source)}")
    for table, keys, obj in (("amplifier", _AMPLIFIER_KEYS, design.amplifier),
                             ("laminations", _LAMINATION_KEYS, design.laminations)):  # fmt: skip
        lines += ["", f"[{table}]"]
        lines += [f"{k} = {_toml(_si(getattr(obj, n), f))}" for k, (n, f) in keys.items()]
    lines += ["", "[transmission]"]
    lines += [f"{k} = {_toml(_si(getattr(tr, n), f))}" for k, (n, f) in _TRANSMISSION_KEYS.items()]
    lines += ["", "[materials]"]
    lines += [f"{k} = {_toml(v)}" for k, v in design.materials.as_dict().items()]
    sup = design.support
    lines += ["", "[support]", f"bearing = {_toml(sup.bearing)}"]
    lines += [f"{k} = {_toml(_si(getattr(sup, n), f))}" for k, (n, f) in _SUPPORT_KEYS.items()]
    if design.uncertainty is not None:
        lines += ["", "[uncertainty]", *uncertainty_to_toml(design.uncertainty)]
    if design.measured is not None:
        lines += ["", "[measured]", *measured_to_toml(design.measured)]

    lines += ["", "[process]"]
    lines += [
        f"{k} = {_toml(_si(getattr(design.process, n), f))}" for k, (n, f) in PROCESS_KEYS.items()
    ]
    lines += ["", "[render]", *render_to_toml(design.render)]
    lines += ["", "[duty]"]
    lines += [f"{k} = {_toml(_si(getattr(design.duty, n), f))}" for k, (n, f) in DUTY_KEYS.items()]
    return "\n".join(lines) + "\n"


def _si(raw: float, factor: float) -> float:
    """The file's value of an SI field read back as value × factor (``_read_table``)."""
    if isinstance(raw, int) and not isinstance(raw, bool):
        return raw
    inv = round(1.0 / factor)
    if factor < 1 and inv * factor == 1:  # as _read_table reads it
        return _exact(float(raw), float(raw) * inv, lambda m: m / inv)
    return _exact(float(raw), float(raw) / factor, lambda m: m * factor)


def _exact(si: float, guess: float, to_si: Any) -> float:
    """The float m nearest ``guess`` with to_si(m) == si (a few ulps around it), so the
    file reads back bit for bit; ``guess`` itself where none is that close."""
    if not math.isfinite(guess) or guess == 0.0:
        return guess
    for digits in range(1, 18):  # the shortest decimal that reads back exactly
        m = float(f"{guess:.{digits}g}")
        if float(to_si(m)) == si:
            return m
    lo = hi = guess
    for _ in range(8):
        for m in (lo, hi):
            if float(to_si(m)) == si:
                return m
        lo, hi = math.nextafter(lo, -math.inf), math.nextafter(hi, math.inf)
    return guess
