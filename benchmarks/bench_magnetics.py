"""Magnetics speed and speed-vs-accuracy.

python -m pytest benchmarks/bench_magnetics.py --benchmark-enable
python benchmarks/bench_magnetics.py [OUT.png]   # table + log-log chart of error vs time
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from geometry.params import preset
from geometry.section import build_section
from magnetics.fem import solve_fem
from magnetics.materials import MRF_132DG
from magnetics.torque import torque_curve, torque_grid_batch

PAPER = preset("paper")


def _designs(s: int = 1000) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(1)
    return {"gap": rng.uniform(0.3e-3, 1.0e-3, s), "zone_length": rng.uniform(4e-3, 8e-3, s)}


def test_circuit_1000_currents_x_1000_designs(benchmark):  # goal < 1 s
    f, cur = _designs(), np.linspace(0, 7, 1000)
    t = benchmark.pedantic(torque_grid_batch, args=(f, cur), rounds=3, iterations=1)
    assert t.shape == (1000, 1000)


def test_fem_paper_default_resolution_one_current(benchmark):  # goal < 5 s
    s = build_section(PAPER)
    sol = benchmark.pedantic(solve_fem, args=(s, 4.0), rounds=2, iterations=1)
    assert sol.residual < 1e-8


def accuracy_table(sizes=(1.0e-3, 0.5e-3, 0.35e-3, 0.25e-3), ref=0.12e-3, currents=(2.0, 4.0, 7.0)):
    s = build_section(PAPER)

    def fem_t(h):
        t0 = time.perf_counter()
        t = [solve_fem(s, i, size=h).gap_yield_torque(MRF_132DG).sum() for i in currents]
        return np.array(t), (time.perf_counter() - t0) / len(currents)

    t_ref, _ = fem_t(ref)
    rows = []
    for h in sizes:
        t, dt = fem_t(h)
        rows.append((f"fem {h * 1e3:.2f} mm", dt, np.max(np.abs(t / t_ref - 1))))
    t0 = time.perf_counter()
    tc = torque_curve(PAPER, currents, method="circuit")
    dt = time.perf_counter() - t0
    rows.append(("circuit", dt / len(currents), np.max(np.abs(tc.yield_torque / t_ref - 1))))
    return rows


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/out/magnetics_error_vs_time.png")
    rows = accuracy_table()
    print(f"{'method':16s} {'s/current':>10s} {'max torque err vs FEM 0.12 mm':>30s}")
    for name, dt, err in rows:
        print(f"{name:16s} {dt:10.4f} {err:30.4f}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for name, dt, err in rows:
        ax.loglog(dt, max(err, 1e-6), "o")
        ax.annotate(name, (dt, max(err, 1e-6)), fontsize=8)
    ax.set_xlabel("time per current (s)")
    ax.set_ylabel("max relative torque error vs fine FEM")
    ax.grid(True, which="both", alpha=0.3)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")
