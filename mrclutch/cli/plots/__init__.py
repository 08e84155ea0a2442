"""matplotlib figures, one module per subject (haptic, magnetics, design). Each module
imports matplotlib inside its functions with the non-interactive Agg backend, so the
library never opens a window and never pays for matplotlib unless it draws.

Every figure is saved by :func:`save_png`: atomically, and with the height of its smallest
text in image pixels in the PNG's metadata (``mrclutch:min_text_px``), so a test can check
how tall that text is on a screen of a given width (the report at 500 px: ≥ 9 px). Figures
are drawn about 6 in wide with text of at least 9 pt for that reason.
"""

from __future__ import annotations

import os
import struct
import sys
import zlib
from pathlib import Path
from typing import Any

from geometry.atomic import atomic_path

#: PNG text key of the smallest text's height (font size) in image pixels.
MIN_TEXT_KEY = "mrclutch:min_text_px"
#: zlib level of the PNGs written (Pillow's default: 6). The same pixels (PNG is lossless)
#: in ~0.6x the encoding time and ~8 % more bytes on the report's six figures (issue 40).
PNG_COMPRESS_LEVEL = 3


def min_text_px(fig: Any, dpi: float) -> float:
    """Font size in pixels of the smallest visible, non-empty text of ``fig``."""
    fig.canvas.draw()  # tick labels exist only once drawn
    return drawn_min_text_px(fig, dpi)


def drawn_min_text_px(fig: Any, dpi: float) -> float:
    """:func:`min_text_px` of a figure already drawn (its text as that draw laid it out)."""
    sizes = [t.get_fontsize() for t in fig.findobj(lambda a: hasattr(a, "get_text")
             and hasattr(a, "get_fontsize")) if t.get_visible() and t.get_text().strip()
             and _on_canvas(t)]  # fmt: skip
    return min(sizes) * dpi / 72 if sizes else float("inf")


def _on_canvas(t: Any) -> bool:
    """Tick labels outside the axis limits are kept by matplotlib but not drawn."""
    try:
        bb = t.get_window_extent()
    except (RuntimeError, ValueError):
        return False
    return bb.width > 0 and bb.height > 0


def text_fits(fig: Any) -> bool:
    """Whether the text of ``fig`` as last drawn lies inside the figure (half a pixel of
    slack): each axes' x and y axis (tick labels, label, offset), title and legend, and the
    figure's own text (its title). Their extents only, not every line's: a layout engine
    measures those too, on every pass."""
    from matplotlib.text import Text

    r = fig.canvas.get_renderer()
    axes = [a for ax in fig.axes for a in (ax.xaxis, ax.yaxis) if _has_text(a)]
    boxes = [b for a in axes if (b := a.get_tightbbox(r)) is not None]
    for ax in fig.axes:
        shown = [ax.title, ax.get_legend()] if ax.get_title() else [ax.get_legend()]
        boxes += [a.get_window_extent(r) for a in shown if a is not None]
    boxes += [t.get_window_extent(r) for t in fig.get_children()
              if isinstance(t, Text) and t.get_visible() and t.get_text()]  # fmt: skip
    page, slack = fig.bbox, 0.5
    return all(page.x0 - slack <= b.x0 and b.x1 <= page.x1 + slack and
               page.y0 - slack <= b.y0 and b.y1 <= page.y1 + slack for b in boxes)  # fmt: skip


def _has_text(axis: Any) -> bool:
    """Whether an axis draws text: its tick labels (off on a shared axis but the bottom
    one) or its label."""
    on = axis.get_tick_params(which="major")
    return any(on.get(k, False) for k in ("labelbottom", "labeltop", "labelleft",
                                          "labelright")) or bool(axis.label.get_text())  # fmt: skip


def stack_axes(fig: Any, rows: int, margins: tuple[float, float, float, float],
               gap: float) -> None:  # fmt: skip
    """A fixed layout (issue 40: a layout engine measures every tick label in extra passes
    before the one draw) of a figure's ``rows`` subplots in one column: equal heights,
    ``margins`` (left, right, bottom, top) from the figure's edges and ``gap`` between
    them, all in inches (``subplots_adjust``: a layout engine set later lays them out
    anew)."""
    left, right, bottom, top = margins
    w, h = fig.get_size_inches()
    height = (h - bottom - top - (rows - 1) * gap) / rows
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        hspace=gap / height)  # fmt: skip


def save_png(fig: Any, path: str | os.PathLike[str], dpi: float = 110,
             relayout: str | None = None) -> Path:  # fmt: skip
    """``fig`` as a PNG at ``path`` through the output layer (temporary file, fsync,
    rename; one OutputError line on any OSError) with its smallest text size in the
    metadata, then closed whatever happened.

    The figure is drawn once: its layout engine runs, its text is measured and its pixels
    are written from that one draw (what ``savefig`` does after its own draws: Agg's
    ``print_png`` draws the canvas and writes ``buffer_rgba`` with ``imsave``), instead of
    a draw to measure and ``savefig``'s layout pass and draw (issue 40: the report).
    ``relayout``: a layout engine ("constrained") for a figure laid out by hand
    (``stack_axes``) whose text, as drawn, does not fit inside it (``text_fits``: a
    design's tick labels wider than its margin): laid out by that engine and drawn again."""
    from matplotlib.image import imsave

    try:
        fig.set_dpi(dpi)
        fig.canvas.draw()
        if relayout is not None and not text_fits(fig):
            fig.set_layout_engine(relayout)
            fig.canvas.draw()
        px = drawn_min_text_px(fig, dpi)
        with atomic_path(path) as tmp:
            imsave(tmp, fig.canvas.buffer_rgba(), format="png", origin="upper", dpi=dpi,
                   metadata={MIN_TEXT_KEY: f"{px:.2f}"},
                   pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})  # fmt: skip
    finally:
        # a pyplot figure leaves pyplot's list; a figure made without pyplot (the sweep
        # plot) is in no list, and pyplot's import is ~0.06 s of a fresh process (issue 40)
        plt = sys.modules.get("matplotlib.pyplot")
        if plt is not None:
            plt.close(fig)
    return Path(path)


def read_min_text_px(path: str | os.PathLike[str]) -> float | None:
    """The ``mrclutch:min_text_px`` a PNG carries, or None (read with the stdlib)."""
    data = Path(path).read_bytes()
    pos = 8
    while pos + 8 <= len(data):
        n, kind = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + n]
        if kind in (b"tEXt", b"zTXt", b"iTXt"):
            key, _, rest = body.partition(b"\0")
            if key.decode("latin-1") == MIN_TEXT_KEY:
                if kind == b"zTXt":
                    rest = zlib.decompress(rest[1:])
                elif kind == b"iTXt":
                    rest = rest[2:].split(b"\0", 2)[-1]
                return float(rest.decode("latin-1"))
        if kind == b"IEND":
            break
        pos += 12 + n
    return None
