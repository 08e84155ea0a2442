"""The runout ripple's gap derivatives: the reluctance network's dT/dg and d²T/dg²
(magnetics/ripple.py, what the ripple figures use) against central differences of the
FEM's torque over the gap on grids moved with the geometry (magnetics/fem/gap_shape.py),
on the paper preset and its 1- and 5-drum variants at 2 A and 7 A. Also each torque,
the log-sensitivities S = (g/T)·dT/dg, their difference and the tolerance the test holds
it to (2B/DELTA_LN_GAP, B the network's error bound at the design,
magnetics.network_bound). Prints JSON (docs/hysteresis.md quotes it via docs/figures.toml).

    python benchmarks/measure_fem_ripple.py                 # FEM at 0.25 mm, ~1 min
    python benchmarks/measure_fem_ripple.py --size-mm 0.5   # the test's mesh
    python benchmarks/measure_fem_ripple.py --scan          # the network's error over the gap
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from geometry.params import preset
from geometry.section import build_section
from magnetics.fem.gap_shape import fem_gap_derivatives
from magnetics.network_bound import network_bound
from magnetics.ripple import gap_derivatives
from magnetics.torque import torque_curve

CURRENTS = (2.0, 7.0)  # A: low field and the paper's current limit
DESIGNS = {"paper": 2, "one_drum": 1, "five_drums": 5}  # name -> n_drums (the rest: paper)
#: The change of ln g over which the network's relative torque error against the FEM swings
#: through its band on the paper preset at 7 A (``--scan`` at 0.5 mm: 4.0 % at 0.55 mm down
#: to 2.0 % at 0.85 mm, ln(0.85/0.55) = 0.435): an error bounded by ±B that crosses its band
#: over that change can tilt the log-sensitivity by up to 2B/0.435.
DELTA_LN_GAP = 0.435


def design(name: str):  # type: ignore[no-untyped-def]
    return replace(preset("paper"), n_drums=DESIGNS[name])


def compare(name: str, size: float) -> dict[str, dict[str, float]]:
    """Per current: the network's and the FEM's T, dT/dg, d²T/dg², S and the tolerance."""
    c = design(name)
    fem = fem_gap_derivatives(c, CURRENTS, size=size)
    fields = {k: v for k, v in vars(c).items() if isinstance(v, int | float)}
    out = {}
    for k, current in enumerate(CURRENTS):
        net = gap_derivatives(c, current)
        s_net = c.gap * net.first / net.torque
        s_fem = c.gap * float(fem.first[k]) / float(fem.torque[k])
        bound = float(network_bound(fields, current)[1])
        out[f"{current:g}A"] = {
            "network_T_N_m": net.torque,
            "fem_T_N_m": float(fem.torque[k]),
            "network_dT_dg_N_m_per_m": net.first,
            "fem_dT_dg_N_m_per_m": float(fem.first[k]),
            "dT_dg_difference_pct": 100.0 * (net.first / float(fem.first[k]) - 1.0),
            "network_d2T_dg2_N_m_per_m2": net.second,
            "fem_d2T_dg2_N_m_per_m2": float(fem.second[k]),
            "network_S": s_net,
            "fem_S": s_fem,
            "S_difference": s_net - s_fem,
            "network_bound": bound,
            "S_tolerance": 2.0 * bound / DELTA_LN_GAP,
        }
    return out


def scan(size: float) -> list[dict[str, float]]:
    """The network's relative error against the FEM (fresh grids) over the gap, paper
    preset: where DELTA_LN_GAP comes from."""
    rows = []
    for g in np.linspace(0.4e-3, 1.0e-3, 13):
        s = build_section(replace(preset("paper"), gap=float(g)))
        n = torque_curve(s, CURRENTS).yield_torque
        f = torque_curve(s, CURRENTS, method="fem", fem_size=size).yield_torque
        err = {f"error_{i:g}A": float(n[k] / f[k] - 1) for k, i in enumerate(CURRENTS)}
        rows.append({"gap_mm": 1e3 * float(g), **err})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size-mm", type=float, default=0.25, help="FEM element size (mm)")
    ap.add_argument("--scan", action="store_true", help="the network's error over the gap")
    args = ap.parse_args()
    size = args.size_mm * 1e-3
    if args.scan:
        print(json.dumps({"size_mm": args.size_mm, "scan": scan(size)}, indent=2))
        return
    print(json.dumps({"size_mm": args.size_mm, "step_m": 7e-6,
                      **{n: compare(n, size) for n in DESIGNS}}, indent=2))  # fmt: skip


if __name__ == "__main__":
    main()
