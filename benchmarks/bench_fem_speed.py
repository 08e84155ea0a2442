"""FEM speed against accuracy, old against new, in one run (issue 12).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fem_speed.py [--rounds 3] [--base e29d0a4]

Torque of the paper preset at 2, 4 and 7 A. Reference: Richardson extrapolation of the
uniform grid at 0.25, 0.125 and 0.0625 mm with the observed order per current (printed).
"old": the FEM as it was before the speed-up, run from that revision (``--base``, default
e29d0a4) in a temporary worktree (``bench_against.base_tree``):
scikit-fem's generic assembly every Newton step, SuperLU with its default ordering and a
fresh factorisation every step, one grid for the curve, each current warm-started.
"new": ``torque_curve(method="fem")`` — the grid's forms assembled once per grid, CG on the
last factorised Jacobian, currents in increasing order each warm-started, on the uniform
grid (same numbers as old) or the graded one. Times are per current, grid building
included, the median of the interleaved rounds (a shared machine: read the ratios).
Goals: ≤ 0.5 s per current at 0.2 % and ≤ 0.3 s at 1 %.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from geometry.params import preset
from geometry.section import build_section
from magnetics.fem import build_grid
from magnetics.torque import torque_curve

sys.path.insert(0, str(Path(__file__).resolve().parent))  # run as a script from anywhere
from bench_against import base_tree

CURRENTS = (2.0, 4.0, 7.0)


#: The FEM before the speed-up, run as it was: that revision checked out beside this one.
OLD_REVISION = "e29d0a4"

OLD = r"""
import json, sys, time
from geometry.params import preset
from geometry.section import build_section
from magnetics.fem import build_grid
from magnetics.torque import torque_curve
size, cur = float(sys.argv[1]), [float(x) for x in sys.argv[2:]]
torque_curve(preset("paper"), [1.0], method="fem", fem_size=1e-3)  # imports out of the timing
t = time.perf_counter()
c = torque_curve(preset("paper"), cur, method="fem", fem_size=size)
dt = (time.perf_counter() - t) / len(cur)
n = int(build_grid(build_section(preset("paper")), size).basis.N)
print(json.dumps([[float(x) for x in c.yield_torque], n, dt]))
"""


def _old_solve(tree: Path, size: float) -> tuple[np.ndarray, int, float]:
    """Old torque_curve (one grid, each current's Newton started from the last field), run
    in the old revision's tree: (torques, unknowns, seconds per current)."""
    out = subprocess.run(
        [sys.executable, "-c", OLD, str(size), *map(str, CURRENTS)], cwd=tree,
        env={**os.environ, "PYTHONPATH": str(tree)}, check=True, capture_output=True, text=True,
    )  # fmt: skip
    t, n, dt = json.loads(out.stdout.strip().splitlines()[-1])
    return np.array(t), int(n), float(dt)


def _new_solve(size: float, mesh: str) -> tuple[np.ndarray, int]:
    c = torque_curve(preset("paper"), CURRENTS, method="fem", fem_size=size, fem_mesh=mesh)
    n = build_grid(build_section(preset("paper")), size, mesh=mesh).basis.N
    return c.yield_torque, n


def reference() -> np.ndarray:
    t = [_new_solve(h, "uniform")[0] for h in (0.25e-3, 0.125e-3, 0.0625e-3)]
    order = np.log2((t[0] - t[1]) / (t[1] - t[2]))
    ref = t[2] + (t[2] - t[1]) / (2**order - 1)
    print(f"reference (Richardson, uniform 0.25/0.125/0.0625 mm): {np.round(ref, 6)} N·m, "
          f"observed order {np.round(order, 2)}; 0.0625 mm is "
          f"{np.round(100 * (t[2] / ref - 1), 3)} % off it")  # fmt: skip
    return ref


CASES = [("old", "uniform", h) for h in (0.5e-3, 0.25e-3, 0.125e-3, 0.09e-3)] + [
    ("new", m, h)
    for m, hs in (("uniform", (0.5e-3, 0.25e-3, 0.125e-3, 0.09e-3)),
                  ("graded", (0.25e-3, 0.18e-3, 0.125e-3, 0.09e-3, 0.08e-3)))
    for h in hs
]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--base", default=OLD_REVISION, help="revision holding the old FEM")
    a = ap.parse_args()
    _new_solve(1e-3, "graded")  # imports out of the timings
    ref = reference()
    times: dict[tuple[str, str, float], list[float]] = {c: [] for c in CASES}
    res: dict[tuple[str, str, float], tuple[np.ndarray, int]] = {}
    with base_tree(a.base) as old_tree:
        for _ in range(a.rounds):  # interleaved: load on a shared machine hits all alike
            for c in CASES:
                if c[0] == "old":
                    t_old, n_old, dt = _old_solve(old_tree, c[2])
                    res[c] = (t_old, n_old)
                else:
                    t0 = time.perf_counter()
                    res[c] = _new_solve(c[2], c[1])
                    dt = (time.perf_counter() - t0) / len(CURRENTS)
                times[c].append(dt)
    med = {c: statistics.median(v) for c, v in times.items()}
    err = {c: float(np.max(np.abs(res[c][0] / ref - 1))) for c in CASES}
    print(f"\n{'code':5}{'mesh':9}{'size mm':>8}{'unknowns':>10}{'s/current':>11}"
          f"{'max |err|':>11}{'old/this':>10}")  # fmt: skip
    for c in CASES:
        old = med.get(("old", "uniform", c[2]))
        ratio = f"{old / med[c]:10.2f}" if old and c[1] == "uniform" else f"{'':10}"
        print(f"{c[0]:5}{c[1]:9}{c[2] * 1e3:8.3f}{res[c][1]:10d}{med[c]:11.3f}"
              f"{100 * err[c]:10.3f}%{ratio}")  # fmt: skip
    print()
    for target, goal in ((0.002, 0.5), (0.01, 0.3)):
        best = {}
        for code in ("old", "new"):
            ok = [c for c in CASES if c[0] == code and err[c] <= target]
            best[code] = min(ok, key=med.get) if ok else None
        o, n = best["old"], best["new"]
        fmt = lambda c: "none" if c is None else f"{c[1]} {c[2] * 1e3:g} mm {med[c]:.3f} s"  # noqa: E731
        ratio = f", {med[o] / med[n]:.1f}× faster" if o and n else ""
        print(
            f"within {target:.1%}: old fastest {fmt(o)}; new fastest {fmt(n)}{ratio} "
            f"(goal ≤ {goal} s: {'met' if n and med[n] <= goal else 'NOT met'})"
        )


if __name__ == "__main__":
    main()
