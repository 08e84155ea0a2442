"""matplotlib figures, one module per subject (haptic, magnetics, design). Each module
imports matplotlib inside its functions with the non-interactive Agg backend, so the
library never opens a window and never pays for matplotlib unless it draws."""

from __future__ import annotations

import os
from typing import Any

from geometry.atomic import atomic_path


def save_png(fig: Any, path: str | os.PathLike[str], dpi: int) -> None:
    """``fig`` as a PNG at ``path`` through the output layer (temporary file, fsync,
    rename; one OutputError line on any OSError), then closed whatever happened."""
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=dpi)
    finally:
        plt.close(fig)
