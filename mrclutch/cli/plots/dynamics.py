"""Torque response figure: the step response of current command → torque (Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mrclutch.cli.plots import save_png, stack_axes

#: Inches: the fixed layout's margins (left, right, bottom, top; ``stack_axes``, issue 40):
#: the y label and 3-character tick labels, half the last x tick label, the x tick labels
#: and label, the title. Text that does not fit: tight layout (``save_png``'s ``relayout``).
MARGINS = (0.72, 0.2, 0.58, 0.36)


def plot_torque_step(
    responses: Sequence[tuple[str, Any]], path: str | Path, typed_delay: float | None = None
) -> None:
    """Torque/final torque after a current-command step, for (label, TorqueResponse of one
    design) pairs, each beside the pure delay τ_eq that stands for it in the haptic model;
    ``typed_delay`` [s]: a design's typed delay, drawn as a step for comparison."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t_end = 4 * max(float(r.equivalent_delay[0]) for _, r in responses)
    t = np.linspace(0.0, t_end, 400)
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, r in responses:
        (line,) = ax.plot(t * 1e3, r.step(t)[0], label=f"{label}: lags")
        tau = float(r.equivalent_delay[0])
        ax.plot([0, tau * 1e3, tau * 1e3, t_end * 1e3], [0, 0, 1, 1], "--", color=line.get_color(),
                label=f"{label}: τ_eq = {tau * 1e3:.3g} ms")  # fmt: skip
    if typed_delay is not None:
        d = typed_delay * 1e3
        ax.plot([0, d, d, t_end * 1e3], [0, 0, 1, 1], ":k", label=f"typed delay {d:.3g} ms")
    ax.set_xlabel("time after the current command (ms)")
    ax.set_ylabel("torque / final torque")
    ax.grid(True, alpha=0.3)
    ax.set_title("torque after a step of the current command to the peak", fontsize=11)
    ax.legend(fontsize=9)
    stack_axes(fig, 1, MARGINS, 0.0)
    save_png(fig, path, dpi=120, relayout="tight")
