"""The haptic metrics of one side as the three text lines ``haptic`` and ``compare`` print
(m1, m2, b1, k, b, delay; K, bandwidth, resonance, rendering area; passivity and stability),
for the catalogue's answer and a design's alike."""

from __future__ import annotations

import math
from typing import Any

from mrclutch.outputs import format_kmax


def print_metrics(m: dict[str, Any], k_source: str, source: str | None = None,
                   rule: str | None = None, own_kmax: float | None = None) -> None:  # fmt: skip
    """The metrics of one side; ``k_source``: where K comes from ("typed", or the source of
    the K_max rendered), ``source``: where m1, b1 come from (default ``k_source``);
    ``rule``: the design's K rule (K then printed as "K … N/m (rule; K_max …)");
    ``own_kmax``: this side's own K_max where the K rendered is another's (catalogue)."""

    def f(v: float, scale: float = 1.0, unit: str = "") -> str:
        return "none" if v is None or not math.isfinite(v) else f"{v * scale:.4g}{unit}"

    if rule is not None:
        k_text = (f"K {f(m['K_N_per_m'])} N/m ({rule}; "
                  f"{format_kmax(m['K_max_N_per_m'], k_source)})")  # fmt: skip
    elif k_source == "typed":
        k_text = f"K {f(m['K_N_per_m'])} N/m [typed]"
    else:
        k_text = format_kmax(m["K_N_per_m"], k_source)
    if own_kmax is not None and rule is None and k_source != source and source is not None:
        k_text = (f"K {f(m['K_N_per_m'])} N/m (the smaller K_max of the two, [{k_source}]; "
                  f"this side's own K_max {f(own_kmax)} N/m [{source}])")  # fmt: skip
    print(
        f"  m1 {f(m['m1_kg'], 1e3)} g  m2 {f(m['m2_kg'], 1e3)} g  b1 {f(m['b1_N_s_per_m'])} N·s/m"
        f"  k {f(m['k_N_per_m'])} N/m  b {f(m['b_N_s_per_m'])} N·s/m"
        f"  delay {f(m['delay_s'], 1e3)} ms  [{source or k_source}]"
    )
    print(
        f"  {k_text}: bandwidth {f(m['bandwidth_hz'], unit=' Hz')}"
        f" (lumped {f(m['bandwidth_lumped_hz'], unit=' Hz')}),"
        f" resonance {f(m['resonance_hz'], unit=' Hz')},"
        f" rendering area {f(m['rendering_area_dB_decade'])} dB·decade"
    )
    print(
        f"  {'passive' if m['passive'] else 'NOT passive'} (up to "
        f"{f(m['max_passive_K_N_per_m'], unit=' N/m')}), stable up to "
        f"{f(m['max_stable_K_N_per_m'], unit=' N/m')}"
    )
