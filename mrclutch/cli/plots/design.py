"""Figures of design sweeps: the Pareto front of bandwidth, torque and drag."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mrclutch.cli.plots import save_png, stack_axes
from mrclutch.sweep import is_parquet, pareto_front, read_results

__all__ = ["pareto_plot", "pareto_set_plot", "read_results"]


#: Lines a parallel-coordinates panel draws of the front at most: past this many front
#: designs it draws this many, evenly spaced along the front's bandwidth order, and says so
#: in its title.
MAX_LINES = 200
#: Lines the parallel-coordinates panel draws, in grey behind the front, of the valid
#: designs off it: a random sample of at most this many (said in its title). All 10⁵ lines
#: of a sweep are a solid block that took ~20 s to draw (issue 40).
MAX_REST_LINES = 2000
#: Points a scatter panel draws at most: past this many valid designs it bins them all
#: instead (``BINS`` cells, each coloured by the mean mass of its designs; empty cells
#: blank) and circles every front member; the title says which (10⁵ points drawn three
#: times and a "best" legend placed among them took ~20 s, issue 40).
MAX_POINTS = 10_000
#: Cells (across, up) of a scatter panel's 2-D histogram past ``MAX_POINTS`` designs.
BINS = (120, 90)
#: Inches: the sweep plot's figure (across, up).
FIGSIZE = (6.0, 11.0)
#: Inches: the sweep plot's fixed layout (issue 40: a layout engine measures every tick
#: label in extra passes before the one draw; benchmarks/bench_sweep_plot.py). Each margin
#: is sized for the text it holds: left of the panels their y label and 3-digit ticks;
#: below the bottom panel its three-line axis names; between the top two panels an x
#: label; above the bottom one an x label and its title of up to three lines; above the top
#: one the figure's title of up to three lines; right of the panels the colour bar, its
#: ticks and label. tests/mrclutch/test_sweep_plot.py checks that no text leaves the figure
#: or overlaps another panel's, at the widest values a sweep gives.
LEFT, PANEL_WIDTH, BOTTOM, GAP, TITLED_GAP, TOP = 0.66, 3.8, 0.62, 0.52, 1.12, 0.8
#: Inches: from the figure's top edge to its title's first line.
TITLE_PAD = 0.08
#: Inches: the colour bar's distance from the panels and its width.
BAR_GAP, BAR_WIDTH = 0.28, 0.25
#: The columns ``pareto_plot`` reads (a sweep's CSV has ~40: only these are parsed).
PLOT_COLUMNS = ("valid", "bandwidth_hz", "max_torque_N_m", "drag_damping_N_m_s",
                "clutch_mass_kg")  # fmt: skip


def plot_columns(results: str | Path, names: tuple[str, ...] = PLOT_COLUMNS) -> dict:
    """The columns ``names`` of a sweep's results as floats (empty cells NaN): a CSV read by
    pyarrow's parser, those columns only (``read_results`` parses every column); a Parquet
    dataset by ``read_results``."""
    if is_parquet(results):
        r = read_results(results)
        return {k: r[k] for k in names}
    import pyarrow as pa
    from pyarrow import csv

    conv = csv.ConvertOptions(include_columns=list(names),
                              column_types={k: pa.float64() for k in names})  # fmt: skip
    # one thread: the plot reads beside matplotlib's import (``pareto_plot``), and pyarrow's
    # pool would take the core that import runs on (10⁵ rows: ~0.2 s of CPU either way)
    table = csv.read_csv(results, read_options=csv.ReadOptions(use_threads=False),
                         convert_options=conv)  # fmt: skip
    return {k: table[k].to_numpy(zero_copy_only=False).astype(float) for k in names}


def sample_lines(order: np.ndarray, most: int = MAX_LINES) -> np.ndarray:
    """At most ``most`` of the indices ``order``, evenly spaced along it (its first and its
    last kept); all of them when there are no more than ``most``."""
    if order.size <= most:
        return order
    return order[np.unique(np.round(np.linspace(0, order.size - 1, most)).astype(int))]


def sample_rows(n: int, most: int, seed: int = 0) -> np.ndarray:
    """At most ``most`` of the indices 0 … n−1, in order: a random sample without
    replacement (seeded: a file draws the same figure every time); all of them when
    n ≤ most. Random rather than evenly spaced: every k-th row of a grid sweep can be one
    value of its fastest axis."""
    if n <= most:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, size=most, replace=False))


def binned_mean(x: np.ndarray, y: np.ndarray, c: np.ndarray, bins: tuple[int, int] = BINS
                ) -> tuple[np.ma.MaskedArray, np.ndarray, np.ndarray]:  # fmt: skip
    """The mean of ``c`` over the points (x, y) in each cell of a ``bins`` grid spanning
    them (rows: y, columns: x, as an image), masked where a cell holds none; and the cell
    edges in x and y. Non-finite points are left out."""
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(c)
    x, y, c = x[ok], y[ok], c[ok]
    (ix, xe), (iy, ye) = _cells(x, bins[0]), _cells(y, bins[1])
    cell = ix * bins[1] + iy  # one pass of bincount, not two 2-D histograms (issue 40)
    n = np.bincount(cell, minlength=bins[0] * bins[1]).reshape(bins)
    total = np.bincount(cell, weights=c, minlength=bins[0] * bins[1]).reshape(bins)
    mean = np.ma.masked_where(n == 0, total / np.maximum(n, 1))
    return mean.T, xe, ye


def _cells(v: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """The cell of each value of ``v`` among ``bins`` equal cells spanning it, and their
    edges: numpy.histogram's (a cell holds its left edge, the last one its right edge too;
    one value: a span of ±0.5 around it)."""
    edges = np.histogram_bin_edges(v, bins=bins)
    return np.minimum(np.searchsorted(edges, v, side="right") - 1, bins - 1), edges


def _panel_rects() -> list[tuple[float, float, float, float]]:
    """The three panels' rectangles, top to bottom, in figure fractions (``FIGSIZE``):
    equal heights between the fixed margins."""
    w, h = FIGSIZE
    height = (h - BOTTOM - TITLED_GAP - GAP - TOP) / 3
    bottoms = (BOTTOM + 2 * height + TITLED_GAP + GAP, BOTTOM + height + TITLED_GAP, BOTTOM)
    return [(LEFT / w, y / h, PANEL_WIDTH / w, height / h) for y in bottoms]


def _colorbar_rect() -> tuple[float, float, float, float]:
    """The colour bar's rectangle beside the top two panels, in figure fractions."""
    top, middle, _ = _panel_rects()
    x = top[0] + top[2] + BAR_GAP / FIGSIZE[0]
    return (x, middle[1], BAR_WIDTH / FIGSIZE[0], top[1] + top[3] - middle[1])


def _span(values: np.ndarray, unit: str) -> str:
    """An axis' range in its unit, worst to best as drawn."""
    return f"{values[0]:.3g} – {values[1]:.3g} {unit}"


@dataclass(frozen=True)
class PlotData:
    """What ``pareto_plot`` draws of a sweep's rows, found before matplotlib is needed: the
    valid designs' bandwidth (Hz), max torque (N·m), damping (µN·m·s) and mass (g); the
    mask of the three-objective front; each top panel's two-objective front (indices in
    the panel's x order) and, past ``MAX_POINTS`` designs, its cells (``binned_mean``);
    the parallel-coordinates panel's lines (n × 3 × 2: axis, 0 worst … 1 best) of the
    front's sample and of the grey sample of the others, with the count of those others
    and each axis' range worst to best (None without a valid design)."""

    rows: int
    bw: np.ndarray
    tq: np.ndarray
    damp: np.ndarray
    mass: np.ndarray
    front: np.ndarray
    fronts: tuple[np.ndarray, np.ndarray]
    cells: tuple[Any, Any]
    shown: np.ndarray
    grey: np.ndarray
    rest: int
    ranges: list[tuple[float, float]] | None


def plot_data(results: str | Path) -> PlotData:
    """``PlotData`` of a sweep's results (its five ``PLOT_COLUMNS``)."""
    r = plot_columns(results)
    ok = r["valid"] == 1
    bw, tq = r["bandwidth_hz"][ok], r["max_torque_N_m"][ok]
    damp, mass = r["drag_damping_N_m_s"][ok] * 1e6, r["clutch_mass_kg"][ok] * 1e3
    front = pareto_front(np.column_stack([bw, tq, damp]), [True, True, False])
    binned = bw.size > MAX_POINTS
    fronts, cells = [], []
    for x, big in ((tq, True), (damp, False)):
        k = np.flatnonzero(pareto_front(np.column_stack([bw, x]), [True, big]))
        fronts.append(k[np.argsort(x[k])])
        cells.append(binned_mean(x, bw, mass) if binned else None)
    lines = np.empty((0, 3, 2))
    shown, grey, rest, ranges = lines, lines, 0, None
    if ok.any():
        cols = [bw, tq, -damp]  # larger is better on every axis
        lo = [float(np.nanmin(c)) for c in cols]
        hi = [float(np.nanmax(c)) for c in cols]
        scaled = np.column_stack([(c - a) / (b - a) if b > a else np.ones_like(c)
                                  for c, a, b in zip(cols, lo, hi, strict=True)])  # fmt: skip
        ranges = [(lo[0], hi[0]), (lo[1], hi[1]), (-lo[2], -hi[2])]  # worst to best
        k = np.flatnonzero(front)
        others = np.flatnonzero(~front & np.all(np.isfinite(scaled), axis=1))
        rest = int(others.size)
        grey = _lines(scaled[others[sample_rows(others.size, MAX_REST_LINES, seed=1)]])
        shown = _lines(scaled[sample_lines(k[np.argsort(bw[k], kind="stable")], MAX_LINES)])
    return PlotData(int(ok.size), bw, tq, damp, mass, front, (fronts[0], fronts[1]),
                    (cells[0], cells[1]), shown, grey, rest, ranges)  # fmt: skip


def _lines(scaled: np.ndarray) -> np.ndarray:
    """Parallel-coordinates lines (n × 3 × 2) of scaled rows (n × 3): x the axis 0, 1, 2."""
    x3 = np.broadcast_to(np.arange(3.0), scaled.shape)
    return np.stack([x3, scaled], axis=2)


def _in_background(fn: Callable[..., Any], *args: Any) -> Callable[[], Any]:
    """``fn(*args)`` started on a thread of its own; returns a wait that gives its result
    or raises its exception here."""
    box: dict[str, Any] = {}

    def run() -> None:
        try:
            box["value"] = fn(*args)
        except BaseException as e:  # raised again in the waiting thread
            box["error"] = e

    thread = threading.Thread(target=run, name="mrclutch-plot-data", daemon=True)
    thread.start()

    def wait() -> Any:
        thread.join()
        if "error" in box:
            raise box["error"]
        return box["value"]

    return wait


def pareto_plot(results: str | Path, out: str | Path,
                progress: Callable[[int], None] | None = None) -> Path:  # fmt: skip
    """The Pareto front of three objectives: rendering bandwidth (max), max torque (max) and
    off-state viscous damping (min). Top two panels: bandwidth against each other objective,
    mass as colour (past ``MAX_POINTS`` designs binned, ``binned_mean``), with
    that panel's own two-objective front (a step line, computed on the panel's axes) and
    every design of the three-objective front circled (it may lie inside a 2-D cloud: a
    design there wins on the third objective). Bottom: the three-objective front on all
    three axes at once (parallel coordinates, each axis from the worst to the best valid
    design; at most ``MAX_LINES`` lines, evenly spaced along the front, ``sample_lines``)
    over a random sample of at most ``MAX_REST_LINES`` of the other valid designs in grey.
    Every sample is said on the figure. ``progress(n)``: called with the steps done of
    ``PLOT_STEPS`` (read, fronts, drawn, written).

    The rows are read and their fronts found (``plot_data``) on a second thread while this
    one imports matplotlib (issue 40: ~0.7 s of CPU in a fresh process; pyarrow's parser
    and numpy's sorts run without the GIL)."""
    data = _in_background(plot_data, results)
    import matplotlib

    matplotlib.use("Agg")  # whatever imports pyplot after: never a window
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    step = progress if progress is not None else (lambda _n: None)
    d = data()
    step(1)  # the rows read and
    step(2)  # their fronts found, beside matplotlib's import
    bw, tq, damp, front = d.bw, d.tq, d.damp, d.front
    fig = Figure(figsize=FIGSIZE)  # no pyplot: nothing to manage
    FigureCanvasAgg(fig)
    axes = [fig.add_axes(rect) for rect in _panel_rects()]  # a fixed layout (issue 40)
    span = {"vmin": np.nanmin(d.mass), "vmax": np.nanmax(d.mass)} if d.mass.size else {}
    for ax, x, two, cells, label, big in (
        (axes[0], tq, d.fronts[0], d.cells[0], "max torque (N·m; more is better)", True),
        (axes[1], damp, d.fronts[1], d.cells[1], "viscous damping (µN·m·s; less is better)",
         False),
    ):  # fmt: skip
        if cells is not None:  # every design, in cells: one image, not 10⁵ markers
            mean, xe, ye = cells
            sc = ax.imshow(mean, origin="lower", extent=(xe[0], xe[-1], ye[0], ye[-1]),
                           aspect="auto", interpolation="nearest", cmap="viridis",
                           **span)  # fmt: skip
        else:
            sc = ax.scatter(x, bw, c=d.mass, s=6, cmap="viridis", alpha=0.6, linewidths=0,
                            **span)  # fmt: skip
        ax.step(x[two], bw[two], where="post" if big else "pre", color="k", lw=1,
                label=f"front of these two axes ({two.size})")  # fmt: skip
        ax.scatter(x[front], bw[front], s=22, facecolors="none", edgecolors="crimson",
                   linewidths=0.8, label=f"front of all three ({front.sum()})")  # fmt: skip
        ax.set_xlabel(label)
        ax.set_ylabel("bandwidth at K_max (Hz)")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize=9)  # not "best": a search among 10⁵ points
    fig.colorbar(sc, cax=fig.add_axes(_colorbar_rect()), label="clutch mass (g)")
    ax = axes[2]
    title = "the three-objective front (crimson) on its own axes"
    names = ["bandwidth (Hz)\n(max)", "max torque (N·m)\n(max)", "damping (µN·m·s)\n(min)"]
    if d.ranges is not None:
        names = [f"{n}\n{_span(v, u)}" for n, v, u in
                 zip(names, d.ranges, ("Hz", "N·m", "µN·m·s"), strict=True)]  # fmt: skip
        ax.add_collection(LineCollection(d.grey, colors="0.45", alpha=0.25, linewidths=0.6,
                                         zorder=1))  # fmt: skip
        ax.add_collection(LineCollection(d.shown, colors="crimson", alpha=0.45,
                                         linewidths=0.7, zorder=2))  # fmt: skip
        n_front, n_rest = int(front.sum()), d.rest
        if len(d.shown) < n_front:
            title += f"\n({len(d.shown)} of its {n_front} designs, evenly spaced in bandwidth)"
        if len(d.grey) < n_rest:
            title += f"\ngrey: a random sample of {len(d.grey)} of the other {n_rest} designs"
        elif n_rest:
            title += f"\ngrey: the other {n_rest} designs"
    ax.set_xticks(range(3), names, fontsize=9)
    ax.set_yticks([0, 1], ["worst", "best"])
    ax.set_xlim(-0.1, 2.1)
    ax.set_ylim(-0.05, 1.05)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    how = (f";\nbinned in {BINS[0]} × {BINS[1]} cells, each the mean mass of its designs"
           if d.cells[0] is not None else "")  # fmt: skip
    fig.suptitle(f"Pareto front: max bandwidth, max torque, min damping\n"
                 f"({bw.size} valid designs of {d.rows}{how})", fontsize=11,
                 y=1 - TITLE_PAD / FIGSIZE[1])  # fmt: skip
    step(3)
    save_png(fig, out, dpi=110)
    step(PLOT_STEPS)
    return Path(out)


PLOT_STEPS = 4  # pareto_plot's progress: read, fronts, drawn, written


#: Colours by material for the section drawing (matches the 3D view's palette in spirit).
MATERIAL_COLOURS = {
    "steel_1018": "#6e7b8b",
    "stainless_304": "#c9ced6",
    "coil": "#c8792a",
    "mrf_132dg": "#3b3b3b",
}


#: Inches: the section drawing's fixed margins (left, right, bottom, top; ``stack_axes``):
#: the y label and 3-character tick labels, half the last x tick label, the x tick labels
#: and label, the title; the drawing at equal scale inside them. Text that does not fit:
#: constrained layout (``save_png``'s ``relayout``).
SECTION_MARGINS = (0.62, 0.2, 0.55, 0.36)


def section_figure(section: object, out: str | Path) -> Path:
    """The r–z half-section: every region coloured by material, gaps and zones marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch, Rectangle

    from mrclutch.solids import material_colour, material_label  # not the sweep plot's

    fig, ax = plt.subplots(figsize=(6, 6))
    stack_axes(fig, 1, SECTION_MARGINS, 0.0)  # a fixed layout (issue 40)
    for reg in section.regions:  # type: ignore[attr-defined]
        colour = MATERIAL_COLOURS.get(reg.material, material_colour(reg.material))
        ax.add_patch(
            Rectangle((reg.r0 * 1e3, reg.z0 * 1e3), (reg.r1 - reg.r0) * 1e3,
                      (reg.z1 - reg.z0) * 1e3, facecolor=colour, edgecolor="white", lw=0.3)
        )  # fmt: skip
    for zone in section.zones:  # type: ignore[attr-defined]
        x0 = section.r_max * 1e3 * 1.005  # type: ignore[attr-defined]
        ax.add_patch(Rectangle((x0, zone.z0 * 1e3), 0.6, zone.length * 1e3, color="gold"))
        ax.text(x0 + 0.9, (zone.z0 + zone.z1) / 2 * 1e3, f"zone {zone.name}", va="center",
                fontsize=9, rotation=90)  # fmt: skip
    ax.set_xlim(0, section.r_max * 1e3 + 2.5)  # type: ignore[attr-defined]
    ax.set_ylim(section.z_min * 1e3 - 1, section.z_max * 1e3 + 1)  # type: ignore[attr-defined]
    ax.set_aspect("equal")
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("z (mm)")
    c = section.clutch  # type: ignore[attr-defined]
    ax.set_title(
        f"{c.n_drums} drums × {c.drum_thickness * 1e3:.3g} mm, gap {c.gap * 1e3:.3g} mm",
        fontsize=10,
    )
    present = dict.fromkeys(reg.material for reg in section.regions)  # type: ignore[attr-defined]
    ax.legend(handles=[Patch(color=MATERIAL_COLOURS.get(m, material_colour(m)),
                             label=material_label(m))
                       for m in present], loc="lower right", fontsize=9)  # fmt: skip
    save_png(fig, out, dpi=130, relayout="constrained")
    return Path(out)


def pareto_set_plot(ps: Any, kept: list[int], paper: dict, out: str | Path) -> Path:
    """The optimiser's Pareto set (``mrclutch.optimize.ParetoSet``): the rendering figure
    against the backdrive force and against the clutch mass, the continuous torque above
    the drag as colour; every front design small, the members kept (numbered) large, the
    paper preset as a star."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (_, rcol, _), *_ = ps.objectives
    f = ps.front
    rend, force = f[rcol], f["backdrive_force_N"]
    cont, mass = f["continuous_above_drag_N_m"] * 1e3, f["clutch_mass_kg"] * 1e3
    rows = {i: m.row for i, m in enumerate(ps.members, 1) if i in kept}
    ph, pc = paper["haptic"], paper["clutch"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    for ax, x, key, scale, label in (
        (axes[0], force, "backdrive_force_N", 1.0, "backdrive force in free motion (N)"),
        (axes[1], mass, "clutch_mass_kg", 1e3, "clutch mass (g)"),
    ):
        sc = ax.scatter(x, rend, c=cont, s=6, cmap="viridis", alpha=0.5, linewidths=0)
        for i, r in rows.items():
            ax.scatter(r[key] * scale, r[rcol], s=40, facecolors="none", edgecolors="crimson")
            ax.annotate(str(i), (r[key] * scale, r[rcol]), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")  # fmt: skip
        if rcol == "bandwidth_hz":
            px = (
                paper["hand"]["mr"]["backdrive_force_N"]
                if key == "backdrive_force_N"
                else (pc["clutch_mass_kg"] * 1e3)
            )
            ax.scatter(px, ph["bandwidth_hz"], marker="*", s=120, c="k", label="paper preset")
            ax.legend(loc="best", fontsize=8)
        ax.set_xlabel(label)
        ax.set_ylabel(rcol)
        ax.grid(alpha=0.3)
    fig.colorbar(sc, ax=axes, label="continuous torque above drag (mN·m)")
    fig.suptitle(f"Pareto front: {ps.front_size} designs meeting every limit (fast path); "
                 f"{len(rows)} members kept at reference fidelity")  # fmt: skip
    save_png(fig, out, dpi=120)
    return Path(out)
