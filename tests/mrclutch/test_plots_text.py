"""Figures record their smallest text (issue 34): what the browser test scales to screen px."""

import pytest

from mrclutch.cli.plots import MIN_TEXT_KEY, read_min_text_px, save_png


def test_smallest_text_in_pixels_is_written_and_read_back(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1], label="a line")
    ax.legend(fontsize=7)
    ax.set_xlabel("x", fontsize=14)
    ax.tick_params(labelsize=11)
    ax.text(0.5, 0.5, "   ", fontsize=3)  # blank: not text anyone reads
    path = save_png(fig, tmp_path / "f.png", dpi=100)
    plt.close(fig)
    assert read_min_text_px(path) == pytest.approx(7 * 100 / 72, abs=0.01)  # the legend
    assert MIN_TEXT_KEY.encode() in path.read_bytes()


def test_a_figure_is_drawn_once_into_the_pixels_savefig_writes(tmp_path, monkeypatch):
    """save_png measures the text and writes the pixels of one draw (issue 40: it drew
    each figure twice): the same image as ``savefig`` at that dpi, for a fixed layout."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure
    from matplotlib.image import imread

    def figure():
        fig, ax = plt.subplots(figsize=(4, 3))
        ax.plot([0, 1, 2], [0, 1, 4], "o-", label="a curve")
        ax.set_xlabel("current (A)")
        ax.legend(fontsize=9)
        fig.tight_layout()
        return fig

    ref = figure()
    ref.savefig(tmp_path / "ref.png", dpi=120)
    plt.close(ref)
    draws = []
    real_draw = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, r: (draws.append(1), real_draw(self, r)))
    path = save_png(figure(), tmp_path / "f.png", dpi=120)
    assert len(draws) == 1
    got, want = imread(path), imread(tmp_path / "ref.png")
    assert got.shape == want.shape == (360, 480, 4) and (got == want).all()
    assert read_min_text_px(path) == pytest.approx(9 * 120 / 72, abs=0.01)  # the legend


def test_a_png_without_the_key_reads_none(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, _ = plt.subplots()
    fig.savefig(tmp_path / "plain.png")
    plt.close(fig)
    assert read_min_text_px(tmp_path / "plain.png") is None
