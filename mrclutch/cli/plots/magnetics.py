"""Magnetics figures: torque–current curves and the |B| map of the section (Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mrclutch.cli.plots import save_png, stack_axes

#: Inches: the torque curve's fixed layout's margins (left, right, bottom, top;
#: ``stack_axes``, issue 40): the y label and 4-character tick labels, half the last x tick
#: label, the x tick labels and label, the title. Text that does not fit: tight layout
#: (``save_png``'s ``relayout``).
TORQUE_MARGINS = (0.72, 0.2, 0.55, 0.36)


def plot_torque(curves: Sequence[Any], path: str | Path, title: str = "") -> None:
    """Torque (N·m) against current (A) for one or more TorqueCurve objects."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for tc in curves:
        ax.plot(tc.currents, tc.torque, "o-", ms=3, label=f"{tc.method} ({tc.speed_rpm:g} rpm)")
    ax.set_xlabel("current (A)")
    ax.set_ylabel("torque (N·m)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    if title:
        ax.set_title(title)
    left, right, bottom, top = TORQUE_MARGINS
    stack_axes(fig, 1, (left, right, bottom, top if title else 0.15), 0.0)
    save_png(fig, path, dpi=120, relayout="tight")


def plot_field(section: Any, sol: Any, path: str | Path) -> None:
    """|B| over the section (element centres) with region outlines; saturation shows as
    the colour reaching the steel's knee (≈ 1.6 T for 1018)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    r, z = sol.r_nodes, sol.z_nodes
    keep_r = r <= section.r_max * 1.3
    keep_z = (z >= section.z_min - 3e-3) & (z <= section.z_max + 3e-3)
    nr, nz = r.size - 1, z.size - 1
    grid = np.full((nz, nr), np.nan)
    ir = np.searchsorted(r, sol.centre_r) - 1
    iz = np.searchsorted(z, sol.centre_z) - 1
    grid[iz, ir] = sol.b
    fig, ax = plt.subplots(figsize=(6, 6))
    m = ax.pcolormesh(r * 1e3, z * 1e3, grid, cmap="inferno", vmin=0, vmax=2.2)
    fig.colorbar(m, ax=ax, label="|B| (T)")
    for g in section.regions:
        if g.part != "fluid":
            ax.add_patch(Rectangle((g.r0 * 1e3, g.z0 * 1e3), (g.r1 - g.r0) * 1e3,
                                   (g.z1 - g.z0) * 1e3, fill=False, lw=0.4, ec="w"))  # fmt: skip
    ax.set_xlim(0, r[keep_r][-1] * 1e3)
    ax.set_ylim(z[keep_z][0] * 1e3, z[keep_z][-1] * 1e3)
    ax.set_aspect("equal")
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title(f"|B| at {sol.current:g} A (max {sol.b.max():.2f} T)")
    fig.tight_layout()
    save_png(fig, path, dpi=120)
