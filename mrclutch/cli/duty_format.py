"""The text of issue 41's figures in ``evaluate``: the hot holds, the fluid's life and the
b1 budget's new terms (``Evaluation.as_json()["duty"]``, mrclutch/duty.py)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mrclutch.uncertainty import RANGE_FROM


def _hold(label: str, h: Mapping[str, Any]) -> list[str]:
    flags = []
    if h["beyond_wire_limit"]:
        flags.append("coil past its wire limit")
    if h["beyond_fluid_range"]:
        flags.append("fluid past its range")
    if h.get("held") is False:
        flags.append(f"torque NOT held ({h['torque_asked_N_m']:.3g} N·m asked)")
    tail = f"  [{'; '.join(flags)}]" if flags else ""
    return [
        f"  {label}: {h['current_A']:.3g} A, coil {h['coil_temperature_C']:.0f} °C, fluid "
        f"{h['fluid_temperature_C']:.0f} °C (τy ×{h['tau_y_factor']:.3f}, η "
        f"{h['viscosity_Pa_s']:.3g} Pa·s){tail}",
        f"    torque {h['torque_N_m']:.4g} N·m, b1 {h['b1_N_s_per_m']:.3g} N·s/m, "
        f"{'passive' if h['passive'] else 'not passive'} at K (largest passive K "
        f"{h['max_passive_K_N_per_m']:.4g} N/m)",
    ]


def duty_lines(d: Mapping[str, Any]) -> list[str]:
    """The lines ``evaluate`` prints for issue 41 (temperature, fluid life, b1 terms)."""
    a = d["asked"]
    coef = d["tau_y_coefficient_per_K"]
    coef_text = "not modelled" if coef is None else f"{coef * 100:.3g} %/K at 20 °C"
    lines = ["", f"hot (thermal network fed back; τy(T) {coef_text}, unverified)"]
    lines += _hold(f"after {a['peak_time_s']:g} s at the current limit", d["peak"])
    if d["duty"] is not None:
        lines += _hold(f"after {a['time_s']:g} s holding {a['torque_N_m']:g} N·m", d["duty"])
    f = d["fluid"]
    life = f["life_h"]
    lde = f["lifetime_energy_J_per_m3"]
    life_text = "unknown (no LDE for this fluid)" if lde is None else (
        f"{life:.4g} h at {f['on_torque_N_m']:.3g} N·m for {f['on_fraction']:.0%} of the "
        f"time (off otherwise), {f['life_off_h']:.4g} h off-state only; LDE "
        f"{lde * 1e-12:.3g} MJ/mL, unverified")  # fmt: skip
    lines.append(f"fluid: {f['volume_mL']:.3g} mL; life {life_text}")
    hc = d["hot_corner"]
    lo, hi = hc["range_C"]
    lines.append(f"[uncertainty] fluid temperature range: {lo:.3g}–{hi:.3g} °C, "
                 f"{RANGE_FROM[hc['range_from']]}")  # fmt: skip
    if hc["covered"] is False:
        hi = hc["range_C"][1]
        lines.append(f"note: the duty warms the fluid to {hc['duty_fluid_temperature_C']:.0f} °C, "
                     f"past the [uncertainty] range's {hi:g} °C: widen fluid_temperature_C to "
                     'cover it (or declare it "duty")')  # fmt: skip
    b = d["b1_budget"]
    parts = ", ".join(f"{t['name']} {t['value']:.3g} ({t['share_of_table2']:.0%})"
                      for t in b["terms"])  # fmt: skip
    lines.append(f"b1 against Table 2's {b['paper_table2']:.3g} N·s/m: {parts}; "
                 f"unexplained {b['unexplained']:.3g} N·s/m")  # fmt: skip
    return lines


def duty_html(d: Mapping[str, Any]) -> str:
    """The report's section for issue 41: ``duty_lines`` as a list (HTML-escaped)."""
    from html import escape  # the report's alone: evaluate prints duty_lines as text

    lines = [s.strip() for s in duty_lines(d) if s.strip()]
    items = "".join(f"<li>{escape(s)}</li>" for s in lines[1:])
    return (f"<h2>After a duty, and the fluid's life</h2><p class=small>{escape(lines[0])}; "
            'docs/hot.md</p><ul>' + items + "</ul>")  # fmt: skip
