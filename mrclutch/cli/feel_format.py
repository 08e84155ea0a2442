"""The text and HTML of issue 41's feel figures in ``evaluate`` and the report: the
steel's remanence (residual torque, loop width, the demagnetising pulse) and the runout
ripple (``Evaluation.as_json()["feel"]``, mrclutch/feel.py; docs/hysteresis.md)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


def feel_lines(f: Mapping[str, Any]) -> list[str]:
    """The lines ``evaluate`` prints (mN·m and mN, as a person reads them)."""
    if not f:
        return []
    h, r = f["hysteresis"], f["ripple"]
    verdict = "negligible" if h["negligible"] else "NOT negligible"
    return [
        "",
        "what the hand feels of the steel's memory and the runout (docs/hysteresis.md; "
        "coercivities unverified)",
        f"  residual torque at 0 A after {h['peak_current_A']:.3g} A: "
        f"{h['residual_torque_N_m'] * 1e3:.3g} mN·m ({h['residual_force_N'] * 1e3:.3g} mN at "
        f"the hand); after the demagnetising pulse "
        f"{h['residual_torque_after_pulse_N_m'] * 1e3:.3g} mN·m",
        f"  torque–current loop: widest gap {h['hysteresis_width_pct']:.3g} % of the full "
        f"torque, {verdict} against the hand's {h['force_jnd_pct']:g} % force "
        "discrimination threshold",
        f"  dynamic range with the residual as floor {h['dynamic_range_with_residual_dB']:.4g} "
        f"dB; backdrive force with it {h['backdrive_force_with_residual_N'] * 1e3:.3g} mN",
        f"  runout ripple ({r['runout_m'] * 1e3:.3g} mm): {r['ripple_torque_N_m'] * 1e3:.3g} "
        f"mN·m, {r['ripple_force_N'] * 1e3:.3g} mN at the hand, at "
        f"{r['ripple_frequency_hz']:.3g} Hz ({r['ripple_pct']:.3g} % of the full torque)",
    ]


def feel_html(f: Mapping[str, Any]) -> str:
    """The report's section of the same lines."""
    import html  # the report's alone: evaluate prints feel_lines as text

    lines = feel_lines(f)
    if not lines:
        return ""
    items = "".join(f"<li>{html.escape(s.strip())}</li>" for s in lines[2:])
    return f"<h2>Remanence and runout ripple</h2><p class=small>{html.escape(lines[1])}</p>" \
           f"<ul>{items}</ul>"  # fmt: skip
