"""The report's haptic and Z-width figures laid out by hand (issue 40: constrained layout's
passes over every tick label cost more than the one draw), and by constrained layout when a
design's text does not fit the fixed margins: never clipped, panels apart."""

import pytest

from mrclutch.design import design_preset
from mrclutch.pipeline import evaluate
from mrclutch.verdict import judge_evaluation


@pytest.fixture(scope="module")
def paper():
    ev = evaluate(design_preset("paper"), "fast")
    k = float(judge_evaluation(ev)["haptic"]["K_N_per_m"])
    return ev, k


def _drawn(monkeypatch):
    """Each figure handed to ``save_png`` by the haptic plots and how often it was drawn."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    import mrclutch.cli.plots.haptic as haptic_plots

    figs, draws, real, real_draw = [], [], haptic_plots.save_png, Figure.draw

    def keep(fig, out, dpi=110, relayout=None):
        figs.append(fig)
        return real(fig, out, dpi=dpi, relayout=relayout)

    monkeypatch.setattr(haptic_plots, "save_png", keep)
    monkeypatch.setattr(Figure, "draw", lambda self, r: (draws.append(self), real_draw(self, r)))
    return figs, draws


def _overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def _inside_and_apart(fig):
    """Every panel's text (ticks, labels, title, legend) and the figure's title inside the
    figure, no two panels' text overlapping, the title over none (drawn again on a canvas
    of its own: ``save_png`` closed it)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    boxes = [ax.get_tightbbox(renderer) for ax in fig.axes]
    if fig._suptitle is not None:
        boxes.append(fig._suptitle.get_window_extent(renderer))
    for i, a in enumerate(boxes):
        assert page.x0 - 0.5 <= a.x0 and a.x1 <= page.x1 + 0.5, (i, a, page)
        assert page.y0 - 0.5 <= a.y0 and a.y1 <= page.y1 + 0.5, (i, a, page)
        for b in boxes[i + 1 :]:
            assert not _overlap(a, b), (a, b)


def _figures(paper, tmp_path, monkeypatch, k_factor):
    from mrclutch.cli.plots.haptic import compare_figure, zwidth_figure

    ev, k = paper
    figs, draws = _drawn(monkeypatch)
    sides = {"MR pair": ev.mr, "Maxon 136206 (equal force)": ev.motor}
    compare_figure(sides, k * k_factor, tmp_path / "haptic.png")
    zw = {"MR pair": ev.zwidth["mr"], "Maxon 136206 (equal force)": ev.zwidth["motor"]}
    zwidth_figure(zw, k * k_factor, tmp_path / "zwidth.png")
    return figs, draws


def test_the_paper_figures_are_drawn_once_in_their_fixed_layout(paper, tmp_path, monkeypatch):
    figs, draws = _figures(paper, tmp_path, monkeypatch, 1.0)
    assert len(figs) == 2 and draws == figs  # each drawn once
    for fig in figs:
        assert fig.get_layout_engine() is None
        _inside_and_apart(fig)
    haptic, zwidth = figs
    # the legend of both sides' two curves above the |Z| panel, under the figure's title
    legend = haptic.axes[0].get_legend().get_window_extent(haptic.canvas.get_renderer())
    assert len(haptic.axes[0].get_legend().get_texts()) == 4
    assert haptic.axes[0].get_window_extent().y1 <= legend.y0 + 1
    assert legend.y1 <= haptic._suptitle.get_window_extent(haptic.canvas.get_renderer()).y0
    assert len(zwidth.axes) == 2


def test_text_wider_than_the_margins_is_laid_out_by_constrained_layout(paper, tmp_path,
                                                                     monkeypatch):  # fmt: skip
    """At 30 K the stiffness panel's tick labels (−20000) are wider than the fixed left
    margin: drawn there, its label would leave the figure; the figure is laid out by
    constrained layout and drawn again, everything inside."""
    from mrclutch.cli.plots import text_fits

    figs, draws = _figures(paper, tmp_path, monkeypatch, 30.0)
    haptic, zwidth = figs
    assert draws == [haptic, haptic, zwidth]
    assert haptic.get_layout_engine() is not None and zwidth.get_layout_engine() is None
    _inside_and_apart(haptic)
    assert text_fits(haptic)
    _inside_and_apart(zwidth)


def test_text_fits_sees_a_label_outside_the_figure():
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from mrclutch.cli.plots import stack_axes, text_fits

    fig = Figure(figsize=(4, 3))
    FigureCanvasAgg(fig)
    ax = fig.subplots(1, 1)
    ax.set_ylim(-1e5, 1e5)
    ax.set_ylabel("a label")
    stack_axes(fig, 1, (1.0, 0.2, 0.5, 0.2), 0.0)
    fig.canvas.draw()
    assert text_fits(fig)
    stack_axes(fig, 1, (0.4, 0.2, 0.5, 0.2), 0.0)  # no room for "−100000" and the label
    fig.canvas.draw()
    assert not text_fits(fig)
    ax.set_ylabel("")
    ax.set_yticks([0], ["0"])
    ax.set_title("a title far too long to fit the width of this small figure at all")
    fig.canvas.draw()
    assert not text_fits(fig)  # the title, not an axis


def test_the_other_report_figures_fit_their_fixed_margins(paper, tmp_path, monkeypatch):
    """The section drawing, torque curve and step response (fixed margins instead of
    constrained or tight layout, issue 40) of the paper preset: drawn once, no layout
    engine, every text inside the figure."""
    import numpy as np
    from matplotlib.figure import Figure

    import mrclutch.cli.plots.design as design_plots
    import mrclutch.cli.plots.dynamics as dynamics_plots
    import mrclutch.cli.plots.magnetics as magnetics_plots
    from magnetics.torque import torque_curve

    ev, _ = paper
    design = design_preset("paper")
    sec = design.section()
    figs, draws, real_draw = [], [], Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, r: (draws.append(self), real_draw(self, r)))
    for module in (design_plots, dynamics_plots, magnetics_plots):
        real = module.save_png

        def keep(fig, out, dpi=110, relayout=None, real=real):
            figs.append(fig)
            return real(fig, out, dpi=dpi, relayout=relayout)

        monkeypatch.setattr(module, "save_png", keep)
    design_plots.section_figure(sec, tmp_path / "section.png")
    curve = torque_curve(sec, np.linspace(0.0, 7.0, 8), method="circuit")
    magnetics_plots.plot_torque([curve], tmp_path / "torque.png", title="paper at 530 rpm")
    dynamics_plots.plot_torque_step([("paper", ev.torque_response)], tmp_path / "response.png",
                                    typed_delay=design.operating.delay)  # fmt: skip
    assert len(figs) == 3 and draws == figs
    for fig in figs:
        assert fig.get_layout_engine() is None
        _inside_and_apart(fig)


def test_pngs_are_written_at_the_fast_compression_level(tmp_path):
    """save_png's PNG_COMPRESS_LEVEL (3: zlib's 'fast' class in the stream header, 6 would
    be 'default'); the pixels are savefig's (test_plots_text), PNG being lossless."""
    import struct

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mrclutch.cli.plots import PNG_COMPRESS_LEVEL, save_png

    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1], [1, 0])
    data = save_png(fig, tmp_path / "f.png", dpi=80).read_bytes()
    pos = 8
    while True:  # the first IDAT chunk: its zlib stream's header
        n, kind = struct.unpack(">I4s", data[pos : pos + 8])
        if kind == b"IDAT":
            break
        pos += 12 + n
    flevel = data[pos + 9] >> 6  # RFC 1950: FLG's two top bits
    assert PNG_COMPRESS_LEVEL == 3 and flevel == 1
