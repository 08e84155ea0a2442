"""The torque response on the paper preset at 48 V and with laminated iron (delay, K at that
delay), and the lumped delay against the lags' own stable K on 40 random designs; one JSON
line (docs/dynamics.md)."""

import json
from dataclasses import replace

import numpy as np

from magnetics.laminations import Laminations
from mrclutch.design import design_preset
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.haptics.delay import lag_stable_stiffness
from mrclutch.haptics.model import max_stable_stiffness
from mrclutch.pipeline import evaluate

p = design_preset("paper")
out = {}
for name, d in (
    ("volts48", replace(p, amplifier=replace(p.amplifier, supply_voltage=48.0))),
    ("laminated", replace(p, laminations=Laminations(core=0.5e-3, shell=0.5e-3))),
):
    r = evaluate(d).response
    out[name] = [r["torque_delay_s"], r["max_stable_K_torque_delay_N_per_m"]]
# the 40 draws of tests/mrclutch/test_response.py::test_tau_eq_error_on_random_designs,
# whose bound the docs quote beside the measured range
rng = np.random.default_rng(14)
e = []
for _ in range(40):
    lags = rng.uniform(0.05e-3, 2e-3, 3)
    m1, b1, k = (getattr(TABLE2_MR, f) * rng.uniform(0.3, 3) for f in ("m1", "b1", "k"))
    q = replace(TABLE2_MR, delay=0.0, m1=m1, b1=b1, k=k)
    e.append(
        max_stable_stiffness(replace(q, delay=float(lags.sum()))) / lag_stable_stiffness(q, lags)
        - 1
    )
out["random"] = [float(np.min(e)), float(np.max(e)), float(np.median(e))]
print(json.dumps(out))
