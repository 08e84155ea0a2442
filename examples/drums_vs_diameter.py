"""Drum count against drum diameter: torque, inertia and bandwidth.

More drums or a larger diameter both raise the torque; they raise the rotor inertia
differently (I ∝ r³ per drum). A grid on the fast path, one curve per drum count.

    python examples/drums_vs_diameter.py [OUT_DIR] [--tiny]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from mrclutch.design import design_preset
from mrclutch.pipeline import evaluate_batch


def main(out_dir: str = "out/drums_vs_diameter", tiny: bool = False) -> dict[str, np.ndarray]:
    counts = np.arange(1, 3 if tiny else 5)
    diam = np.linspace(8e-3, 16e-3, 3 if tiny else 40)
    N, D = np.meshgrid(counts, diam, indexing="ij")
    r = evaluate_batch({"n_drums": N.ravel(), "drum_inner_diameter": D.ravel()},
                       design_preset("paper"))  # fmt: skip

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4), constrained_layout=True)
    for i, n in enumerate(counts):
        sl = slice(i * diam.size, (i + 1) * diam.size)
        for ax, key, scale in zip(axes, ("max_torque_N_m", "rotor_inertia_kg_m2", "bandwidth_hz"),
                                  (1, 1e7, 1), strict=True):  # fmt: skip
            ax.plot(diam * 1e3, r[key][sl] * scale, label=f"{n} drum(s)")
    for ax, label in zip(axes, ("max torque (N·m)", "rotor inertia (g·cm²)",
                                "bandwidth at K_max (Hz)"), strict=True):  # fmt: skip
        ax.set_xlabel("inner diameter of the first drum (mm)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend()
    fig.savefig(out / "drums_vs_diameter.png", dpi=110)
    plt.close(fig)
    print(f"{N.size} designs; torque {np.nanmin(r['max_torque_N_m']):.3g}–"
          f"{np.nanmax(r['max_torque_N_m']):.3g} N·m")  # fmt: skip
    return r


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--tiny"]
    main(*args[:1], tiny="--tiny" in sys.argv)
