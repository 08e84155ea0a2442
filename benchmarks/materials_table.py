"""The paper clutch made of each fluid × each housing steel: torque at 7 A, clutch mass, b1
and the torque response's equivalent delay (docs/materials.md prints this table).

    python benchmarks/materials_table.py           # the Markdown table
    python benchmarks/materials_table.py --json    # the same figures as JSON

The steel goes in the core and the shell (the drums stay steel 1018); every figure is the
fast path's (``mrclutch.pipeline.evaluate``, the reluctance network), whose error bound is
measured only for MRF-132DG / steel 1018 (docs/magnetics.md, per fluid against the FEM).
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace

from geometry.materials import LABEL, MaterialChoice
from mrclutch.design import design_preset
from mrclutch.pipeline import evaluate

FLUIDS = ("mrf_122eg", "mrf_132dg", "mrf_140cg")
STEELS = ("steel_1018", "pure_iron", "hiperco_50", "stainless_430")


def rows() -> dict[str, dict[str, float]]:
    base = design_preset("paper")
    out = {}
    for fluid in FLUIDS:
        for steel in STEELS:
            d = replace(base, materials=MaterialChoice(fluid=fluid, core=steel, shell=steel))
            e = evaluate(d)
            out[f"{fluid}/{steel}"] = {
                "torque_N_m": e.clutch.max_torque,
                "clutch_mass_kg": e.clutch.clutch_mass,
                "b1_N_s_per_m": float(e.mr.b1),
                "delay_s": float(e.torque_response.equivalent_delay[0]),
            }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    table = rows()
    if ap.parse_args().json:
        print(json.dumps(table, indent=1))
        return
    print("| fluid | core + shell | torque at 7 A (N·m) | clutch mass (g) | b1 (N·s/m) "
          "| delay (ms) |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for key, r in table.items():
        fluid, steel = key.split("/")
        print(f"| {LABEL[fluid]} | {LABEL[steel]} | {r['torque_N_m']:.3f} | "
              f"{r['clutch_mass_kg'] * 1e3:.1f} | {r['b1_N_s_per_m']:.3f} | "
              f"{r['delay_s'] * 1e3:.2f} |")  # fmt: skip


if __name__ == "__main__":
    main()
