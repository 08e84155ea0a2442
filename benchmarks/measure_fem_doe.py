"""Measure the FEM torque on a design of experiments over EVERY section dimension and the
coil's ampere-turns (issue 31), and write it as data, `benchmarks/data/fem_doe.json`, from
which `benchmarks/measure_network_bound.py` builds and checks the network's error bound.

Ranges (RANGES below, SI; the paper preset sits inside every one): all 15 length fields of
the section that the axisymmetric FEM sees (the hub holes it does not) and the drum count,
plus the ampere-turns N·I at which the torque is read. The coil keeps the preset's 140
turns (the field depends on N·I only); its wire is thinned where the coil window is smaller
than the preset's so they fit (the wire is not magnetic).

Two sets, two seeds, two designs of experiments:
* ``build``: a scrambled Sobol sample (seed BUILD_SEED) of the 16 design dimensions, the
  invalid draws (validation: envelope, hub over the shaft, …) skipped. The bound is fitted
  on it.
* ``check``: ``--check`` designs drawn uniformly at random with another seed (CHECK_SEED,
  never used to build): the bound's validation.
At each design: the FEM (uniform 0.25 mm mesh, Newton warm-started up the currents) yield
torque at three ampere-turns, one drawn in each third of the N·I range (stratified), by
both torque conventions read from the same solve.

    python benchmarks/measure_fem_doe.py [--jobs 2] [--build 512] [--check 200]  # ~15 min/core
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measure_circuit_map import pool_map
from measure_fem_reference import REFERENCE_SIZE, fem_yield_torques

OUT = Path(__file__).resolve().parent / "data" / "fem_doe.json"
TURNS = 140  # the paper preset's coil
#: The design space of the bound (SI; n_drums inclusive integers). The error-map axes keep
#: their ranges; every other length spans about half to twice the paper preset's value.
RANGES: dict[str, tuple[float, float]] = {
    "n_drums": (1, 6),
    "gap": (0.2e-3, 1.0e-3),
    "zone_length": (3e-3, 9e-3),
    "drum_inner_diameter": (6e-3, 18e-3),
    "drum_thickness": (0.1e-3, 0.6e-3),
    "input_drum_thickness": (0.1e-3, 0.6e-3),
    "band_length": (4e-3, 12e-3),
    "end_clearance": (0.25e-3, 1.0e-3),
    "hub_thickness": (0.4e-3, 1.6e-3),
    "end_cap_thickness": (0.4e-3, 1.6e-3),
    "shell_thickness": (0.7e-3, 2.8e-3),
    "sleeve_thickness": (0.15e-3, 0.6e-3),
    "coil_depth": (1.25e-3, 5e-3),
    "shaft_radius": (1.5e-3, 2.5e-3),
    "shaft_length": (3e-3, 8e-3),
    "shaft_bore_clearance": (0.1e-3, 0.4e-3),
}
#: The coil's ampere-turns N·I [A] at which the torque is read (140 turns × 0.36 … 8.6 A).
AMPERE_TURNS = (50.0, 1200.0)
BUILD_SEED = 31
CHECK_SEED = 3101


def coil_wire(design: dict[str, float], base: dict) -> float:  # type: ignore[type-arg]
    """The preset's wire, thinned (2 % margin) where TURNS of it would not fit the window."""
    window = 0.9 * design["coil_depth"] * design["band_length"]  # COIL_PACKING
    fit = 0.98 * math.sqrt(window / TURNS) - 2 * base["wire_insulation"]
    return min(base["wire_diameter"], fit)


def to_design(u: list[float]) -> dict[str, float]:
    """Unit-cube point (one coordinate per RANGES entry) → design dict (SI)."""
    d = {}
    for (k, (lo, hi)), x in zip(RANGES.items(), u, strict=True):
        if k == "n_drums":
            d[k] = float(min(int(lo + x * (hi - lo + 1)), int(hi)))
        else:
            d[k] = lo + x * (hi - lo)
    return d


def sample(n: int, seed: int, sobol: bool) -> list[dict[str, float]]:
    """``n`` valid designs: scrambled Sobol points (``sobol``, invalid ones skipped, the
    sequence drawn on) or uniform random draws (invalid ones redrawn); with their wire and
    their three ampere-turns (one uniform in each third of AMPERE_TURNS, ascending)."""
    import numpy as np
    from scipy.stats import qmc

    from geometry.params import valid
    from mrclutch.design import design_preset

    base = vars(design_preset("paper").clutch)
    rng = np.random.default_rng(seed)
    eng = qmc.Sobol(len(RANGES), scramble=True, seed=seed) if sobol else None
    out: list[dict[str, float]] = []
    while len(out) < n:
        u = eng.random(1)[0] if eng is not None else rng.uniform(size=len(RANGES))
        d = to_design(list(u))
        d["wire_diameter"] = coil_wire(d, base)
        p = {k: np.atleast_1d(np.asarray(d.get(k, v), dtype=float)) for k, v in base.items()}
        p["coil_turns"] = np.atleast_1d(float(TURNS))
        if d["wire_diameter"] > 0 and bool(valid(p)[0]):
            lo, hi = AMPERE_TURNS
            third = (hi - lo) / 3
            d["ampere_turns"] = [round(lo + third * (k + rng.uniform()), 3) for k in range(3)]
            out.append(d)
    return out


def fem(design: dict) -> dict[str, list[float]] | None:  # type: ignore[type-arg]
    """{convention: FEM yield torque (N·m) at the design's ampere-turns, "s": seconds}
    (``measure_fem_reference.fem_yield_torques`` at I = N·I/TURNS)."""
    from dataclasses import replace

    from geometry.validation import ParameterError
    from magnetics.fem import FEMConvergenceError
    from mrclutch.design import design_preset

    t0 = time.perf_counter()
    base = design_preset("paper").clutch
    kw = {k: (int(v) if k == "n_drums" else v) for k, v in design.items() if k != "ampere_turns"}
    try:
        c = replace(base, coil_turns=TURNS, **kw)
    except ParameterError:
        return None
    try:
        out = fem_yield_torques(c, [ni / TURNS for ni in design["ampere_turns"]], 10)
    except FEMConvergenceError:  # recorded as a failed design, never guessed
        return None
    out["s"] = [round(time.perf_counter() - t0, 3)]
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--build", type=int, default=448)
    ap.add_argument("--check", type=int, default=200)
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args()
    t0 = time.perf_counter()
    build = sample(a.build, BUILD_SEED, sobol=True)
    check = sample(a.check, CHECK_SEED, sobol=False)
    work = build + check
    res = pool_map(fem, work, min(a.jobs, 2), chunksize=1)

    def rows(designs, results):  # type: ignore[no-untyped-def]
        return [{"design": d, "torque": r} for d, r in zip(designs, results, strict=True)]

    data = {
        "about": (
            "FEM yield torque (N·m) on a design of experiments over every section dimension "
            f"(ranges, SI) and the coil's ampere-turns (coil_turns = {TURNS}; current = "
            "ampere_turns / coil_turns): build = scrambled Sobol sample (seed "
            f"{BUILD_SEED}), check = uniform random designs (seed {CHECK_SEED}, not used to "
            f"build the bound); uniform mesh {REFERENCE_SIZE} m, both torque conventions, "
            "the paper preset's materials (steel_1018, mrf_132dg) and other fields; "
            f"measured on {datetime.date.today()}; do not edit by hand. torque.s: seconds."
        ),
        "generated_by": "python benchmarks/measure_fem_doe.py",
        "base_preset": "paper",
        "materials": {"steel": "steel_1018", "fluid": "mrf_132dg"},
        "fem_size_m": REFERENCE_SIZE,
        "coil_turns": TURNS,
        "ranges": {k: list(v) for k, v in RANGES.items()},
        "ampere_turns_range": list(AMPERE_TURNS),
        "seeds": {"build": BUILD_SEED, "check": CHECK_SEED},
        "build": rows(build, res[: len(build)]),
        "check": rows(check, res[len(build) :]),
    }
    a.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = a.out.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=0) + "\n")
    tmp.replace(a.out)
    bad = sum(r is None for r in res)
    print(f"wrote {a.out}: {len(work)} designs, {bad} failed, "
          f"{time.perf_counter() - t0:.0f} s wall", file=sys.stderr)  # fmt: skip


if __name__ == "__main__":
    main()
