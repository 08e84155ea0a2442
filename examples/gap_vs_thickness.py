"""Gap against drum thickness: what the hand gains and loses.

A grid over the fluid gap and the drum thickness of the paper clutch, on the vectorised
fast path, then two maps: rendering bandwidth at K_max and the reflected damping b1.
Thin drums lower the inertia; small gaps raise the torque (so K_max) but also the drag.

    python examples/gap_vs_thickness.py [OUT_DIR] [--tiny]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from mrclutch.design import design_preset
from mrclutch.pipeline import evaluate_batch


def main(out_dir: str = "out/gap_vs_thickness", tiny: bool = False) -> dict[str, np.ndarray]:
    n = 4 if tiny else 60
    gaps = np.linspace(0.2e-3, 1.0e-3, n)
    thick = np.linspace(0.1e-3, 0.6e-3, n)
    G, T = np.meshgrid(gaps, thick, indexing="ij")
    r = evaluate_batch({"gap": G.ravel(), "drum_thickness": T.ravel()}, design_preset("paper"))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    for ax, key, label in (
        (axes[0], "bandwidth_hz", "rendering bandwidth at K_max (Hz)"),
        (axes[1], "b1_N_s_per_m", "reflected damping b1 (N·s/m)"),
    ):
        m = ax.pcolormesh(thick * 1e3, gaps * 1e3, r[key].reshape(G.shape), shading="auto")
        fig.colorbar(m, ax=ax, label=label)
        ax.set_xlabel("drum thickness (mm)")
        ax.set_ylabel("gap (mm)")
    fig.savefig(out / "gap_vs_thickness.png", dpi=110)
    plt.close(fig)
    best = int(np.nanargmax(r["bandwidth_hz"]))
    print(
        f"{G.size} designs; best bandwidth {r['bandwidth_hz'][best]:.1f} Hz at gap "
        f"{G.ravel()[best] * 1e3:.2f} mm, drum {T.ravel()[best] * 1e3:.2f} mm"
    )
    return r


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--tiny"]
    main(*args[:1], tiny="--tiny" in sys.argv)
