"""What we do not know, declared: the ranges of the least certain inputs (``[uncertainty]``)
and what a bench measured (``[measured]``), read from a design file.

The ranges travel with the design (DESIGN.md, "Uncertainty with the design"); the verdicts
over them are computed in :mod:`mrclutch.robust` from the haptic kernels. SI inside; the
file's keys carry their unit. Defaults and their sources (docs/verdicts.md)::

    [uncertainty]
    viscosity_spread_pct = 18          # ± on the carrier's η: the datasheet's spread at 40 °C
    fluid_temperature_C = [20, 40]     # default: the operating value to 20 K above it;
                                       # "duty": to the thermal model's end of the duty
    gap_tolerance_mm = 0.02            # ± on every gap: ISO 286 IT7 at 18–30 mm (21 µm)
    runout_mm = 0.02                   # drum eccentricity: the films' mean 1/gap rises
    drum_thickness_tolerance_mm = 0.02 # ± on the output drums' wall, IT7 as the gap
    delay_ms = [1.0, 2.15]             # default: from the typed delay to the geometry's
    bench_damping_N_s_per_m = [0, 0.73]  # b1 the model does not explain (default: 0 to
                                       # Table 2's b1 less the model's, paper clutch)
    yield_stress_spread_pct = 10       # ± on τy (fluid lot)
    bh_spread_pct = 5                  # ± on the torque from the steel's B–H lot

    [measured]                         # a bench's figures, model against measurement
    torque = [{current_A = 7.0, torque_N_m = 0.4}]
    step_delay_ms = 1.0
    m1_g = 1.5
    b1_N_s_per_m = 1.0
    off_state_torque_mN_m = 4
    use_in_model = false               # true: the haptic model uses m1, b1 and the delay
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from geometry.materials import MRF
from geometry.params import preset
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.drag import Support, drag_terms, totals
from magnetics.materials import FLUIDS
from mrclutch.haptics.actuator import MR_170, TABLE2_MR
from mrclutch.inputs import toml_value

#: Where each default comes from (docs/verdicts.md).
SOURCES: dict[str, str] = {
    "viscosity_spread": "±18 %: the datasheet's viscosity spread at 40 °C [lord-mrf132dg]",
    "fluid_temperature": "the operating temperature to 20 K above it (a clutch warmed by "
    "slip; our choice)",
    "gap_tolerance": "±0.02 mm: ISO 286 grade IT7 at 18–30 mm is 21 µm [iso286]",
    "runout": "0.02 mm drum eccentricity (IT7 as the gap; our choice)",
    "drum_thickness_tolerance": "±0.02 mm on the output drums' wall (IT7; our choice)",
    "delay": "from the typed delay to the torque response's equivalent delay "
    "(magnetics.dynamics, docs/dynamics.md)",
    "bench_damping": "0 to the b1 Table 2 identified on the paper's bench less the fast "
    "model's b1 of the paper clutch (lever, cables and what the model misses) [lebel]",
    "yield_stress_spread": "±10 %: lot-to-lot spread of the fluid's yield stress (our choice)",
    "bh_spread": "±5 %: lot-to-lot spread of the steel's saturation, read as torque (our choice)",
    "fluid_temperature_from": 'the fluid temperature range as typed (or the default), or "duty": '
    "to the fluid's temperature at the end of the duty hold (mrclutch.hot_range, docs/hot.md)",
}


def _check_range(name: str, lo: float, hi: float, unit: str, *, min_lo: float = 0.0) -> None:
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ParameterError(f"{name} = [{lo:g}, {hi:g}]{unit}: must be finite")
    if lo > hi:
        raise ParameterError(f"{name} = [{lo:g}, {hi:g}]{unit}: low > high")
    if lo < min_lo:
        raise ParameterError(f"{name} = [{lo:g}, {hi:g}]{unit}: must be >= {min_lo:g}")


def _check_spread(name: str, v: float, hi: float, unit: str = "") -> None:
    if not (math.isfinite(v) and 0.0 <= v < hi):
        raise ParameterError(f"{name} = {v:g}{unit}: must be in [0, {hi:g})")


@dataclass(frozen=True)
class Uncertainty:
    """Ranges of the least certain inputs (SI; relative spreads as fractions, ±).

    ``fluid_temperature`` [°C], ``delay`` [s] and ``bench_damping`` [N·s/m at the hand]
    are (low, high); ``fluid_temperature`` and ``delay`` None: the defaults of
    :func:`default_uncertainty` (the operating value to 20 K above it; the typed delay to
    the geometry's equivalent delay, one range per design). ``fluid_temperature_from``
    "duty": the range is the operating temperature to the fluid's at the end of the
    design's duty hold (``mrclutch.hot_range``; None here until resolved there)."""

    viscosity_spread: float = 0.18
    fluid_temperature: tuple[float, float] | None = None
    gap_tolerance: float = 0.02e-3
    runout: float = 0.02e-3
    drum_thickness_tolerance: float = 0.02e-3
    delay: tuple[float, float] | None = None
    bench_damping: tuple[float, float] = (0.0, 0.0)
    yield_stress_spread: float = 0.10
    bh_spread: float = 0.05
    fluid_temperature_from: str = "range"  # "range": as given (or default); "duty"

    def __post_init__(self) -> None:
        if self.fluid_temperature_from not in TEMPERATURE_FROM:
            raise ParameterError(f"fluid_temperature_from = {self.fluid_temperature_from!r}: "
                                 f"must be one of {', '.join(TEMPERATURE_FROM)}")  # fmt: skip
        _check_spread("viscosity_spread", self.viscosity_spread, 1.0)
        _check_spread("yield_stress_spread", self.yield_stress_spread, 1.0)
        _check_spread("bh_spread", self.bh_spread, 1.0)
        for name in ("gap_tolerance", "runout", "drum_thickness_tolerance"):
            _check_spread(name, getattr(self, name), 1e-2, " m")
        if self.fluid_temperature is not None:
            lo, hi = self.fluid_temperature
            _check_range("fluid_temperature", lo, hi, " °C", min_lo=-273.15)
        if self.delay is not None:
            _check_range("delay", *self.delay, " s")
            if self.delay[1] > 1.0:
                raise ParameterError(f"delay = {list(self.delay)} s: must be <= 1 s")
        _check_range("bench_damping", *self.bench_damping, " N·s/m")
        if self.bench_damping[1] > MEASURED_RANGES["b1"][1]:  # as a bench's b1
            raise ParameterError(f"bench_damping = {list(self.bench_damping)} N·s/m: must be "
                                 f"<= {MEASURED_RANGES['b1'][1]:g} N·s/m")  # fmt: skip

    @property
    def torque_factor(self) -> tuple[float, float]:
        """(low, high) multiplier of the torque: yield-stress and B–H lot spreads (torque
        rises with both; their extremes combine)."""
        return (
            (1 - self.yield_stress_spread) * (1 - self.bh_spread),
            (1 + self.yield_stress_spread) * (1 + self.bh_spread),
        )


#: Where the fluid temperature range comes from: typed (or the default), or the duty's end.
TEMPERATURE_FROM = ("range", "duty")
#: Most torque points a bench table may hold.
MAX_TORQUE_POINTS = 1000
#: What a bench value may be (SI): (low, high] and the unit. Our plausibility bounds, each
#: orders of magnitude around the paper's bench ([lebel]: 0.4 N·m at 7 A, m1 = 1.5 g,
#: b1 = 1 N·s/m, 1 ms), wide enough for any haptic clutch and narrow enough that every
#: model stays finite (a 1e300 N·m torque gave K = 8.6e302 N/m and NaN in the robust table).
MEASURED_RANGES: dict[str, tuple[float, float, str]] = {
    "current": (0.0, 1e4, " A"),  # as Operating.max_current
    "torque": (0.0, 1e3, " N·m"),
    "step_delay": (0.0, 1.0, " s"),  # as Operating.delay (MAX_DELAY)
    "m1": (1e-6, 100.0, " kg"),
    "b1": (1e-6, 1e4, " N·s/m"),  # as the transmission's b (1e4 N·s/m)
    "off_state_torque": (0.0, 1e3, " N·m"),
}


def _check_bench(name: str, v: float, lo: float, hi: float, unit: str) -> None:
    """``v`` finite in (lo, hi] (lo = 0) or [lo, hi] (lo > 0), else the error naming it."""
    inside = (v > lo if lo == 0 else v >= lo) and v <= hi
    if not (math.isfinite(v) and inside):
        lb = "(" if lo == 0 else "["
        raise ParameterError(f"{name} = {v:g}{unit}: must be in {lb}{lo:g}, {hi:g}]{unit}")


@dataclass(frozen=True)
class TorquePoint:
    current: float  # A
    torque: float  # N·m


@dataclass(frozen=True)
class Measured:
    """What a bench measured (SI): torque at currents, the delay of a torque step, the
    identified m1 [kg] and b1 [N·s/m] at the hand, the off-state torque [N·m]. None: not
    measured. ``use_in_model``: the haptic model takes m1, b1 and the delay from here."""

    torque: tuple[TorquePoint, ...] = ()
    step_delay: float | None = None
    m1: float | None = None
    b1: float | None = None
    off_state_torque: float | None = None
    use_in_model: bool = False
    source: str = ""

    def __post_init__(self) -> None:
        if len(self.torque) > MAX_TORQUE_POINTS:
            raise ParameterError(f"torque: {len(self.torque)} points: at most "
                                 f"{MAX_TORQUE_POINTS}")  # fmt: skip
        for i, pt in enumerate(self.torque):
            for name, v in (("current", pt.current), ("torque", pt.torque)):
                _check_bench(f"torque[{i}].{name}", v, *MEASURED_RANGES[name])
            # two torques at one current: which one the model uses would be first-come
            j = next((j for j, q in enumerate(self.torque[:i])
                      if math.isclose(q.current, pt.current, rel_tol=1e-9)), None)  # fmt: skip
            if j is not None:
                raise ParameterError(
                    f"torque[{i}].current = {pt.current:g} A: torque[{j}] is at the same "
                    f"current ({self.torque[j].torque:g} and {pt.torque:g} N·m); give one "
                    "torque per current (their mean, say)"
                )
        for name in ("step_delay", "m1", "b1", "off_state_torque"):
            v = getattr(self, name)
            if v is not None:
                _check_bench(name, v, *MEASURED_RANGES[name])

    @property
    def empty(self) -> bool:
        return not self.torque and all(
            getattr(self, n) is None for n in ("step_delay", "m1", "b1", "off_state_torque")
        )


# ---- design-file tables ------------------------------------------------------------------

# key -> (field, factor to SI, kind): "spread" a number, "range" [low, high]
_UNCERTAINTY_KEYS: dict[str, tuple[str, float, str]] = {
    "viscosity_spread_pct": ("viscosity_spread", 1e-2, "spread"),
    "fluid_temperature_C": ("fluid_temperature", 1.0, "range"),
    "gap_tolerance_mm": ("gap_tolerance", 1e-3, "spread"),
    "runout_mm": ("runout", 1e-3, "spread"),
    "drum_thickness_tolerance_mm": ("drum_thickness_tolerance", 1e-3, "spread"),
    "delay_ms": ("delay", 1e-3, "range"),
    "bench_damping_N_s_per_m": ("bench_damping", 1.0, "range"),
    "yield_stress_spread_pct": ("yield_stress_spread", 1e-2, "spread"),
    "bh_spread_pct": ("bh_spread", 1e-2, "spread"),
}
_MEASURED_KEYS: dict[str, tuple[str, float]] = {
    "step_delay_ms": ("step_delay", 1e-3),
    "m1_g": ("m1", 1e-3),
    "b1_N_s_per_m": ("b1", 1.0),
    "off_state_torque_mN_m": ("off_state_torque", 1e-3),
}


def _number(where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{where} = {value!r}: must be a number")
    return float(value)


def _unknown(where: str, key: str, known: Mapping[str, Any]) -> ParameterError:
    return ParameterError(f"{where}.{key}: unknown key (known: {', '.join(sorted(known))})")


def uncertainty_from_mapping(table: Mapping[str, Any], where: str = "uncertainty",
                             base: Uncertainty | None = None) -> Uncertainty:  # fmt: skip
    """An :class:`Uncertainty` from a design file's ``[uncertainty]`` table (keys above);
    keys not given keep ``base``'s (default: the defaults). Errors name the key."""
    if not isinstance(table, Mapping):
        raise ParameterError(f"{where}: must be a table")
    kw: dict[str, Any] = {}
    for key, value in table.items():
        if key not in _UNCERTAINTY_KEYS:
            raise _unknown(where, key, _UNCERTAINTY_KEYS)
        name, factor, kind = _UNCERTAINTY_KEYS[key]
        if key == "fluid_temperature_C" and value == "duty":  # resolved by hot_range
            kw.update(fluid_temperature=None, fluid_temperature_from="duty")
            continue
        if key == "fluid_temperature_C":
            kw["fluid_temperature_from"] = "range"
        if kind == "range":
            if not isinstance(value, list) or len(value) != 2:
                duty = ' or "duty"' if key == "fluid_temperature_C" else ""
                raise ParameterError(f"{where}.{key} = {value!r}: must be [low, high]{duty}")
            lo, hi = (_number(f"{where}.{key}", v) for v in value)
            if lo > hi:
                raise ParameterError(f"{where}.{key} = [{lo:g}, {hi:g}]: low > high")
            kw[name] = (lo * factor, hi * factor)
        else:
            v = _number(f"{where}.{key}", value)
            if v < 0:
                raise ParameterError(f"{where}.{key} = {v:g}: must be >= 0 (a ± spread)")
            kw[name] = v * factor
    try:
        return replace(base if base is not None else Uncertainty(), **kw)
    except ParameterError as exc:
        name = str(exc).split(" ", 1)[0]
        key = next((k for k, v in _UNCERTAINTY_KEYS.items() if v[0] == name and k in table), name)
        raise ParameterError(f"{where}.{key}: {exc}") from None


def measured_from_mapping(table: Mapping[str, Any], where: str = "measured",
                          source: str = "") -> Measured:  # fmt: skip
    """A :class:`Measured` from a design file's ``[measured]`` table (keys above)."""
    if not isinstance(table, Mapping):
        raise ParameterError(f"{where}: must be a table")
    kw: dict[str, Any] = {}
    for key, value in table.items():
        if key == "torque":
            if not isinstance(value, list):
                raise ParameterError(f"{where}.torque: must be a list of "
                                     "{{current_A = …, torque_N_m = …}}")  # fmt: skip
            pts = []
            for i, pt in enumerate(value):
                w = f"{where}.torque[{i}]"
                if not isinstance(pt, Mapping):
                    raise ParameterError(f"{w} = {pt!r}: must be {{current_A, torque_N_m}}")
                extra = set(pt) - {"current_A", "torque_N_m"}
                if extra:
                    raise ParameterError(f"{w}.{sorted(extra)[0]}: unknown key "
                                         "(known: current_A, torque_N_m)")  # fmt: skip
                if "current_A" not in pt:
                    raise ParameterError(f"{w}: no current_A (a torque needs its current)")
                if "torque_N_m" not in pt:
                    raise ParameterError(f"{w}: no torque_N_m")
                pts.append(TorquePoint(_number(f"{w}.current_A", pt["current_A"]),
                                       _number(f"{w}.torque_N_m", pt["torque_N_m"])))  # fmt: skip
            kw["torque"] = tuple(pts)
        elif key == "use_in_model":
            if not isinstance(value, bool):
                raise ParameterError(f"{where}.use_in_model = {value!r}: must be true or false")
            kw["use_in_model"] = value
        elif key == "source":
            if not isinstance(value, str):
                raise ParameterError(f"{where}.source = {value!r}: must be a string")
            kw["source"] = value
        elif key in _MEASURED_KEYS:
            name, factor = _MEASURED_KEYS[key]
            kw[name] = _number(f"{where}.{key}", value) * factor
        else:
            known = {**_MEASURED_KEYS, "torque": 0, "use_in_model": 0, "source": 0}
            raise _unknown(where, key, known)
    kw.setdefault("source", source)
    try:
        return Measured(**kw)
    except ParameterError as exc:
        name = str(exc).split(" ", 1)[0]  # the field, told with the file's key first
        key = next((k for k, v in _MEASURED_KEYS.items() if v[0] == name and k in table), None)
        if key is not None:
            raise ParameterError(f"{where}.{key} = {table[key]!r}: {exc}") from None
        raise ParameterError(f"{where}: {exc}") from None


def check_consistent(design: Any, where: str = "design") -> None:
    """A design file's ranges checked against the design and each other (ParameterError
    naming the keys, the values and the rule):

    * ``[uncertainty]`` and ``[process]``: runout plus tolerance must stay below the gap
      (the film's thinnest point g − (R + T), ``mrclutch.process``; beyond it the film
      closes and the drag's 1/h has no value), the drum-wall tolerance below the wall;
    * a declared range must contain its nominal value — the fluid temperature range the
      operating temperature (and lie in the fluid's own range), the delay range the typed
      delay (``delay_source = "fixed"``, no measured delay used) — or the robust verdict
      ("for every value of the ranges") would not contain the nominal verdict beside it.
    """
    gap = float(design.clutch.gap)
    wall = float(design.clutch.drum_thickness)
    proc = design.process
    if proc.runout + proc.tolerance >= gap:
        raise ParameterError(
            f"{where}: process.runout_mm + process.tolerance_mm = {proc.runout * 1e3:g} + "
            f"{proc.tolerance * 1e3:g} mm: must be less than the gap ({gap * 1e3:g} mm): the "
            "film's thinnest point g - (runout + tolerance) would close"
        )
    u = design.uncertainty
    if u is None:
        return
    w = f"{where}: uncertainty"
    if u.runout + u.gap_tolerance >= gap:
        raise ParameterError(
            f"{w}.runout_mm + gap_tolerance_mm = {u.runout * 1e3:g} + "
            f"{u.gap_tolerance * 1e3:g} mm: must be less than the gap ({gap * 1e3:g} mm): "
            "the thinnest film would close (every geometry corner beyond it is void)"
        )
    if u.drum_thickness_tolerance >= wall:
        raise ParameterError(
            f"{w}.drum_thickness_tolerance_mm = {u.drum_thickness_tolerance * 1e3:g}: must "
            f"be less than the drum wall ({wall * 1e3:g} mm)"
        )
    if u.fluid_temperature is not None:
        lo, hi = u.fluid_temperature
        t = float(design.operating.fluid_temperature)
        flo, fhi = FLUIDS[design.materials.fluid].temperature_range
        if not lo <= t <= hi:
            raise ParameterError(
                f"{w}.fluid_temperature_C = [{lo:g}, {hi:g}]: must contain the operating "
                f"temperature ({t:g} °C), where the nominal verdict is computed; widen it "
                f"to [{min(lo, t):g}, {max(hi, t):g}]"
            )
        if lo < flo or hi > fhi:
            raise ParameterError(
                f"{w}.fluid_temperature_C = [{lo:g}, {hi:g}]: must lie in the fluid's range "
                f"[{flo:g}, {fhi:g}] °C ({design.materials.fluid})"
            )
    meas = design.measured
    measured_delay = meas is not None and meas.use_in_model and meas.step_delay is not None
    if u.delay is not None and design.operating.delay_source == "fixed" and not measured_delay:
        lo, hi = u.delay
        d = float(design.operating.delay)
        if not lo <= d <= hi:
            raise ParameterError(
                f"{w}.delay_ms = [{lo * 1e3:g}, {hi * 1e3:g}]: must contain the typed delay "
                f"({d * 1e3:g} ms), where the nominal verdict is computed; widen it to "
                f"[{min(lo, d) * 1e3:g}, {max(hi, d) * 1e3:g}]"
            )


#: °C the default fluid temperature range reaches above the operating value.
WARMING = 20.0


@functools.cache
def paper_unexplained_b1() -> float:
    """N·s/m at the hand: Table 2's identified b1 of the paper's MR pair less the fast
    model's drag damping of the paper clutch at the paper's operating point (Eq. 3 through
    the MR bench's transmission): the default top of the bench-damping range."""
    rg = build_section(preset("paper")).table
    damping = float(np.ravel(totals(drag_terms(rg, 530 * 2 * math.pi / 60, 20.0, Support()))[1])[0])
    b1 = 2.0 * damping * MR_170.reduction**2  # both clutches of the pair, Eq. 3
    return max(float(TABLE2_MR.b1) - b1, 0.0)


def default_uncertainty(design: Any = None) -> Uncertainty:
    """The documented defaults (``SOURCES``) for ``design`` (a ClutchDesign; None: the
    default one): the fluid temperature from its operating value to ``WARMING`` above it
    (capped at the fluid's limit), the bench damping from 0 to
    :func:`paper_unexplained_b1`, the delay from the typed value to the geometry's (None:
    resolved per design)."""
    t = 20.0 if design is None else float(design.operating.fluid_temperature)
    fluid = MRF if design is None else design.materials.fluid
    t_hi = min(t + WARMING, FLUIDS[fluid].temperature_range[1])
    return Uncertainty(fluid_temperature=(t, t_hi), bench_damping=(0.0, paper_unexplained_b1()))


#: What ``range_from`` says of each source of the fluid temperature range.
RANGE_FROM: dict[str, str] = {
    "default": "the operating temperature to 20 K above it (the default)",
    "typed": "typed in [uncertainty]",
    "duty": "the operating temperature to the fluid's at the end of the [duty] hold (of the "
    "current limit for peak_time_s without a duty torque; thermal model)",
}


def range_from(design: Any) -> str:
    """Which fluid temperature range ``design``'s verdicts take: "duty", "typed" or
    "default" (``RANGE_FROM``; a declared range equal to the default's reads "default")."""
    unc = design.uncertainty
    if unc is not None and unc.fluid_temperature_from == "duty":
        return "duty"
    if unc is None or unc.fluid_temperature == default_uncertainty(design).fluid_temperature:
        return "default"
    return "typed"


def no_uncertainty(design: Any = None) -> Uncertainty:
    """No spread at all: every range shrunk to the nominal value (``--no-uncertainty``)."""
    t = 20.0 if design is None else float(design.operating.fluid_temperature)
    d = 1e-3 if design is None else float(design.operating.delay)
    return Uncertainty(0.0, (t, t), 0.0, 0.0, 0.0, (d, d), (0.0, 0.0), 0.0, 0.0)


#: The paper's own bench [lebel] (examples/paper_bench.toml holds the same): Fig. 2b's
#: blocked torque ~0.4 N·m at 7 A (530 rpm), Table 2's identified m1 = 1.5 g and
#: b1 = 1.0 N·s/m (170 mm lever, "manually adjusted … to a best visual fit"), and §IV-B's
#: 1 ms pure delay "corroborating experiments". No off-state torque is published.
PAPER_BENCH = Measured(
    torque=(TorquePoint(7.0, 0.4),),
    step_delay=1e-3,
    m1=1.5e-3,
    b1=1.0,
    source="the paper's bench: Fig. 2b, Table 2, §IV-B [lebel]",
)


def _fmt(v: float) -> str:
    return repr(float(v))


def uncertainty_to_toml(u: Uncertainty) -> list[str]:
    """The ``[uncertainty]`` lines that ``uncertainty_from_mapping`` reads back to ``u``."""
    lines = []
    for key, (name, factor, kind) in _UNCERTAINTY_KEYS.items():
        v = getattr(u, name)
        if name == "fluid_temperature" and u.fluid_temperature_from == "duty":
            lines.append(f'{key} = "duty"')
            continue
        if v is None:
            continue
        if kind == "range":
            lines.append(f"{key} = [{_fmt(v[0] / factor)}, {_fmt(v[1] / factor)}]")
        else:
            lines.append(f"{key} = {_fmt(v / factor)}")
    return lines


def measured_to_toml(m: Measured) -> list[str]:
    """The ``[measured]`` lines that ``measured_from_mapping`` reads back to ``m``."""
    lines = []
    if m.torque:
        pts = ", ".join(f"{{current_A = {_fmt(p.current)}, torque_N_m = {_fmt(p.torque)}}}"
                        for p in m.torque)  # fmt: skip
        lines.append(f"torque = [{pts}]")
    for key, (name, factor) in _MEASURED_KEYS.items():
        v = getattr(m, name)
        if v is not None:
            lines.append(f"{key} = {_fmt(v / factor)}")
    lines.append(f"use_in_model = {toml_value(m.use_in_model)}")
    if m.source:
        lines.append(f"source = {toml_value(m.source)}")
    return lines
