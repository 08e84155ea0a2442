"""The sweep's Pareto plot on many rows (issue 40): the front found in blocks is the
front, a parallel-coordinates panel draws a sample of a large front, and the plot reports
its steps."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from mrclutch.cli.plots.design import (
    BINS,
    MAX_LINES,
    MAX_REST_LINES,
    PLOT_STEPS,
    binned_mean,
    pareto_plot,
    sample_lines,
    sample_rows,
)
from mrclutch.sweep import pareto_front


def _brute(x: np.ndarray, maximize: list[bool]) -> np.ndarray:
    """The definition, all pairs: a finite row no other row weakly beats everywhere and
    strictly somewhere (rows distinct here)."""
    y = x * np.where(maximize, 1.0, -1.0)
    ok = np.all(np.isfinite(y), axis=1)
    ge = (y[:, None] >= y[None]).all(-1) & (y[:, None] > y[None]).any(-1)  # [i, j]: i beats j
    ge &= ok[:, None]
    return ok & ~ge.any(0)


def test_front_in_blocks_is_the_front_of_the_definition():
    """Against all pairs on 1200 random rows (blocks of 256 and their carry-over), 1 to 4
    objectives, mixed directions, a few NaN rows; two equal rows keep one."""
    rng = np.random.default_rng(3)
    for k in (1, 2, 3, 4):
        x = rng.normal(size=(1200, k))
        if k > 1:
            x[:, -1] -= x[:, 0]  # anti-correlated: a front of many rows
        x[rng.random(1200) < 0.02, 0] = np.nan
        mx = [bool(b) for b in rng.random(k) < 0.5]
        got = pareto_front(x, mx)
        assert got.sum() >= 1
        np.testing.assert_array_equal(got, _brute(x, mx))
    two = np.array([[1.0, 2.0], [1.0, 2.0], [0.0, 0.0]])
    assert pareto_front(two, [True, True]).tolist() == [True, False, False]


def test_front_of_two_objectives_is_the_block_sweeps_front_with_ties():
    """Two objectives take a running maximum, more take blocks: on integer rows (many
    ties, equal rows) the 2-D front equals the front of the same rows with a constant
    third objective (which changes no dominance), 1 to 3000 rows, mixed directions."""
    rng = np.random.default_rng(11)
    for n in (1, 2, 7, 300, 3000):
        x = rng.integers(0, 9, size=(n, 2)).astype(float)
        x[rng.random(n) < 0.03, 1] = np.nan
        for mx in ([True, True], [True, False], [False, False]):
            three = np.column_stack([x, np.zeros(n)])
            got = pareto_front(x, mx)
            np.testing.assert_array_equal(got, pareto_front(three, [*mx, True]))
            assert got.sum() >= 1
    assert pareto_front(np.empty((0, 2)), [True, True]).shape == (0,)


def test_binned_mean_is_the_mean_of_numpys_2d_histograms():
    """One pass of bincount over numpy.histogram's cells: the same edges, counts and means
    as numpy.histogram2d's count and weighted sum, on points on the cells' edges (the last
    edge in the last cell), a NaN point, and an axis of one value (its span ±0.5)."""
    rng = np.random.default_rng(5)
    for same in (False, True):
        x = np.repeat(np.linspace(0.0, 1.0, 11), 30)  # on the edges of 10 cells
        x = np.full_like(x, 2.0) if same else x
        y = rng.integers(0, 5, size=x.size).astype(float)
        c = rng.random(x.size)
        y[3] = np.nan
        ok = np.isfinite(y)
        mean, xe, ye = binned_mean(x, y, c, bins=(10, 4))
        n, xe2, ye2 = np.histogram2d(x[ok], y[ok], bins=(10, 4))
        total, _, _ = np.histogram2d(x[ok], y[ok], bins=[xe2, ye2], weights=c[ok])
        np.testing.assert_array_equal(xe, xe2)
        np.testing.assert_array_equal(ye, ye2)
        np.testing.assert_array_equal(mean.mask, (n == 0).T)
        np.testing.assert_allclose(mean.filled(0), np.where(n > 0, total / np.maximum(n, 1),
                                                            0).T, rtol=1e-12)  # fmt: skip


def test_sample_lines_keeps_ends_and_at_most_the_limit():
    order = np.arange(10_000)[::-1]
    s = sample_lines(order)
    assert s.size == MAX_LINES and s[0] == order[0] and s[-1] == order[-1]
    assert np.all(np.diff(s) < 0)  # in the order given, no repeats
    assert sample_lines(order[:50]).tolist() == order[:50].tolist()


def test_plot_of_a_large_front_draws_a_sample_and_reports_its_steps(tmp_path, monkeypatch):
    """3000 valid rows on a front of 3000 (each better in one objective, worse in
    another): the scatter panels draw every point (3000 ≤ ``MAX_POINTS``), the
    parallel-coordinates panel ``MAX_LINES`` of the front and says so, no grey line (no
    design is off the front); progress runs 1 … 4."""
    n = 3000
    t = np.linspace(0, 1, n)
    cols = {"valid": np.ones(n), "bandwidth_hz": 10 + 50 * t, "max_torque_N_m": 2 - t,
            "drag_damping_N_m_s": np.full(n, 1e-4), "clutch_mass_kg": np.full(n, 0.2)}  # fmt: skip
    csv = tmp_path / "r.csv"
    csv.write_text(",".join(cols) + "\n" + "\n".join(
        ",".join(f"{float(cols[k][i])!r}" for k in cols) for i in range(n)) + "\n")  # fmt: skip
    steps = []
    figs = _drawn(monkeypatch)
    out = pareto_plot(csv, tmp_path / "p.png", progress=steps.append)
    assert out.stat().st_size > 0 and steps == list(range(1, PLOT_STEPS + 1))
    top, par = figs[0].axes[0], figs[0].axes[2]
    assert not top.images and len(top.collections[0].get_offsets()) == n
    grey, red = par.collections
    assert len(red.get_segments()) == MAX_LINES and len(grey.get_segments()) == 0
    assert f"{MAX_LINES} of its {n} designs" in par.get_title() and "grey" not in par.get_title()
    import matplotlib.pyplot as plt

    assert plt.get_fignums() == []  # save_png closed it


def _results_csv(path, cols):
    n = len(next(iter(cols.values())))
    path.write_text(",".join(cols) + "\n" + "\n".join(
        ",".join(f"{float(cols[k][i])!r}" for k in cols) for i in range(n)) + "\n")  # fmt: skip
    return path


def _drawn(monkeypatch):
    """The figures ``pareto_plot`` hands to ``save_png`` (written and closed as usual)."""
    import mrclutch.cli.plots.design as design_plots

    figs, real = [], design_plots.save_png

    def keep(fig, out, dpi=110):
        figs.append(fig)
        return real(fig, out, dpi=dpi)

    monkeypatch.setattr(design_plots, "save_png", keep)
    return figs


def test_sample_rows_is_a_seeded_random_subset_in_order():
    """Every 10th row of a grid holds one value of its fastest axis (index mod 10): an
    evenly spaced sample of 10⁵ rows by 10⁴ would draw that one value only; the random one
    holds each of the ten values ~10⁴/10 = 1000 times (±3σ = ±90 for a share of 1/10)."""
    s = sample_rows(100_000, 10_000)
    assert s.size == 10_000 and np.all(np.diff(s) > 0) and 0 <= s[0] and s[-1] < 100_000
    assert np.array_equal(s, sample_rows(100_000, 10_000))  # the same figure every time
    counts = np.bincount(s % 10, minlength=10)
    assert counts.min() > 1000 - 90 and counts.max() < 1000 + 90
    assert sample_rows(50, 10_000).tolist() == list(range(50))


def test_binned_mean_by_hand():
    """Points (0, 0) c=1, (0.2, 0.1) c=3 and (1, 1) c=5 in 2 × 2 cells over [0, 1]²: the
    lower-left cell holds the first two (mean 2), the upper-right the third (5), the other
    two none (masked); a NaN point is left out."""
    x, y = np.array([0.0, 0.2, 1.0, np.nan]), np.array([0.0, 0.1, 1.0, 0.5])
    mean, xe, ye = binned_mean(x, y, np.array([1.0, 3.0, 5.0, 7.0]), bins=(2, 2))
    assert xe.tolist() == [0, 0.5, 1] and ye.tolist() == [0, 0.5, 1]
    assert mean[0, 0] == 2 and mean[1, 1] == 5  # rows: y, columns: x
    assert mean.mask.tolist() == [[False, True], [True, False]]


def test_plot_of_many_rows_draws_what_it_says(tmp_path, monkeypatch):
    """20 000 rows, 1 in 20 invalid (19 000 valid): the scatter panels bin all 19 000 (past
    ``MAX_POINTS`` = 10⁴) in ``BINS`` cells and circle every design of the front; the
    parallel-coordinates panel draws the front (fewer than ``MAX_LINES`` here) over
    ``MAX_REST_LINES`` = 2000 grey lines of the other valid designs; the titles say both
    samples, the axes their units and ranges. Bandwidth spans 10 – 60 Hz, torque 0.5 – 2
    N·m, damping 1e-4 – 5e-4 N·m·s = 100 – 500 µN·m·s (worst, 500, first)."""
    n = 20_000
    rng = np.random.default_rng(7)
    bw = rng.uniform(10, 60, n)
    tq = rng.uniform(0.5, 2.0, n)
    damp = rng.uniform(1e-4, 5e-4, n)
    bw[:2], tq[:2], damp[:2] = (10, 60), (0.5, 2.0), (5e-4, 1e-4)  # the ranges' ends
    valid = np.where(np.arange(n) % 20 == 19, 0.0, 1.0)
    csv = _results_csv(tmp_path / "r.csv", {
        "valid": valid, "bandwidth_hz": bw, "max_torque_N_m": tq,
        "drag_damping_N_m_s": damp, "clutch_mass_kg": rng.uniform(0.05, 0.2, n)})  # fmt: skip
    figs = _drawn(monkeypatch)
    pareto_plot(csv, tmp_path / "p.png")
    (fig,) = figs
    ok = valid == 1
    front = pareto_front(np.column_stack([bw[ok], tq[ok], damp[ok]]), [True, True, False])
    assert 0 < front.sum() < MAX_LINES
    top, _, par = fig.axes[:3]
    (image,), circles = top.images, top.collections[-1]
    assert image.get_array().shape == (BINS[1], BINS[0])
    # 19 000 uniform points in 10 800 cells leave 1 − e^(−19000/10800) = 82.8 % of them
    # holding some (torque and bandwidth are independent here); each a mean of 50–200 g
    cells = image.get_array()
    assert 0.80 < cells.count() / cells.size < 0.86
    assert 50 <= cells.min() and cells.max() <= 200
    drawn = {tuple(p) for p in np.asarray(circles.get_offsets())}
    assert drawn == set(zip(tq[ok][front], bw[ok][front], strict=True))  # every front design
    grey, red = par.collections
    assert len(grey.get_segments()) == MAX_REST_LINES
    assert len(red.get_segments()) == front.sum()
    assert f"a random sample of {MAX_REST_LINES} of the other {ok.sum() - front.sum()}" \
        in par.get_title()  # fmt: skip
    assert (f"19000 valid designs of 20000;\nbinned in {BINS[0]} × {BINS[1]} cells, each the "
            "mean mass of its designs") in fig._suptitle.get_text()  # fmt: skip
    assert top.get_ylabel() == "bandwidth at K_max (Hz)"
    assert top.get_xlabel().startswith("max torque (N·m")
    ticks = [t.get_text() for t in par.get_xticklabels()]
    assert ticks[0].endswith("10 – 60 Hz") and ticks[1].endswith("0.5 – 2 N·m")
    assert ticks[2].endswith("500 – 100 µN·m·s")


def test_sweep_says_it_draws_the_plot_on_stderr(tmp_path):
    """After the sweep's rows, before the drawing: one line on stderr, not on stdout (a
    process of its own: a sweep leaves its kernels' choice in the process)."""
    spec = tmp_path / "s.toml"
    spec.write_text('[sweep]\nmode = "random"\nsamples = 40\nseed = 1\n\n[parameters]\n'
                    "gap_mm = {min = 0.3, max = 0.8}\n")  # fmt: skip
    r = subprocess.run([sys.executable, "-m", "mrclutch", "sweep", str(spec), "--out",
                        str(tmp_path / "r.csv"), "--no-progress", "--pareto",
                        str(tmp_path / "p.png")], capture_output=True, text=True,
                       timeout=300)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "p.png").stat().st_size > 1000
    assert "drawing the plot of 40 designs …" in r.stderr and "drawing" not in r.stdout


def _boxes_overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("n", [3000, 20_000])  # every point drawn; binned
def test_the_fixed_layout_keeps_every_text_inside_and_apart(tmp_path, monkeypatch, n):
    """The plot's fixed layout (no layout engine, issue 40) at the widest text a sweep
    gives: 3-digit bandwidths, 4-digit damping (µN·m·s) and masses (g), the titles at their
    most lines. Every drawn text lies inside the figure, no panel's text (ticks, labels,
    title, legend) overlaps another panel's or the colour bar's, and the figure's title
    overlaps none."""
    rng = np.random.default_rng(3)
    bw, tq = rng.uniform(100, 950, n), rng.uniform(0.001, 20, n)
    damp, mass = rng.uniform(1e-4, 9e-3, n), rng.uniform(0.05, 5.0, n)
    csv = _results_csv(tmp_path / "r.csv", {
        "valid": np.ones(n), "bandwidth_hz": bw, "max_torque_N_m": tq,
        "drag_damping_N_m_s": damp, "clutch_mass_kg": mass})  # fmt: skip
    figs = _drawn(monkeypatch)
    pareto_plot(csv, tmp_path / "p.png")
    (fig,) = figs
    assert fig.get_layout_engine() is None  # the layout is the one fixed in the module
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    # each panel's drawn text as constrained layout measures it: its ticks, labels, title
    # and legend (tick labels outside the view limits are kept by matplotlib, not drawn)
    boxes = [ax.get_tightbbox(renderer) for ax in fig.axes]
    assert len(boxes) == 4  # three panels and the colour bar
    for i, a in enumerate(boxes):
        assert page.x0 - 0.5 <= a.x0 and a.x1 <= page.x1 + 0.5
        assert page.y0 - 0.5 <= a.y0 and a.y1 <= page.y1 + 0.5
        for b in boxes[i + 1 :]:
            assert not _boxes_overlap(a, b)
    title = fig._suptitle.get_window_extent(renderer)
    assert fig._suptitle.get_text().count("\n") == (2 if n > 10_000 else 1)
    assert page.y1 >= title.y1 and not any(_boxes_overlap(title, b) for b in boxes)


def test_the_rows_are_read_beside_matplotlibs_import_and_their_errors_come_back(
    tmp_path, monkeypatch
):
    """``pareto_plot`` reads the rows and finds their fronts on a second thread while it
    imports matplotlib (issue 40): the reader runs off the calling thread, and a file the
    reader refuses (no ``clutch_mass_kg`` column) raises its error in the caller, with no
    PNG written."""
    import threading

    import mrclutch.cli.plots.design as design_plots

    seen, real = [], design_plots.plot_columns

    def spy(results):
        seen.append(threading.current_thread())
        return real(results)

    monkeypatch.setattr(design_plots, "plot_columns", spy)
    n = 50
    cols = {"valid": np.ones(n), "bandwidth_hz": np.linspace(10, 60, n),
            "max_torque_N_m": np.linspace(2, 0.5, n), "drag_damping_N_m_s": np.full(n, 1e-4),
            "clutch_mass_kg": np.full(n, 0.1)}  # fmt: skip
    pareto_plot(_results_csv(tmp_path / "r.csv", cols), tmp_path / "p.png")
    assert len(seen) == 1 and seen[0] is not threading.main_thread()
    del cols["clutch_mass_kg"]
    with pytest.raises(Exception, match="clutch_mass_kg"):
        pareto_plot(_results_csv(tmp_path / "bad.csv", cols), tmp_path / "bad.png")
    assert not (tmp_path / "bad.png").exists()


def test_the_sweep_plot_loads_neither_pyplot_nor_the_solids(tmp_path):
    """In a process of its own, the sweep plot draws on an Agg canvas without pyplot (its
    import ~0.06 s) and without mrclutch.solids (the section figure's materials, ~0.08 s):
    ``save_png`` closes a pyplot figure only where pyplot is loaded (issue 40). Nor does it
    load the sweep's running machinery (``mrclutch.sweep.run``, ``lock``: the package
    re-exports on first use), only the front and the store it reads with."""
    n = 30
    cols = {"valid": np.ones(n), "bandwidth_hz": np.linspace(10, 60, n),
            "max_torque_N_m": np.linspace(2, 0.5, n), "drag_damping_N_m_s": np.full(n, 1e-4),
            "clutch_mass_kg": np.full(n, 0.1)}  # fmt: skip
    csv = _results_csv(tmp_path / "r.csv", cols)
    code = ("import sys\nfrom mrclutch.cli.plots.design import pareto_plot\n"
            f"pareto_plot({str(csv)!r}, {str(tmp_path / 'p.png')!r})\n"
            "print(sorted(m for m in ('matplotlib.pyplot', 'mrclutch.solids', "
            "'mrclutch.sweep.run', 'mrclutch.sweep.lock') if m in sys.modules))")  # fmt: skip
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=300)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "p.png").stat().st_size > 1000
    assert r.stdout.strip() == "[]"


def test_the_parallel_coordinates_lines_are_the_scaled_rows():
    """Each line of the parallel-coordinates panel runs through the axes 0, 1, 2 at its
    row's scaled values."""
    from mrclutch.cli.plots.design import _lines

    scaled = np.array([[0.0, 0.5, 1.0], [1.0, 0.25, 0.0]])
    lines = _lines(scaled)
    assert lines.shape == (2, 3, 2)
    for j in range(2):
        np.testing.assert_array_equal(lines[j], np.column_stack([np.arange(3.0), scaled[j]]))
