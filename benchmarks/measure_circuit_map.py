"""Measure the saturating circuit's torque error against the FEM over the design space and
write it as the stored map `magnetics/data/circuit_error_map.json` (issue 6: the failure map and the
accuracy-target choice use it).

Grid: n_drums × gap × zone length × drum bore × drum thickness, other dimensions, coil and
current limit of the paper preset. At each node: yield torque at the current limit by the
circuit and by the reference FEM (0.25 mm); the signed relative error circuit/FEM − 1. On
the slice through the paper preset's bore and drum thickness also the coarse FEMs (1, 0.5,
0.35 mm), whose largest error over the slice is stored as their bound. Then designs at
cell centres (off the grid) measure how far multilinear interpolation of the map is from
the truth: its largest miss relative to the map's local variation is stored as
RANGE_FACTOR, which sets the margin of the circuit's error bound.

    python benchmarks/measure_circuit_map.py [--jobs 2]     # ~10 min on 2 cores
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

AXES: dict[str, tuple[float, ...]] = {
    "n_drums": (1, 2, 3, 4, 5, 6),
    "gap": (0.2e-3, 0.4e-3, 0.7e-3, 1.0e-3),
    "zone_length": (3e-3, 6e-3, 9e-3),
    "drum_inner_diameter": (6e-3, 11.5e-3, 18e-3),
    "drum_thickness": (0.1e-3, 0.3e-3, 0.6e-3),
}
REFERENCE_SIZE = 0.25e-3
COARSE_SIZES = (1.0e-3, 0.5e-3, 0.35e-3)
OUT = Path(__file__).resolve().parents[1] / "magnetics" / "data" / "circuit_error_map.json"


def _node(args: tuple[dict[str, float], bool]) -> tuple[float, dict[float, float]]:
    """(circuit error, {coarse FEM size: error}) of one design; NaN if it is invalid."""
    values, coarse = args
    from geometry.validation import ParameterError
    from magnetics.torque import torque_curve
    from mrclutch.design import design_preset

    base = design_preset("paper")
    try:
        kw = {k: (int(v) if k == "n_drums" else v) for k, v in values.items()}
        c = replace(base.clutch, **kw)
    except ParameterError:
        return math.nan, {}
    i = [replace(base, clutch=c).current_limit]
    ref = float(torque_curve(c, i, method="fem", fem_size=REFERENCE_SIZE).yield_torque[0])
    circ = float(torque_curve(c, i, method="circuit").yield_torque[0])
    fem = {}
    if coarse:
        for s in COARSE_SIZES:
            t = float(torque_curve(c, i, method="fem", fem_size=s).yield_torque[0])
            fem[s] = t / ref - 1.0
    return circ / ref - 1.0, fem


def checks_of(base) -> list[dict[str, float]]:  # type: ignore[no-untyped-def]
    """Off-grid designs: cell centres in gap and zone length, on the bore/thickness slice
    of the base preset and at the centre of the bore/thickness cells above it."""
    mid = lambda ax: [(x + y) / 2 for x, y in itertools.pairwise(AXES[ax])]  # noqa: E731
    return [
        {"n_drums": n, "gap": g, "zone_length": z, "drum_inner_diameter": d, "drum_thickness": t}
        for n in (1, 2, 3, 4, 6)
        for g in mid("gap")
        for z in mid("zone_length")
        for d, t in ((base.drum_inner_diameter, base.drum_thickness), (14.75e-3, 0.45e-3))
    ]


def grid_nodes() -> list[dict[str, float]]:
    """The map's designs: every combination of the AXES values (the last axis fastest)."""
    return [dict(zip(AXES, v, strict=True)) for v in itertools.product(*AXES.values())]


def pool_map(fn, work: list, jobs: int, chunksize: int) -> list:  # type: ignore[no-untyped-def]
    """fn over ``work`` on ``jobs`` processes, in order, a count of those done on stderr."""
    out = []
    with ProcessPoolExecutor(jobs) as ex:
        for k, r in enumerate(ex.map(fn, work, chunksize=chunksize)):
            out.append(r)
            print(f"\r{k + 1}/{len(work)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    from mrclutch.design import design_preset

    base = design_preset("paper").clutch
    nodes = grid_nodes()
    on_slice = [
        n["drum_inner_diameter"] == base.drum_inner_diameter
        and n["drum_thickness"] == base.drum_thickness
        for n in nodes
    ]
    checks = checks_of(base)
    work = [(n, s) for n, s in zip(nodes, on_slice, strict=True)] + [(c, False) for c in checks]
    out = pool_map(_node, work, a.jobs, chunksize=4)
    errs = [e for e, _ in out[: len(nodes)]]
    sliced = [f for (_, f), sl in zip(out[: len(nodes)], on_slice, strict=True) if sl and f]
    fem_bound = {s: max(abs(f[s]) for f in sliced) for s in COARSE_SIZES}
    measured = [(c, e) for c, (e, _) in zip(checks, out[len(nodes) :], strict=True)]
    write(errs, fem_bound, len(sliced), measured)


def map_data(
    errs: list[float], checks: list[tuple[dict[str, float], float]], axes: dict | None = None
) -> tuple[dict, float]:
    """The map's measured part — axes, errors, checks, range_factor — and the raw factor:
    the largest interpolation miss at the checks over the local variation of the map there
    (magnetics.error_map). Shared by the circuit's and the network's maps."""
    import numpy as np

    sys.path.insert(0, str(OUT.parents[2]))
    from magnetics.interpolation import _interp

    axes = AXES if axes is None else axes
    grid = np.array(errs).reshape([len(v) for v in axes.values()])
    ratios = []
    for c, e in checks:
        est, _, rng = _interp(axes, grid, c)
        if math.isfinite(e) and math.isfinite(est) and rng > 0:
            ratios.append(abs(e - est) / rng)
    factor = max(ratios)
    num = lambda e: round(e, 5) if math.isfinite(e) else None  # noqa: E731  (JSON: null = NaN)
    keys = ("n_drums", "gap", "zone_length", "drum_inner_diameter", "drum_thickness")
    return {
        "axes": {k: list(v) for k, v in axes.items()},
        "errors": [num(e) for e in errs],
        "checks": [[*(c[k] for k in keys), num(e)] for c, e in checks],
        "range_factor": math.ceil(factor * 100) / 100,
    }, factor


def write(
    errs: list[float],
    fem_bound: dict[float, float],
    n_sliced: int,
    checks: list[tuple[dict[str, float], float]],
) -> None:
    """Write the data file (``map_data`` and the FEM's coarse bounds)."""
    measured, factor = map_data(errs, checks)
    data = {
        "about": (
            "Measured torque error of the saturating circuit against the FEM (signed, "
            "circuit/FEM - 1, yield torque at the current limit) on a grid over the design "
            f"space, measured on {datetime.date.today()}; do not edit by hand. Other "
            "dimensions, coil and current limit are the base preset's; null marks designs "
            "that fail validation. errors: row-major over axes (n_drums slowest). "
            "fem_error_bound: largest |FEM(size)/FEM(reference) - 1| over the grid's slice "
            f"through the base preset's bore and drum thickness ({n_sliced} designs). checks: "
            "off-grid designs (n_drums, gap, zone_length, bore, drum thickness, error). "
            "range_factor: largest interpolation miss at the checks over the map's local "
            "variation there."
        ),
        "generated_by": "python benchmarks/measure_circuit_map.py",
        "base_preset": "paper",
        "reference_fem_size_m": REFERENCE_SIZE,
        "axes": measured["axes"],
        "errors": measured["errors"],
        "fem_error_bound": {repr(s): round(v, 5) for s, v in fem_bound.items()},
        "checks": measured["checks"],
        "range_factor": measured["range_factor"],
    }
    OUT.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {OUT}: FEM bounds {fem_bound}, range factor {factor:.3f}")


if __name__ == "__main__":
    main()
