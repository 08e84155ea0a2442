"""Haptic figures: impedance Bode magnitude with rendering areas, effective stiffness and
damping (matplotlib imported inside, Agg backend)."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from mrclutch.cli.plots import save_png, stack_axes
from mrclutch.impedance import band_frequencies, impedance_curves

#: Inches: both figures' fixed margins (left, right, bottom) beside and below the panels
#: (``stack_axes``; issue 40): left the y label and tick labels of up to five characters
#: ("−1000", "10000"), right half of the last x tick label, below the x tick labels and
#: label. A design whose tick labels do not fit is laid out by constrained layout instead
#: (``save_png``'s ``relayout``).
LEFT, RIGHT, BOTTOM = 0.8, 0.25, 0.55
#: Inches: above the |Z| panel, the figure's title; each line of the legend above it, and
#: the legend's border; between the three panels, which share their x axis.
TITLE, LEGEND_LINE, LEGEND_PAD, SHARED_GAP = 0.4, 0.19, 0.1, 0.12
#: Inches: above each Z-width panel its title; between them the upper one's x tick labels
#: and label and the lower one's title.
PANEL_TITLE, PANEL_GAP = 0.3, 0.85


def compare_figure(
    sides: dict[str, Any],
    K: float,
    path: str | os.PathLike[str],
    band: tuple[float, float] | None = None,
) -> None:
    """Write a PNG comparing designs (label → HapticParams) rendering a spring K [N/m].

    Top: |Z| of the closed loop (solid) and the passive device (dashed, Eq. 2) with the
    rendering area shaded over the band and the full-model bandwidth marked. Bottom:
    effective stiffness k_eff = Re(jωZ) and effective damping b_eff = Re Z.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = band_frequencies(band)
    fig, axes = plt.subplots(3, 1, figsize=(6, 8.4), sharex=True)
    legend_lines = 2 * min(len(sides), 3)  # closed loop and passive, of each side drawn
    top = TITLE + legend_lines * LEGEND_LINE + LEGEND_PAD
    stack_axes(fig, 3, (LEFT, RIGHT, BOTTOM, top), SHARED_GAP)
    ax_z, ax_k, ax_b = axes
    colors = ("tab:blue", "tab:red", "tab:green")
    for j, ((label, p), color) in enumerate(zip(sides.items(), colors, strict=False)):
        c = impedance_curves(p, K, f, band)
        zc, zp, area, bw = c["closed"], c["passive"], c["area"], c["bandwidth"]
        ax_z.loglog(f, zc, color=color, label=f"{label}: closed loop, area {area:.1f} dB·dec")
        ax_z.loglog(f, zp, "--", color=color, label=f"{label}: passive (Eq. 2)")
        ax_z.fill_between(f, zp, zc, where=zc > zp, color=color, alpha=0.15)
        if np.isfinite(bw):
            for ax in axes:
                ax.axvline(bw, color=color, lw=0.8, ls=":")
            # each design's label on its own height (bandwidths close together stay legible)
            ax_z.annotate(f" {bw:.1f} Hz", (bw, 0.03 + 0.08 * j), color=color, fontsize=9,
                          xycoords=ax_z.get_xaxis_transform())  # fmt: skip
        ax_k.semilogx(f, c["stiffness"], color=color, label=label)
        ax_b.semilogx(f, c["damping"], color=color, label=label)
    ax_k.axhline(K, color="0.5", lw=0.8, label=f"K = {K:.0f} N/m")
    ax_k.axhline(0.0, color="k", lw=0.5)
    ax_z.set_ylabel("|Z| = |F/ẋ| [N·s/m]")
    fig.suptitle(f"Rendering K = {K:.0f} N/m (dotted: bandwidth)", fontsize=11)
    ax_k.set_ylabel("effective stiffness [N/m]")
    ax_k.set_ylim(-2 * K, 2 * K)
    ax_b.set_ylabel("effective damping [N·s/m]")
    ax_b.set_xlabel("frequency [Hz]")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    # the |Z| legend above its panel: inside, it covered the low-frequency curves
    ax_z.legend(fontsize=9, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=1, frameon=False)
    ax_k.legend(fontsize=9)
    ax_b.legend(fontsize=9)
    save_png(fig, path, dpi=110, relayout="constrained")


def zwidth_figure(sides: dict[str, dict[str, Any]], K: float, path: str | os.PathLike[str]) -> None:
    """Write a PNG of the Z-width (label → ``zwidth`` result of one design): the passive set
    {K_min(B) ≤ K ≤ K_max(B)} in the (K, B) plane, one panel per side (their scales differ
    by orders of magnitude), with the rendered spring (K, 0) marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(sides), 1, figsize=(6, 3.6 * len(sides)))
    stack_axes(fig, len(sides), (LEFT, RIGHT, BOTTOM, PANEL_TITLE), PANEL_GAP)
    colors = ("tab:blue", "tab:red", "tab:green")
    for ax, (label, zw), color in zip(np.atleast_1d(axes), sides.items(), colors, strict=False):
        b = np.asarray(zw["B_N_s_per_m"], dtype=float)
        hi = np.asarray(zw["K_max_N_per_m"], dtype=float)
        lo = np.nan_to_num(np.asarray(zw["K_min_N_per_m"], dtype=float), nan=0.0)
        ok = np.isfinite(hi)
        ax.fill_betweenx(b[ok], lo[ok], hi[ok], color=color, alpha=0.25, label="passive")
        ax.plot(hi[ok], b[ok], color=color, lw=1.5, label="K_max(B)")
        if np.any(lo[ok] > 0):
            ax.plot(lo[ok], b[ok], color=color, lw=1.0, ls="--", label="K_min(B)")
        ax.plot([K], [0.0], "kx", ms=8, label=f"rendered K = {K:.0f} N/m")
        area = float(zw["zwidth_area_N2_s_per_m2"])
        if np.isfinite(area):
            ax.set_title(f"{label}: area {area:.4g} N²·s/m²", fontsize=10)
        else:  # no delay: a damper alone is passive at any B (zwidth module docstring)
            ax.set_title(f"{label}: unbounded in B", fontsize=10)
            ax.axvline(float(zw["K_max_at_B0_N_per_m"]), color=color, lw=1.5,
                       label="K_max at B = 0")  # fmt: skip
        ax.set_xlabel("virtual stiffness K [N/m]")
        ax.set_ylabel("virtual damping B [N·s/m]")
        ax.set_xlim(0, 1.1 * max(float(np.nanmax(hi[ok], initial=0.0)), K))
        ax.set_ylim(0, None)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=9)
    save_png(fig, path, dpi=110, relayout="constrained")
