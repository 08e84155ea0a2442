"""The design file's reference, generated from the code's own key tables and checks:
``python -m mrclutch.design_schema`` writes docs/design-file.md, and
tests/mrclutch/test_design_schema.py fails when the file differs from what this prints.

Every section and key a design file accepts (``mrclutch.design.design_from_mapping``), with
its unit (from the key's name), its default (the field's default, in the file's unit) and
its allowed range — the message of the field's own validator, probed with values far out
of range, so the range quoted is the one the code enforces — and what reads it.
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from geometry.materials import SLOTS, MaterialChoice
from geometry.params import INT_RANGES, LENGTH_RANGES, DrumClutch, preset
from geometry.validation import ParameterError
from magnetics.amplifier import Amplifier
from magnetics.drag import Support
from magnetics.laminations import Laminations
from mrclutch import design as design_mod
from mrclutch.haptics.actuator import MR_170
from mrclutch.process import PROCESS_KEYS, Process
from mrclutch.render import RENDER_KEYS
from mrclutch.uncertainty import (
    _MEASURED_KEYS,
    _UNCERTAINTY_KEYS,
    Measured,
    default_uncertainty,
    uncertainty_from_mapping,
)

#: A key's unit, from the end of its name (longest suffix first).
UNITS: tuple[tuple[str, str], ...] = (
    ("_A_per_mm2", "A/mm²"), ("_mm2_per_s", "mm²/s"), ("_N_s_per_m", "N·s/m"),
    ("_N_per_m", "N/m"), ("_mN_m", "mN·m"), ("_N_m", "N·m"), ("_rpm", "rpm"), ("_ms", "ms"),
    ("_mm", "mm"), ("_pct", "%"), ("_Hz", "Hz"), ("_A", "A"), ("_V", "V"), ("_C", "°C"),
    ("_N", "N"), ("_g", "g"), ("_s", "s"),
)  # fmt: skip


def unit_of(key: str) -> str:
    """The unit a key's name carries ("—" for a number without one or a name)."""
    return next((u for suffix, u in UNITS if key.endswith(suffix)), "—")


def _fmt(v: Any) -> str:
    if v is None:
        return "computed"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def probe_range(make: Callable[[float], Any]) -> str:
    """The allowed range of a number, as the validator states it: ``make(v)`` builds the
    object with the field at v; the first refusal of a far-out value that names a range
    is quoted ("must be in (0, 1e+04] A" → "(0, 1e+04] A")."""
    said = []
    for v in (-1e300, 1e300, 0.0):
        try:
            make(v)
        except ParameterError as exc:
            text = str(exc).split(": must be ", 1)[-1] if ": must be " in str(exc) else str(exc)
            said.append(text.removeprefix("in ").strip())
        except (TypeError, ValueError, OverflowError):
            continue
    inside = [s for s in said if s.startswith(("[", "("))]
    if inside:
        return inside[0]
    return "; ".join(dict.fromkeys(said)) or "any number"


_RANGE = re.compile(r"^([\[(])\s*([-+0-9.eE]+|-?inf),\s*([-+0-9.eE]+|-?inf)([\])])\s*(.*)$")


def in_file_unit(text: str, key: str, factor: float) -> str:
    """A validator's range, stated in SI ("[0, 0.001] m"), in the file key's unit
    ("[0, 1] mm"): each bound divided by the key's factor to SI."""
    m = _RANGE.match(text)
    if m is None or factor == 1.0:
        return text
    lo, hi = (float(m.group(i)) / factor for i in (2, 3))
    unit = unit_of(key)
    return f"{m.group(1)}{lo:.6g}, {hi:.6g}{m.group(4)}" + (f" {unit}" if unit != "—" else "")


def _rows(keys: Mapping[str, tuple[Any, ...]], default: Any,
          make: Callable[[str, float], Any]) -> list[tuple[str, str, str, str]]:  # fmt: skip
    """(key, unit, default, range) of a table of ``key → (field, factor, …)``."""
    out = []
    for key, (name, factor, *_) in keys.items():
        raw = getattr(default, name)
        shown = None if raw is None else (raw / factor if isinstance(raw, float) else raw)
        rng = probe_range(lambda v, n=name, f=factor: make(n, v * f))
        out.append((key, unit_of(key), _fmt(shown), in_file_unit(rng, key, factor)))
    return out


def _replace(obj: Any) -> Callable[[str, float], Any]:
    return lambda name, v: dataclasses.replace(obj, **{name: v})


def sections() -> list[tuple[str, str, list[tuple[str, str, str, str]]]]:
    """(section, what reads it, rows of (key, unit, default, range)) for every table."""
    paper = preset("paper")
    clutch_rows = [("base", "—", "none", "a preset name: " + ", ".join(design_mod.DESIGNS))]
    ints = {n: (lo, hi) for n, lo, hi in INT_RANGES}
    lengths = {n: (lo, hi, lo_open) for n, lo, hi, lo_open in LENGTH_RANGES}
    for f in dataclasses.fields(DrumClutch):
        v = getattr(paper, f.name)
        if f.name in ints:
            lo, hi = ints[f.name]
            clutch_rows.append((f.name, "—", f"{v} (paper)", f"integer in [{lo}, {hi}]"))
        else:
            rng = "checked with the others (collisions)"
            if f.name in lengths:
                lo, hi, lo_open = lengths[f.name]
                rng = f"{'(' if lo_open else '['}{lo * 1e3:.6g}, {hi * 1e3:.6g}] mm"
            clutch_rows.append((f"{f.name}_mm", "mm", f"{v * 1e3:.6g} (paper)", rng))
    op = design_mod.Operating()
    op_rows = _rows(design_mod._OPERATING_KEYS, op, _replace(op))
    op_rows.append(("delay_source", "—", op.delay_source,
                    "one of " + ", ".join(design_mod.DELAY_SOURCES)))  # fmt: skip
    sup = Support()
    sup_rows = [("bearing", "—", sup.bearing, "an SKF series (magnetics.drag) or none")]
    sup_rows += _rows(design_mod._SUPPORT_KEYS, sup, _replace(sup))
    out = [
        ("clutch", "geometry.params.DrumClutch: every model reads the section", clutch_rows),
        ("operating", "mrclutch.design.Operating: current limit, speed, delay, temperatures",
         op_rows),
        ("support", "magnetics.drag.Support: bearing and seal drag", sup_rows),
        ("amplifier", "magnetics.amplifier.Amplifier: supply current, torque response",
         _rows(design_mod._AMPLIFIER_KEYS, Amplifier(), _replace(Amplifier()))),
        ("laminations", "magnetics.laminations.Laminations: eddy currents of the torque response",
         _rows(design_mod._LAMINATION_KEYS, Laminations(), _replace(Laminations()))),
        ("transmission", "mrclutch.haptics.actuator.Transmission: Eq. 3-4 to the hand",
         _rows(design_mod._TRANSMISSION_KEYS, MR_170, _replace(MR_170))),
        ("process", "mrclutch.process.Process: the smallest gap and wall (optimize)",
         _rows(PROCESS_KEYS, Process(), _replace(Process()))),
    ]  # fmt: skip
    duty_keys = getattr(design_mod, "DUTY_KEYS", None)
    duty_cls = getattr(design_mod, "Duty", None)
    if duty_keys is not None and duty_cls is not None:
        out.append(("duty", "mrclutch.duty.Duty: hot torque, duty hold and fluid life",
                    _rows(duty_keys, duty_cls(), _replace(duty_cls()))))  # fmt: skip
    out += _uncertainty_sections()
    mats = MaterialChoice()
    mat_rows = [(slot, "—", str(getattr(mats, slot)), f"a {kind} of the registry "
                 "(docs/materials.md)") for slot, kind in SLOTS.items()]  # fmt: skip
    mat_rows.append(("fluid_file", "—", "none", "a fluid file's path, relative to the design "
                     "file (instead of fluid)"))  # fmt: skip
    out.append(("materials", "geometry.materials.MaterialChoice: each part's material",
                mat_rows))  # fmt: skip
    out.append(
        (
            "render",
            "mrclutch.render.Render, applied by mrclutch.verdict: every command "
            "that judges a design",
            [(k, u, d, m) for k, (m, u, d) in RENDER_KEYS.items()],
        )
    )
    return out


def _uncertainty_sections() -> list[tuple[str, str, list[tuple[str, str, str, str]]]]:

    base = default_uncertainty(design_mod.design_preset("paper"))
    rows = []
    for key, (name, factor, kind) in _UNCERTAINTY_KEYS.items():
        raw = getattr(base, name)
        if raw is None:  # derived from the design (the typed and the geometry's delay)
            shown = None
        else:
            shown = [x / factor for x in raw] if kind == "range" else raw / factor

        def make(v: float, key: str = key, kind: str = kind) -> Any:
            value = [v, v] if kind == "range" else v
            return uncertainty_from_mapping({key: value}, "uncertainty")

        what = "[low, high]" if kind == "range" else "a spread (±)"
        if key == "fluid_temperature_C":  # or derived from the duty (mrclutch.hot_range)
            what = '[low, high] or "duty" (to the duty hold\'s end, docs/hot.md)'
        rows.append((key, unit_of(key), "from the design" if shown is None else
                     _fmt(shown) + " (paper)",
                     f"{what}: {in_file_unit(probe_range(make), key, factor)}"))  # fmt: skip
    meas = [(k, unit_of(k), "none", "> 0, a bench's measurement") for k in _MEASURED_KEYS]
    meas += [("torque", "—", "none", "[[current_A, torque_N_m], …]: torques measured at "
              "currents"), ("use_in_model", "—", "false", "true: the model uses the "
              "measured m1, b1 and step delay"), ("source", "—", "none", "text")]  # fmt: skip
    assert Measured  # the class the `[measured]` table builds
    return [("uncertainty", "mrclutch.uncertainty.Uncertainty: the ranges robust verdicts "
             "are taken over (docs/verdicts.md)", rows),
            ("measured", "mrclutch.uncertainty.Measured: a built device's bench "
             "(evaluate's model against the bench)", meas)]  # fmt: skip


def reference_markdown() -> str:
    """docs/design-file.md's text."""
    lines = [
        "# The design file, key by key",
        "",
        "<!-- generated by `python -m mrclutch.design_schema`; "
        "tests/mrclutch/test_design_schema.py checks it -->",
        "",
        "A design file is TOML: a top-level `name` and the tables below; only `[clutch]` is "
        "required. Lengths are in mm and every other unit is in the key's name; a key not "
        "listed here is refused with the known keys named. Defaults are the code's (the "
        '`[clutch]` defaults are the `paper` preset\'s, which `base = "paper"` starts '
        "from); ranges are the ones its validators enforce (a value outside is refused, "
        "naming the key, the value and the range).",
        "",
    ]
    for name, reader, rows in sections():
        lines += [f"## `[{name}]`", "", f"Read by {reader}.", "",
                  "| key | unit | default | allowed |", "|---|---|---|---|"]  # fmt: skip
        lines += [f"| `{k}` | {u} | {d} | {r} |" for k, u, d, r in rows]
        lines.append("")
    return "\n".join(lines)


def main() -> int:
    path = Path(__file__).resolve().parents[1] / "docs" / "design-file.md"
    if "--check" in sys.argv:
        return 0 if path.read_text() == reference_markdown() else 1
    path.write_text(reference_markdown())
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
