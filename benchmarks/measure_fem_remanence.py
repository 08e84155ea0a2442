"""The residual torque at 0 A after a peak current: the FEM with the steel's coercive
magnetisation (magnetics/fem/remanence.py) against magnetics.hysteresis's network answer
(the single-valued yield torque at the coercive current I_c), on the paper preset and on
a design where it is not negligible (0.15 mm gaps, steel 1117 in core, drums and shell).
Also the FEM's own single-valued torque at I_c (the torque model's share of the
difference) and the 7 A torque (the residual's share of full scale). Prints JSON
(docs/hysteresis.md quotes it through docs/figures.toml).

    python benchmarks/measure_fem_remanence.py            # ~30 s on a 2-core machine
    python benchmarks/measure_fem_remanence.py --size-mm 0.25   # the mesh check
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from geometry.materials import MaterialChoice
from geometry.params import preset
from geometry.section import build_section
from magnetics.circuit import path_from_section
from magnetics.fem.remanence import solve_remanent
from magnetics.hysteresis import coercive_current
from magnetics.torque import torque_curve

PEAK = 7.0  # A: the paper's current limit
HARD_STEEL = MaterialChoice(core="steel_1117", drums="steel_1117", shell="steel_1117")
CASES = {  # name -> (geometry, materials)
    "paper": (preset("paper"), MaterialChoice()),
    "thin_gaps_1117": (replace(preset("paper"), gap=0.15e-3), HARD_STEEL),
}


def measure(size: float) -> dict[str, dict[str, float]]:
    """Per case: I_c (A), the network's and the FEM's residual torque (N·m), their ratio,
    the FEM's single-valued torque at I_c and the network's torque at the peak."""
    out = {}
    for name, (clutch, materials) in CASES.items():
        sec = build_section(clutch, materials)
        ic = float(coercive_current(path_from_section(sec), [PEAK])[0])
        net = torque_curve(sec, np.array([ic, PEAK]), method="network").yield_torque
        fem_ic = torque_curve(sec, np.array([ic]), method="fem", fem_size=size).yield_torque[0]
        rem = solve_remanent(sec, PEAK, size=size)
        out[name] = {
            "coercive_current_A": ic,
            "network_residual_N_m": float(net[0]),
            "fem_residual_N_m": rem.residual_torque,
            "network_over_fem": float(net[0]) / rem.residual_torque,
            "fem_single_valued_at_ic_N_m": float(fem_ic),
            "peak_torque_N_m": float(net[1]),
            "fem_residual_pct_of_peak": 100.0 * rem.residual_torque / float(net[1]),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size-mm", type=float, default=0.5, help="FEM element size (mm)")
    args = ap.parse_args()
    print(json.dumps({"size_mm": args.size_mm, "peak_A": PEAK, **measure(args.size_mm * 1e-3)},
                     indent=2))  # fmt: skip


if __name__ == "__main__":
    main()
