"""MRF-132DG's yield stress (Carlson's law) against the datasheet's points: the relative
difference at each point and the saturated yield stress, one JSON line (docs/magnetics.md)."""

import json

from magnetics.materials import MRF_132DG, MRF_132DG_DATASHEET_TAU

print(
    json.dumps(
        {
            "off": [float(MRF_132DG.tau_y(h) / t - 1) for h, t in MRF_132DG_DATASHEET_TAU],
            "max": MRF_132DG.tau_y_max,
        }
    )
)
