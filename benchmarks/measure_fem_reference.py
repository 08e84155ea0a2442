"""Measure the FEM reference torque the reluctance network is tested against (issue 12) and
write it as data, `benchmarks/data/fem_reference.json` (not package code: the tests read it).

Designs: the error map's 648-node grid (benchmarks/measure_circuit_map.AXES: drum count ×
gap × zone length × drum bore × drum thickness, the rest of the paper preset) and 200
random designs drawn uniformly inside the same ranges with another seed (``--seed``,
default 2026; invalid draws are redrawn). At each design: the FEM (uniform 0.25 mm mesh,
one grid, Newton warm-started across the currents) yield torque at 2, 4 and 7 A, by both
torque conventions (mid-line and weakest-layer) read from the same solve.

    python benchmarks/measure_fem_reference.py [--jobs 2] [--random 200]   # ~25 min, 2 cores
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measure_circuit_map import AXES, grid_nodes, pool_map

CURRENTS = (2.0, 4.0, 7.0)
CONVENTIONS = ("mid-line", "weakest-layer")
REFERENCE_SIZE = 0.25e-3
OUT = Path(__file__).resolve().parent / "data" / "fem_reference.json"


def fem_yield_torques(clutch, currents, digits: int) -> dict[str, list[float]]:  # type: ignore[no-untyped-def]
    """{convention: FEM yield torque (N·m) at ``currents`` (A), rounded to ``digits``} of one
    clutch: one grid at REFERENCE_SIZE, Newton warm-started across the currents. Raises
    ``FEMConvergenceError`` where a solve does not converge."""
    from geometry.section import build_section
    from magnetics.fem import build_grid, solve_fem
    from magnetics.torque import _fluid

    section = build_section(clutch)
    fluid = _fluid(section, None)
    grid = build_grid(section, REFERENCE_SIZE)
    out: dict[str, list[float]] = {k: [] for k in CONVENTIONS}
    psi = None
    for i in currents:
        sol = solve_fem(section, i, grid=grid, psi0=psi)
        psi = sol.psi
        for k in CONVENTIONS:
            out[k].append(round(float(sol.gap_yield_torque(fluid, None, k).sum()), digits))
    return out


def _design(values: dict[str, float]) -> dict[str, list[float]] | None:
    """{convention: torque at CURRENTS (N·m)} of one design; None if it fails validation."""
    from dataclasses import replace

    from geometry.validation import ParameterError
    from mrclutch.design import design_preset

    base = design_preset("paper").clutch
    try:
        c = replace(base, **{k: (int(v) if k == "n_drums" else v) for k, v in values.items()})
    except ParameterError:
        return None
    return fem_yield_torques(c, CURRENTS, 9)


def random_designs(n: int, seed: int) -> list[dict[str, float]]:
    """``n`` valid designs drawn uniformly inside the map's ranges (drum count uniform)."""
    import numpy as np

    from geometry.params import valid
    from mrclutch.design import design_preset

    base = vars(design_preset("paper").clutch)
    rng = np.random.default_rng(seed)
    out: list[dict[str, float]] = []
    while len(out) < n:
        d = {k: (float(rng.integers(min(v), max(v) + 1)) if k == "n_drums"
                 else float(rng.uniform(min(v), max(v)))) for k, v in AXES.items()}  # fmt: skip
        p = {k: np.atleast_1d(np.asarray(d.get(k, v), dtype=float)) for k, v in base.items()}
        if bool(valid(p)[0]):
            out.append(d)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--random", type=int, default=200)
    ap.add_argument("--seed", type=int, default=2026)
    a = ap.parse_args()
    grid = grid_nodes()
    rand = random_designs(a.random, a.seed)
    work = grid + rand
    res = pool_map(_design, work, a.jobs, chunksize=2)

    def rows(designs, results):  # type: ignore[no-untyped-def]
        return [{"design": d, "torque": r} for d, r in zip(designs, results, strict=True)]

    data = {
        "about": (
            "FEM yield torque (N·m) of the paper preset varied along the error map's axes "
            f"(grid) and at {a.random} random designs inside the same ranges (seed {a.seed}), "
            f"at the currents {list(CURRENTS)} A, uniform mesh {REFERENCE_SIZE} m, both "
            f"torque conventions; measured on {datetime.date.today()}; do not edit by hand. "
            "torque null: the design fails validation."
        ),
        "generated_by": "python benchmarks/measure_fem_reference.py",
        "base_preset": "paper",
        "fem_size_m": REFERENCE_SIZE,
        "currents_A": list(CURRENTS),
        "axes": {k: list(v) for k, v in AXES.items()},
        "grid": rows(grid, res[: len(grid)]),
        "random": rows(rand, res[len(grid) :]),
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    tmp = OUT.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=0) + "\n")
    tmp.replace(OUT)
    bad = sum(r is None for r in res)
    print(f"wrote {OUT}: {len(work)} designs, {bad} invalid", file=sys.stderr)


if __name__ == "__main__":
    main()
