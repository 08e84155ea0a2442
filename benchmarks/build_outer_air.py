"""The table of the air's permeance outside the shell (magnetics.outer_air), written to
`magnetics/data/outer_air.json`: the exterior solve at every node of AXES (the pole lengths
symmetric: p(b, a_A, a_B, ρ) = p(b, a_B, a_A, ρ), so each pair is solved once), and the
table's own checks, stored with it and read by tests/magnetics/test_outer_air.py:

- ``checks``: solves at random off-node points (seed 12) against the interpolation;
- ``convergence``: the solve at SIZE and SIZE/2 at a few nodes (the discretisation error);
- ``open_boundary_ratio``: the open exterior's p (air box 10× farther) over the FEM box's.

    python benchmarks/build_outer_air.py [--jobs 2]     # ~5 min on 2 cores
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measure_circuit_map import pool_map

from magnetics import outer_air
from magnetics.outer_air import AXES, DATA_FILE, SIZE

N_CHECKS = 40
SAMPLE = ((0.6, 0.5, 0.45, 0.7), (0.1, 0.1, 2.0, 0.4), (2.0, 1.0, 0.2, 0.9), (0.3, 3.0, 3.0, 0.6))


def _solve(args: tuple[float, ...]) -> float:
    *point, size, box = args
    return outer_air.solve(*point, size=size, box=box)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    shape = tuple(len(v) for v in AXES.values())
    idx = [i for i in itertools.product(*(range(n) for n in shape)) if i[1] <= i[2]]
    point = lambda i: tuple(AXES[k][j] for k, j in zip(AXES, i, strict=True))  # noqa: E731
    rng = np.random.default_rng(12)
    coords = outer_air._log_axes()  # the interpolation's coordinates (ln of the lengths)
    u = rng.uniform([v[0] for v in coords.values()], [v[-1] for v in coords.values()],
                    (N_CHECKS, len(coords)))  # fmt: skip
    checks = [tuple(float(np.exp(x)) if k in outer_air._LOG_AXES else float(x)
                    for k, x in zip(AXES, r, strict=True)) for r in u]  # fmt: skip
    work = [(*point(i), SIZE, "fem") for i in idx]
    work += [(*c, SIZE, "fem") for c in checks]
    work += [(*s, SIZE / 2, "fem") for s in SAMPLE] + [(*s, SIZE, "fem") for s in SAMPLE]
    work += [(*s, SIZE, "open") for s in SAMPLE]
    out = pool_map(_solve, work, a.jobs, chunksize=8)
    p = np.full(shape, np.nan)
    for i, v in zip(idx, out, strict=False):
        p[i] = v
        p[i[0], i[2], i[1], i[3]] = v
    n, c = len(idx), len(checks)
    fine, base, wide = (out[n + c + k * len(SAMPLE) : n + c + (k + 1) * len(SAMPLE)]
                        for k in range(3))  # fmt: skip
    data = {
        "what": "p = P/(mu0 R) of the air outside the shell at the band's mid-plane "
        "(magnetics.outer_air), written by benchmarks/build_outer_air.py",
        "date": datetime.date.today().isoformat(),
        "size": SIZE,
        "growth": outer_air.GROWTH,
        "box": "fem",
        "axes": {k: list(v) for k, v in AXES.items()},
        "p": [round(float(x), 6) for x in p.ravel()],
        "checks": [[*pt, round(float(v), 6)] for pt, v in zip(checks, out[n : n + c], strict=True)],
        "convergence": [
            [*s, round(float(f), 6), round(float(b), 6)]
            for s, f, b in zip(SAMPLE, fine, base, strict=True)
        ],
        "open_boundary_ratio": [
            [*s, round(float(w / b), 6)] for s, w, b in zip(SAMPLE, wide, base, strict=True)
        ],
    }
    DATA_FILE.write_text(json.dumps(data, indent=1) + "\n")
    outer_air.load.cache_clear()
    est = outer_air.unit_permeance(*np.array(checks).T)
    miss = est / np.array(out[n : n + c]) - 1
    print(f"wrote {DATA_FILE}: {n} solves; off-node checks: interpolation within "
          f"{np.abs(miss).max():.2%} (median {np.median(np.abs(miss)):.2%}); "
          f"size/2: {max(abs(f / b - 1) for f, b in zip(fine, base, strict=True)):.2%}; "
          f"open/box: {min(w / b for w, b in zip(wide, base, strict=True)):.3f}-"
          f"{max(w / b for w, b in zip(wide, base, strict=True)):.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
