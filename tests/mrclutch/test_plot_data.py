"""What a person sees, read back from the figure: each plot's drawn data against the model
it claims to show (issue 46). The figure is caught at ``save_png`` (the one output layer),
before it is written, so the test reads the lines matplotlib would draw.

* ``haptic.png`` (``compare --plot``, the report's haptic figure): the drawn k_eff of each
  side crosses zero, going down, on that side's dotted bandwidth line, and the line sits at
  ``haptics.model.bandwidth``; the closed loop's |Z| at the lowest frequency drawn is the
  spring's K/ω with ω = 2πf (the x axis says Hz). Drawn against ω = f, the crossing moves
  2π to the right (24.4 → 153 Hz on the paper pair at K_max).
* the torque chart (``torque --plot``, the report's torque.png): its points are
  ``torque --json``'s, on axes labelled A and N·m.
"""

from __future__ import annotations

import json
import math

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from mrclutch.cli import report
from mrclutch.cli.main import main
from mrclutch.cli.plots import haptic as haptic_plots
from mrclutch.cli.plots import magnetics as magnetics_plots
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.haptics.model import BAND_HZ, bandwidth


@pytest.fixture
def caught(monkeypatch):
    """The figures the plot modules hand to ``save_png``, kept open (closed after)."""
    import matplotlib.pyplot as plt

    figs: list = []

    def keep(fig, path, dpi=110, relayout=None):
        figs.append(fig)

    monkeypatch.setattr(haptic_plots, "save_png", keep)
    monkeypatch.setattr(magnetics_plots, "save_png", keep)
    yield figs
    for f in figs:
        plt.close(f)


def _axis(fig, word: str):
    hits = [ax for ax in fig.axes if word in ax.get_ylabel()]
    assert len(hits) == 1, f"{len(hits)} axes with {word!r} in the y label"
    return hits[0]


def _down_crossing(f: np.ndarray, y: np.ndarray) -> float:
    """The first + → − zero crossing of a drawn curve, linear between the drawn points."""
    i = np.nonzero((y[:-1] > 0) & (y[1:] <= 0))[0]
    assert i.size, "the curve never crosses zero going down"
    j = i[0]
    return float(f[j] - y[j] * (f[j + 1] - f[j]) / (y[j + 1] - y[j]))


def test_report_draws_its_haptic_figure_with_the_same_function():
    """The report's haptic.png is drawn by the function tested here."""
    assert report.compare_figure is haptic_plots.compare_figure


def test_drawn_k_eff_crosses_zero_on_the_bandwidth_line(caught, tmp_path):
    """``compare --plot`` on the paper's pairs at K_max (299.2 N/m): for each side the
    drawn k_eff(f) crosses zero going down within one grid step (1500 points over 1–1000
    Hz: 0.46 %) of the dotted line drawn at its bandwidth, and that line is at
    ``bandwidth(p, K)`` (MR pair 21.98 Hz, Maxon 14.61 Hz)."""
    out = tmp_path / "haptic.png"
    assert main(["compare", "--plot", str(out)]) == 0
    (fig,) = caught
    ax_k = _axis(fig, "stiffness")
    assert fig.axes[-1].get_xlabel() == "frequency [Hz]"
    lines = {ln.get_label(): ln for ln in ax_k.get_lines()}
    step = (BAND_HZ[1] / BAND_HZ[0]) ** (1 / 1499) - 1
    seen = 0
    for label, ln in lines.items():
        if label.startswith(("_", "K =")):
            continue
        f, y = (np.asarray(v, float) for v in ln.get_data())
        f0 = _down_crossing(f, y)
        verticals = [float(v.get_xdata()[0]) for v in ax_k.get_lines()
                     if v.get_color() == ln.get_color() and np.ptp(v.get_xdata()) == 0]  # fmt: skip
        assert len(verticals) == 1, label
        assert f0 == pytest.approx(verticals[0], rel=2 * step), label
        seen += 1
    assert seen == 2
    from mrclutch.haptic_run import compare_params

    mr, em, K = compare_params(None, None, TABLE2_MR.workspace)
    bws = sorted(float(bandwidth(p, K)) for p in (mr, em))
    drawn = sorted(float(v.get_xdata()[0]) for v in ax_k.get_lines()
                   if np.ptp(v.get_xdata()) == 0 and v.get_xdata()[0] > 0)  # fmt: skip
    assert drawn == pytest.approx(bws, rel=1e-12)
    assert bws == pytest.approx([14.61, 21.98], abs=0.01)


def test_drawn_closed_loop_impedance_is_the_spring_at_low_frequency(caught, tmp_path):
    """At 1 Hz, far below every corner, the closed loop renders the spring: |Z| ≈ K/ω with
    ω = 2π·1 = 6.283 rad/s, K = 299.2 N/m: 47.62 N·s/m (the masses' and dampers' part is
    under 0.5 % here). The y axis says N·s/m, the x axis Hz."""
    assert main(["compare", "--plot", str(tmp_path / "h.png")]) == 0
    (fig,) = caught
    ax_z = _axis(fig, "|Z|")
    assert "[N·s/m]" in ax_z.get_ylabel()
    from mrclutch.haptic_run import compare_params

    _, _, K = compare_params(None, None, TABLE2_MR.workspace)
    closed = [ln for ln in ax_z.get_lines() if "closed loop" in ln.get_label()]
    assert len(closed) == 2
    for ln in closed:
        f, z = (np.asarray(v, float) for v in ln.get_data())
        assert f[0] == pytest.approx(BAND_HZ[0])
        assert z[0] == pytest.approx(K / (2 * math.pi * f[0]), rel=0.01)


def test_torque_chart_points_are_torque_json(caught, tmp_path, capsys):
    """``torque --plot`` draws ``torque --json``'s points: currents on x in A, torques on y
    in N·m (the axis labels say so), one line per method."""
    argv = ["torque", "--preset", "paper", "--current", "0:7:1"]
    assert main([*argv, "--plot", str(tmp_path / "t.png")]) == 0
    capsys.readouterr()
    assert main([*argv, "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    (fig,) = caught
    (ax,) = fig.axes
    assert ax.get_xlabel() == "current (A)" and ax.get_ylabel() == "torque (N·m)"
    (ln,) = ax.get_lines()
    x, y = (np.asarray(v, float) for v in ln.get_data())
    np.testing.assert_allclose(x, [p["current_A"] for p in js["points"]], rtol=1e-12)
    np.testing.assert_allclose(y, [p["torque_N_m"] for p in js["points"]], rtol=1e-12)
    assert y[-1] == pytest.approx(0.4272, rel=2e-3)  # 7 A on the paper preset: evaluate's
