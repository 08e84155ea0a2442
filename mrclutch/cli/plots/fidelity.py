"""The speed-against-accuracy chart: error against time, log–log (Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mrclutch.cli.plots import save_png

#: Errors below this are drawn at it (a log axis has no 0; the references sit there): the
#: order of double-precision rounding, so no measured error is hidden under it.
ERROR_FLOOR = 1e-16
COLOURS = {"inertia": "tab:blue", "torque": "tab:red", "stability": "tab:green",
           "bandwidth": "tab:purple", "eddy_delay": "tab:orange"}  # fmt: skip
MARKER_PT = 8.0  # marker diameter [pt]


def plot_fidelity(rows: Sequence[Any], path: str | Path, title: str = "") -> None:
    """The chart of :func:`fidelity_figure` saved as a PNG at ``path``."""
    save_png(fidelity_figure(rows, title), path, dpi=120)


def fidelity_figure(rows: Sequence[Any], title: str = "") -> Any:
    """One marker per method (Row of mrclutch.fidelity.measure), one colour per quantity,
    each labelled with its method and setting (labels placed by :func:`place_labels`: no
    two overlap); references drawn as open markers on the error floor."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 7))
    seen: set[str] = set()
    notes = []
    for r in rows:
        c = COLOURS.get(r.quantity, "k")
        y = max(r.error_rel, ERROR_FLOOR)
        ax.loglog([r.time_s], [y], "o", ms=MARKER_PT, mec=c, mfc="none" if r.reference else c,
                  label=None if r.quantity in seen else r.quantity)  # fmt: skip
        seen.add(r.quantity)
        notes.append(ax.annotate(f"{r.method} {r.setting}" + (" (ref)" if r.reference else ""),
                                 (r.time_s, y), textcoords="offset points", xytext=(6, 0),
                                 fontsize=8, color=c, va="center"))  # fmt: skip
        notes[-1].set_in_layout(False)  # placed after the layout, inside the axes
    ax.axhline(0.01, color="0.6", ls=":", lw=1)
    ax.set_xlabel("time per evaluation [s] (median)")
    ax.set_ylabel(f"relative error against the reference (floor {ERROR_FLOOR:g})")
    ax.set_ylim(ERROR_FLOOR / 3, 30.0)  # room above the worst error: no label in the title
    ax.set_title(title or "speed against accuracy")
    ax.grid(True, which="both", alpha=0.3)
    legend = ax.legend(loc="center left")
    fig.tight_layout()
    place_labels(fig, ax, notes, avoid=[legend])
    return fig


#: Where a label may go, nearest first, as (distance [pt], angle [deg]) from its marker's
#: centre: beside it in 8 directions (no line), then on rings ever farther out in 16
#: directions (joined by a thin line). The cheapest spot wins, the nearest of equals.
_NEAR_PT = 7.0
_SPOTS = [(_NEAR_PT, a) for a in (0, 180, 45, -45, 135, -135, 90, -90)] + [
    (d, a) for d in (20.0, 34.0, 50.0, 70.0, 95.0, 125.0, 160.0, 200.0, 250.0, 310.0)
    for a in (0, 180, 45, -45, 135, -135, 90, -90, 22.5, -22.5, 157.5, -157.5, 67.5, -67.5,
              112.5, -112.5)]  # fmt: skip
_PAD_PX = 1.5  # clearance kept around every label [px]
_LEADING_PX = 1.0  # between the lines of a stacked list [px]
_PASSES = 3  # improvement passes after the greedy placement


def place_labels(fig: Any, ax: Any, notes: Sequence[Any], avoid: Sequence[Any] = ()) -> None:
    """Label placement, after the layout. Markers drawn over each other (centres closer
    than a marker's radius, chained) share one block: their labels stacked as a list.
    Each block may take any spot of ``_SPOTS`` around its markers; a spot costs the
    overlap of its box with the other blocks, other markers and ``avoid`` (the legend),
    plus its leader line crossing blocks, markers or lines, plus 0.3/px of leader; a box
    outside the axes is barred. Greedy first (blocks with most markers near them first,
    each the cheapest spot given those before it, the nearest of equals), then up to
    ``_PASSES`` passes moving each block to its cheapest spot given all the others.
    A block off its markers is joined to them by a thin line from its nearest point.

    Boxes are computed arithmetically (numpy) from each text's rendered size, one
    ``get_window_extent`` per label, so placement takes milliseconds."""
    renderer = fig.canvas.get_renderer()
    px = fig.dpi / 72.0  # pixels per point
    frame = ax.get_window_extent(renderer)
    lo = np.array([frame.x0, frame.y0]) + _PAD_PX
    hi = np.array([frame.x1, frame.y1]) - _PAD_PX
    blocked = np.array([_box(a.get_window_extent(renderer)) for a in avoid]).reshape(-1, 4)
    dots = np.array([ax.transData.transform(n.xy) for n in notes]).reshape(-1, 2)
    r_dot = (MARKER_PT / 2 + 1.0) * px  # marker radius with its edge [px]
    markers = np.hstack([dots - r_dot, dots + r_dot])
    sizes = np.array([_size(n, renderer) for n in notes]).reshape(-1, 2)
    d = np.array([s[0] for s in _SPOTS]) * px
    a = np.radians([s[1] for s in _SPOTS])
    ux, uy = np.round(np.cos(a), 12), np.round(np.sin(a), 12)
    off = np.stack([d * ux, d * uy], axis=1)  # anchor offsets from the group's centre [px]
    fx = np.where(ux > 0.3, 0.0, np.where(ux < -0.3, 1.0, 0.5))  # box fraction left of it
    fy = np.where(uy > 0.3, 0.0, np.where(uy < -0.3, 1.0, 0.5))  # box fraction below it
    far = d > _NEAR_PT * px
    gap = np.abs(dots[:, None, :] - dots[None, :, :])
    crowd = ((gap[..., 0] < 150 * px) & (gap[..., 1] < 60 * px)).sum(axis=1)
    groups = sorted(_groups(dots, r_dot), key=lambda g: -max(crowd[g]))
    spots = []  # per group: box, padded box, leader (centre → anchor) of every spot
    fixed = []  # per group: what a spot costs whatever the other blocks do
    for g in groups:
        centre = dots[g].mean(axis=0)
        spread = np.ptp(dots[g], axis=0) / 2  # the group's markers reach this far more
        w, h = sizes[g, 0].max(), (sizes[g, 1] + _LEADING_PX).sum() - _LEADING_PX
        anchor = centre + off + np.sign(off) * spread
        x0, y0 = anchor[:, 0] - fx * w, anchor[:, 1] - fy * h
        boxes = np.stack([x0, y0, x0 + w, y0 + h], axis=1)
        padded = boxes + np.array([-1, -1, 1, 1]) * _PAD_PX
        leads = np.hstack([np.broadcast_to(centre, anchor.shape), anchor])
        others = np.delete(markers, g, axis=0)
        cost = 10.0 * _overlap(padded, blocked).sum(axis=1)
        cost += 4.0 * _overlap(padded, others).sum(axis=1)
        cost += far * (40.0 * _crossing(leads, others).sum(axis=1)
                       + 100.0 * _crossing(leads, blocked).sum(axis=1)
                       + 0.3 * np.hypot(*(anchor - centre).T))  # fmt: skip
        out = np.clip(lo - padded[:, :2], 0, None).sum(axis=1)
        out += np.clip(padded[:, 2:] - hi, 0, None).sum(axis=1)
        fixed.append(cost + np.where(out > 0, 1e9 + out, 0.0))
        spots.append((boxes, padded, leads))

    choice = [-1] * len(groups)

    def cost(n: int) -> Any:
        """Every spot of group n given the spots the other groups hold now."""
        held = [m for m, k in enumerate(choice) if k >= 0 and m != n]
        placed = np.array([spots[m][1][choice[m]] for m in held]).reshape(-1, 4)
        lines = np.array([spots[m][2][choice[m]] for m in held if far[choice[m]]])
        lines = lines.reshape(-1, 4)
        _, padded, leads = spots[n]
        c = fixed[n] + 10.0 * _overlap(padded, placed).sum(axis=1)
        c += 100.0 * _crossing(lines, padded).sum(axis=0)
        return c + far * (100.0 * _crossing(leads, placed).sum(axis=1)
                          + 60.0 * _intersect(leads, lines).sum(axis=1))  # fmt: skip

    for n in range(len(groups)):
        choice[n] = int(np.argmin(cost(n)))  # the first of the cheapest: the nearest
    for _ in range(_PASSES):
        moved = False
        for n in range(len(groups)):
            c = cost(n)
            k = int(np.argmin(c))
            if c[k] < c[choice[n]] - 1e-6:
                choice[n], moved = k, True
        if not moved:
            break

    for g, (boxes, _, leads), k in zip(groups, spots, choice, strict=True):
        top, x = boxes[k, 3], boxes[k, 0] + fx[k] * (boxes[k, 2] - boxes[k, 0])
        ha = {0.0: "left", 1.0: "right"}.get(fx[k], "center")
        for i in g:  # stacked top down in the order given, on a common edge
            top -= sizes[i, 1]
            _move(notes[i], ((x, top) - dots[i]) / px, ha)
            top -= _LEADING_PX
        if far[k]:
            _leader(ax, notes[g[0]], leads[k, :2], leads[k, 2:] - leads[k, :2], px)


def _groups(dots: Any, r: float) -> list[list[int]]:
    """Indices of markers chained by centres closer than ``r`` (drawn over each other)."""
    near = np.hypot(*(dots[:, None, :] - dots[None, :, :]).transpose(2, 0, 1)) < r
    parent = list(range(len(dots)))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i, j in zip(*np.nonzero(near), strict=True):
        parent[root(int(i))] = root(int(j))
    out: dict[int, list[int]] = {}
    for i in range(len(dots)):
        out.setdefault(root(i), []).append(i)
    return list(out.values())


def _size(note: Any, renderer: Any) -> tuple[float, float]:
    """Width and height [px] of the text's own box (an Annotation's extent holds its arrow)."""
    from matplotlib.text import Text

    bb = Text.get_window_extent(note, renderer)
    return (bb.width, bb.height)


def _box(bb: Any) -> tuple[float, float, float, float]:
    return (bb.x0, bb.y0, bb.x1, bb.y1)


def _move(note: Any, offset_pt: Any, ha: str) -> None:
    """Put the label's text with its bottom ``ha`` point at ``offset_pt`` from its marker."""
    note.xyann = (float(offset_pt[0]), float(offset_pt[1]))
    note.set_ha(ha)
    note.set_va("bottom")


def _leader(ax: Any, note: Any, centre: Any, offset_px: Any, px: float) -> None:
    """A thin line, in the label's colour, from the block's nearest point (``offset_px``
    from ``centre``, pixels) to the markers' centre, stopping at the marker's edge."""
    c = note.get_color()
    ax.annotate("", ax.transData.inverted().transform(centre), xytext=offset_px / px,
                textcoords="offset points", annotation_clip=False,
                arrowprops={"arrowstyle": "-", "color": c, "lw": 0.6, "alpha": 0.7,
                            "shrinkA": 0.0, "shrinkB": MARKER_PT / 2 + 1.0},
                ).set_in_layout(False)  # fmt: skip


def _overlap(a: Any, b: Any) -> Any:
    """Overlap areas (len(a), len(b)) of boxes (x0, y0, x1, y1)."""
    w = np.minimum(a[:, None, 2], b[None, :, 2]) - np.maximum(a[:, None, 0], b[None, :, 0])
    h = np.minimum(a[:, None, 3], b[None, :, 3]) - np.maximum(a[:, None, 1], b[None, :, 1])
    return np.clip(w, 0, None) * np.clip(h, 0, None)


def _crossing(segs: Any, boxes: Any) -> Any:
    """Whether each segment (x0, y0, x1, y1) meets each box: (len(segs), len(boxes)),
    by Liang–Barsky clipping of the segment's parameter t ∈ [0, 1] to the box's slabs."""
    s, b = segs[:, None, :], boxes[None, :, :]
    t0 = np.zeros((len(segs), len(boxes)))
    t1 = np.ones_like(t0)
    ok = np.ones(t0.shape, dtype=bool)
    for k in (0, 1):  # x, then y slab
        p = s[..., 2 + k] - s[..., k]
        lo, hi = b[..., k] - s[..., k], b[..., 2 + k] - s[..., k]
        flat = p == 0
        ok &= ~flat | ((lo <= 0) & (hi >= 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = lo / p, hi / p
        t0 = np.where(flat, t0, np.maximum(t0, np.minimum(ta, tb)))
        t1 = np.where(flat, t1, np.minimum(t1, np.maximum(ta, tb)))
    return ok & (t0 <= t1)


def _intersect(a: Any, b: Any) -> Any:
    """Whether segments a and b cross properly (not at a shared end): (len(a), len(b))."""

    def side(p: Any, q: Any, r: Any) -> Any:  # sign of the turn p → q → r
        return np.sign((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
                       - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))  # fmt: skip

    a1, a2 = a[:, None, :2], a[:, None, 2:]
    b1, b2 = b[None, :, :2], b[None, :, 2:]
    return (side(a1, a2, b1) * side(a1, a2, b2) < 0) & (side(b1, b2, a1) * side(b1, b2, a2) < 0)
