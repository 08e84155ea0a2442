"""The stored network error map: its range factor, median and largest error, the circuit
map's range factor, the map's bound at 2, 3 and 6 drums, and the estimate and bound on the
paper preset and a 0.7 mm shell; one JSON line (docs/magnetics.md)."""

import json
from dataclasses import replace

import numpy as np

from magnetics.error_map import circuit_error, load, map_bound
from mrclutch.design import design_preset
from mrclutch.trust import torque_error_bound

m = load("network")
e = np.abs(np.array(m.errors, dtype=float))
p = design_preset("paper")
b = [map_bound(vars(replace(p.clutch, n_drums=n)), "network")[1] for n in (2, 3, 6)]
thin = replace(p, clutch=replace(p.clutch, shell_thickness=0.7e-3))
now = [
    [
        circuit_error(d.clutch, "network", d.current_limit).estimate,
        torque_error_bound(d.clutch, "network", None, d.current_limit),
    ]
    for d in (p, thin)
]
print(
    json.dumps(
        {
            "map": [m.range_factor, float(np.nanmedian(e)), float(np.nanmax(e))],
            "circuit_range_factor": load("circuit").range_factor,
            "map_bound": b,
            "paper": now[0],
            "thin_shell": now[1],
        }
    )
)
