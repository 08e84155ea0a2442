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
import zlib
from pathlib import Path
from typing import Any

from geometry.atomic import atomic_path

#: PNG text key of the smallest text's height (font size) in image pixels.
MIN_TEXT_KEY = "mrclutch:min_text_px"


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


def save_png(fig: Any, path: str | os.PathLike[str], dpi: float = 110) -> Path:
    """``fig`` as a PNG at ``path`` through the output layer (temporary file, fsync,
    rename; one OutputError line on any OSError) with its smallest text size in the
    metadata, then closed whatever happened.

    The figure is drawn once: its layout engine runs, its text is measured and its pixels
    are written from that one draw (what ``savefig`` does after its own draws: Agg's
    ``print_png`` draws the canvas and writes ``buffer_rgba`` with ``imsave``), instead of
    a draw to measure and ``savefig``'s layout pass and draw (issue 40: the report)."""
    import matplotlib.pyplot as plt
    from matplotlib.image import imsave

    try:
        fig.set_dpi(dpi)
        fig.canvas.draw()
        px = drawn_min_text_px(fig, dpi)
        with atomic_path(path) as tmp:
            imsave(tmp, fig.canvas.buffer_rgba(), format="png", origin="upper", dpi=dpi,
                   metadata={MIN_TEXT_KEY: f"{px:.2f}"})  # fmt: skip
    finally:
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
