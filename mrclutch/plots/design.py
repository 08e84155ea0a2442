"""Figures of design sweeps: the Pareto front of bandwidth, torque and drag."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geometry.atomic import atomic_path


def read_results(path: str | Path) -> dict[str, np.ndarray]:
    """A sweep CSV as columns of floats (empty cells → NaN)."""
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=float, ndmin=1)
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


def pareto_plot(results: str | Path, out: str | Path) -> Path:
    """Bandwidth against max torque and against off-state damping, mass as colour,
    the non-dominated designs (max bandwidth, max torque, min damping) outlined."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mrclutch.sweep import pareto_front

    r = read_results(results)
    ok = r["valid"] == 1
    bw, tq = r["bandwidth_hz"][ok], r["max_torque_N_m"][ok]
    damp, mass = r["damping_N_m_s"][ok], r["clutch_mass_kg"][ok] * 1e3
    front = pareto_front(np.column_stack([bw, tq, damp]), [True, True, False])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    for ax, x, label in (
        (axes[0], tq, "max torque (N·m)"),
        (axes[1], damp * 1e6, "viscous damping (µN·m·s)"),
    ):
        sc = ax.scatter(x, bw, c=mass, s=6, cmap="viridis", alpha=0.6, linewidths=0)
        ax.scatter(x[front], bw[front], s=22, facecolors="none", edgecolors="crimson",
                   linewidths=0.8, label=f"Pareto front ({front.sum()})")  # fmt: skip
        ax.set_xlabel(label)
        ax.set_ylabel("rendering bandwidth at K_max (Hz)")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    fig.colorbar(sc, ax=axes, label="clutch mass (g)")
    fig.suptitle(f"{ok.sum()} valid designs of {ok.size}")
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=120, format="png")
    plt.close(fig)
    return Path(out)
