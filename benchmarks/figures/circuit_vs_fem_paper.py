"""The single-loop circuit against the FEM (0.25 mm) at 1, 2.5, 4 and 7 A on the paper preset
and seven variants of it (gap, zone length, drum count): circuit/FEM - 1, one JSON line
(docs/magnetics.md; eight FEM curves, ~20 s)."""

import json
from dataclasses import replace

from geometry.params import preset
from magnetics.torque import torque_curve

p = preset("paper")
rows = {
    "paper": p,
    "gap03": replace(p, gap=0.3e-3),
    "gap05": replace(p, gap=0.5e-3),
    "gap10": replace(p, gap=1.0e-3),
    "zone4": replace(p, zone_length=4e-3),
    "zone8": replace(p, zone_length=8e-3),
    "drums1": replace(p, n_drums=1),
    "drums3": replace(p, n_drums=3),
}
a = [1.0, 2.5, 4.0, 7.0]
out = {}
for k, c in rows.items():
    fem = torque_curve(c, a, method="fem", fem_size=0.25e-3).yield_torque
    out[k] = [float(x) for x in torque_curve(c, a, method="circuit").yield_torque / fem - 1]
print(json.dumps(out))
