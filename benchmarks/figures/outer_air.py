"""The solved outside-air permeance (magnetics/data/outer_air.json): the interpolation's
error on its stored checks, the mesh-halving change and the open-boundary ratio's range;
one JSON line (docs/magnetics.md)."""

import json

import numpy as np

from magnetics.outer_air import load, unit_permeance

_, d = load()
c = np.array(d["checks"])
e = np.abs(unit_permeance(*c[:, :4].T) / c[:, 4] - 1)
v = np.array(d["convergence"])
o = np.array(d["open_boundary_ratio"])[:, 4]
print(
    json.dumps(
        {
            "interp": [float(e.max()), float(np.median(e))],
            "halving": float(np.max(np.abs(v[:, 5] / v[:, 4] - 1))),
            "open": [float(o.min() - 1), float(o.max() - 1)],
        }
    )
)
