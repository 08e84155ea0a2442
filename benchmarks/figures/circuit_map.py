"""The stored circuit error map (magnetics/data/circuit_error_map.json, circuit/FEM - 1 at
7 A): its range overall and per drum count, the paper preset's node, the FEM's own bound, and
`choose` on the paper preset with 3 drums; one JSON line (README, docs/fidelity.md)."""

import json
from dataclasses import replace

import numpy as np

from magnetics.error_map import circuit_error, load
from mrclutch.design import design_preset
from mrclutch.trust import choose, torque_error_bound

m = load()
e = np.array(m.errors, dtype=float).reshape(len(m.axes["n_drums"]), -1)


def s(a):
    return [float(np.nanmin(a)), float(np.nanmax(a)), float(np.mean(np.abs(a) <= 0.1))]


p = design_preset("paper")
t = replace(p, clutch=replace(p.clutch, n_drums=3))
print(
    json.dumps(
        {
            "map": s(e),
            "drums": [s(r) for r in e],
            "paper": circuit_error(p.clutch).estimate,
            "fem_bound": [m.fem_error_bound[h] for h in (1e-3, 0.5e-3, 0.35e-3)],
            "three_drums": [
                circuit_error(t.clutch).estimate,
                torque_error_bound(t.clutch, "network", None, t.current_limit),
                choose(t, 0.01).torque,
                choose(t, 0.03).torque,
            ],
        }
    )
)
