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

    fig, ax = plt.subplots(figsize=(9, 7))
    seen: set[str] = set()
    notes = []
    for r in rows:
        c = COLOURS.get(r.quantity, "k")
        y = max(r.error_rel, ERROR_FLOOR)
        ax.loglog([r.time_s], [y], "o", ms=8, mec=c, mfc="none" if r.reference else c,
                  label=None if r.quantity in seen else r.quantity)  # fmt: skip
        seen.add(r.quantity)
        floor = y == ERROR_FLOOR  # references side by side: labels steeper, less overlap
        notes.append(ax.annotate(f"{r.method} {r.setting}" + (" (ref)" if r.reference else ""),
                                 (r.time_s, y), textcoords="offset points", xytext=(5, 3),
                                 fontsize=8, color=c, rotation=70 if floor else 0,
                                 arrowprops={"arrowstyle": "-", "color": c, "lw": 0.5,
                                             "alpha": 0.6}))  # fmt: skip
    ax.axhline(0.01, color="0.6", ls=":", lw=1)
    ax.set_xlabel("time per evaluation [s] (median)")
    ax.set_ylabel(f"relative error against the reference (floor {ERROR_FLOOR:g})")
    ax.set_ylim(ERROR_FLOOR / 3, 30.0)  # room above the worst error: no label in the title
    ax.set_title(title or "speed against accuracy")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="center left")
    fig.tight_layout()
    _spread(fig, notes)
    save_png(fig, path, dpi=120)


#: Where a label may sit beside its marker (points right/up; "right" aligns its end there).
_SPOTS = [(dx, dy, ha) for dy in (3, -12, 13, -22, 23, -32, 33, -42, 43, -52, 53, -62)
          for dx, ha in ((6, "left"), (-6, "right"), (40, "left"), (-40, "right"))]  # fmt: skip


def _spread(fig: Any, notes: list[Any]) -> None:
    """Give each label the first spot beside its marker where its box overlaps no label
    placed before it, no marker, nor the title, and stays inside the axes (else the spot
    it overlaps least); a thin line joins a moved label to its marker."""
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    frame = ax.get_window_extent(renderer)
    title = ax.title.get_window_extent(renderer)
    dots = [ax.transData.transform(n.xy) for n in notes]
    placed: list[Any] = []

    def cost(box: Any) -> float:
        bad = sum(_area(box, b) for b in placed) + _area(box, title)
        bad += sum(25.0 for x, y in dots if box.x0 <= x <= box.x1 and box.y0 <= y <= box.y1)
        inside = frame.x0 <= box.x0 and box.x1 <= frame.x1 and box.y1 <= frame.y1
        return bad + (0.0 if inside else 1e6)

    for note in notes:
        if note.get_rotation():  # the references' steep labels along the floor stay
            placed.append(note.get_window_extent(renderer))
            continue
        best = None
        for dx, dy, ha in _SPOTS:
            note.xyann = (dx, dy)
            note.set_ha(ha)
            c = cost(note.get_window_extent(renderer))
            if best is None or c < best[0]:
                best = (c, dx, dy, ha)
            if c == 0:
                break
        _, dx, dy, ha = best
        note.xyann = (dx, dy)
        note.set_ha(ha)
        placed.append(note.get_window_extent(renderer))


def _area(a: Any, b: Any) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(w, 0.0) * max(h, 0.0)
