"""The sweep's Pareto plot on many rows (issue 40): the front found in blocks is the
front, a parallel-coordinates panel draws a sample of a large front, and the plot reports
its steps."""

from __future__ import annotations

import numpy as np

from mrclutch.cli.plots.design import MAX_LINES, PLOT_STEPS, pareto_plot, sample_lines
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


def test_sample_lines_keeps_ends_and_at_most_the_limit():
    order = np.arange(10_000)[::-1]
    s = sample_lines(order)
    assert s.size == MAX_LINES and s[0] == order[0] and s[-1] == order[-1]
    assert np.all(np.diff(s) < 0)  # in the order given, no repeats
    assert sample_lines(order[:50]).tolist() == order[:50].tolist()


def test_plot_of_a_large_front_draws_a_sample_and_reports_its_steps(tmp_path):
    """3000 valid rows on a front of 3000 (each better in one objective, worse in
    another): the panel draws ``MAX_LINES`` of them and says so; progress runs 1 … 4."""
    n = 3000
    t = np.linspace(0, 1, n)
    cols = {"valid": np.ones(n), "bandwidth_hz": 10 + 50 * t, "max_torque_N_m": 2 - t,
            "drag_damping_N_m_s": np.full(n, 1e-4), "clutch_mass_kg": np.full(n, 0.2)}  # fmt: skip
    csv = tmp_path / "r.csv"
    csv.write_text(",".join(cols) + "\n" + "\n".join(
        ",".join(f"{float(cols[k][i])!r}" for k in cols) for i in range(n)) + "\n")  # fmt: skip
    steps = []
    out = pareto_plot(csv, tmp_path / "p.png", progress=steps.append)
    assert out.stat().st_size > 0 and steps == list(range(1, PLOT_STEPS + 1))
    import matplotlib.pyplot as plt

    assert plt.get_fignums() == []  # save_png closed it
