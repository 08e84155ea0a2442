"""The speed-against-accuracy chart: error against time, log–log (Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mrclutch.cli.plots import save_png

#: Errors below this are drawn at it (a log axis has no 0; the references sit there): the
#: order of double-precision rounding, so no measured error is hidden under it.
ERROR_FLOOR = 1e-16
COLOURS = {"inertia": "tab:blue", "torque": "tab:red", "stability": "tab:green",
           "bandwidth": "tab:purple", "eddy_delay": "tab:orange"}  # fmt: skip


def plot_fidelity(rows: Sequence[Any], path: str | Path, title: str = "") -> None:
    """One marker per method (Row of mrclutch.fidelity.measure), one colour per quantity,
    each labelled with its method and setting; references drawn as open markers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6.5))
    seen: set[str] = set()
    for r in rows:
        c = COLOURS.get(r.quantity, "k")
        y = max(r.error_rel, ERROR_FLOOR)
        ax.loglog([r.time_s], [y], "o", ms=8, mec=c, mfc="none" if r.reference else c,
                  label=None if r.quantity in seen else r.quantity)  # fmt: skip
        seen.add(r.quantity)
        floor = y == ERROR_FLOOR  # references side by side: labels steeper, less overlap
        ax.annotate(f"{r.method} {r.setting}" + (" (ref)" if r.reference else ""),
                    (r.time_s, y), textcoords="offset points", xytext=(4, 4), fontsize=7,
                    color=c, rotation=70 if floor else 20)  # fmt: skip
    ax.axhline(0.01, color="0.6", ls=":", lw=1)
    ax.set_xlabel("time per evaluation [s] (median)")
    ax.set_ylabel(f"relative error against the reference (floor {ERROR_FLOOR:g})")
    ax.set_ylim(ERROR_FLOOR / 3, 3.0)
    ax.set_title(title or "speed against accuracy")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="center left")
    fig.tight_layout()
    save_png(fig, path, dpi=120)
