"""The reluctance network's torque error against the FEM over the design space, written as
the stored map `magnetics/data/network_error_map.json` (the same format and axes as the
circuit's map, read by magnetics.error_map with ``model="network"``).

No new FEM runs: the FEM's yield torque at the current limit (7 A, mid-line convention) of
the 648 grid designs and of the 200 random designs comes from the stored reference
(`benchmarks/data/fem_reference.json`, measure_fem_reference.py). The grid designs are
the map's nodes; the random designs, off the grid, are its checks: their largest
interpolation miss over the map's local variation is stored as range_factor, which sets
the margin of the network's error bound (magnetics.error_map). The FEM's own bounds at
coarse sizes are the circuit map's (a property of the FEM, not of the model).

    python benchmarks/measure_network_map.py     # ~2 s
"""

from __future__ import annotations

import datetime
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "magnetics" / "data" / "network_error_map.json"
CURRENT = 7.0  # A, the paper preset's current limit: the map's operating point


def measure() -> tuple[dict, list[float], list[tuple[dict[str, float], float]]]:
    """(axes, the grid's errors in the map's row-major order, the checks)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from measure_circuit_map import AXES
    from measure_network import DATA

    from magnetics.torque import network_torque_batch
    from mrclutch.design import design_preset

    data = json.loads(DATA.read_text())
    col = data["currents_A"].index(CURRENT)
    base = vars(design_preset(data["base_preset"]).clutch)

    def errors(rows: list[dict]) -> list[float]:
        fields = {k: np.array([r["design"].get(k, v) for r in rows], dtype=float)
                  for k, v in base.items()}  # fmt: skip
        net = network_torque_batch(fields, [CURRENT])[:, 0]
        fem = np.array([math.nan if r["torque"] is None else r["torque"]["mid-line"][col]
                        for r in rows])  # fmt: skip
        return (net / fem - 1.0).tolist()

    order = [tuple(r["design"][k] for k in AXES) for r in data["grid"]]
    expect = [tuple(v) for v in __import__("itertools").product(*AXES.values())]
    if order != expect:
        raise SystemExit("fem_reference.json: the grid is not in the map's row-major order")
    checks = [({k: r["design"][k] for k in AXES}, e)
              for r, e in zip(data["random"], errors(data["random"]), strict=True)]  # fmt: skip
    return AXES, errors(data["grid"]), checks


def main() -> None:
    from measure_circuit_map import map_data

    from magnetics.error_map import DATA_FILES

    axes, errs, checks = measure()
    measured, factor = map_data(errs, checks, axes)
    circuit = json.loads(DATA_FILES["circuit"].read_text())
    data = {
        "about": (
            "Measured torque error of the reluctance network against the FEM (signed, "
            f"network/FEM - 1, yield torque at {CURRENT:g} A, the current limit, mid-line "
            "convention) on the circuit map's grid, from the stored FEM reference "
            f"(benchmarks/data/fem_reference.json), measured on {datetime.date.today()}; do "
            "not edit by hand. errors: row-major over axes (n_drums slowest); null marks "
            "designs that fail validation. checks: the reference's random designs (n_drums, "
            "gap, zone_length, bore, drum thickness, error). range_factor: largest "
            "interpolation miss at the checks over the map's local variation there. "
            "fem_error_bound: the circuit map's (the FEM's own error at coarse sizes)."
        ),
        "generated_by": "python benchmarks/measure_network_map.py",
        "base_preset": circuit["base_preset"],
        "reference_fem_size_m": circuit["reference_fem_size_m"],
        **{k: measured[k] for k in ("axes", "errors")},
        "fem_error_bound": circuit["fem_error_bound"],
        **{k: measured[k] for k in ("checks", "range_factor")},
    }
    OUT.write_text(json.dumps(data, indent=1) + "\n")
    finite = np.abs([e for e in errs if math.isfinite(e)])
    print(f"wrote {OUT}: grid |error| median {np.median(finite):.2%}, max {finite.max():.2%}; "
          f"range factor {factor:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
