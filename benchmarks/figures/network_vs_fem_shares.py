"""The network against the stored FEM reference (measure_network.errors): shares within 5 %
and 10 % on the grid and the random designs, at 7 A and over whole curves, medians, means
and the worst designs per drum count; one JSON line (docs/magnetics.md)."""

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/
from measure_network import errors

e, rnd, f = errors("network")
g, r, n = e[~rnd], e[rnd], f["n_drums"][~rnd]


def w(x, t):
    return 100 * float(np.mean(np.abs(x) <= t))


top = [g[n == k][np.argmax(g[n == k][:, 2])] for k in (4, 5, 6)]
print(
    json.dumps(
        {
            "grid": [w(g, 0.05), w(g, 0.1)],
            "random": [w(r, 0.05), w(r, 0.1)],
            "at7": [w(g[:, 2], 0.05), w(g[:, 2], 0.1), w(r[:, 2], 0.05), w(r[:, 2], 0.1)],
            "whole": [
                w(np.abs(g).max(1), 0.1),
                w(np.abs(r).max(1), 0.1),
                w(np.abs(g).max(1), 0.05),
            ],
            "median": [100 * float(np.median(np.abs(g))), 100 * float(np.median(np.abs(r)))],
            "mean": [100 * float(g.mean()), 100 * float(r.mean())],
            "low7": [100 * float(g[n == k][:, 2].min()) for k in (1, 2)],
            "top7": [100 * float(x[2]) for x in top],
            "top2": [100 * float(x[0]) for x in top],
        }
    )
)
