"""The paper preset's torque curve (the paper's Fig. 2b) by the network, the circuit and the
FEM at 530 rpm: T(7 A), the linearity R² from 1 to 4 A, the rise from 4 to 7 A, the
off-state torque, and each model's largest gap to the FEM; one JSON line (docs/magnetics.md)."""

import json

import numpy as np

from geometry.params import preset
from magnetics.torque import torque_curve

i = np.array([0.0, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0, 6.0, 7.0])
m = (i >= 1) & (i <= 4)
out = {}
t = {}
for k in ("network", "circuit", "fem"):
    tc = torque_curve(preset("paper"), i, method=k, speed_rpm=530)
    y = tc.torque
    t[k] = y
    r = y[m] - np.polyval(np.polyfit(i[m], y[m], 1), i[m])
    r2 = 1 - r @ r / np.sum((y[m] - y[m].mean()) ** 2)
    out[k] = [float(y[-1]), float(r2), float(y[-1] / y[7] - 1), float(tc.off_state_torque)]
w = np.isin(i, [1, 2, 3, 4, 5, 6, 7])
out["max_diff"] = [float(np.max(np.abs(t[k][w] / t["fem"][w] - 1))) for k in ("circuit", "network")]
print(json.dumps(out))
