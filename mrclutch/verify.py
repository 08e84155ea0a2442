"""FEM re-check of a sweep's best rows (issue 12): the sweep ranks on the fast path (the
reluctance network), this re-solves the N best designs by one column with the FEM at the
error map's reference size, through the same executor as the sweep (one design a task, so
a Dask cluster runs them in parallel), and tabulates the network's error on each, beside
the single loop's (``method="circuit"``, solved here one design at a time).

A row's design is rebuilt from the spec and its design id (``SweepSpec.design_fields``:
the same SI fields and materials the sweep evaluated, not the rounded numbers of the file);
a worker registers the spec's material files before it solves (``MaterialFile.ensure``).
"max torque" is the sweep's: yield + drag at the current limit and the input speed
(``clutch_figures``), here with the torque by the FEM.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from geometry.atomic import atomic_path
from geometry.materials import SLOTS
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.error_map import circuit_error
from magnetics.torque import torque_curve
from mrclutch.design import ClutchDesign
from mrclutch.sweep import MaterialFile, SweepSpec, read_results

TORQUE = "max_torque_N_m"
BOUND = "torque_error_bound"
#: the sidecar's columns: each number's fidelity named beside it
COLUMNS = ("design_id", "objective", "objective_value", "fast_max_torque_N_m",
           "fast_fidelity", "fem_max_torque_N_m", "fem_fidelity", "relative_error",
           "torque_error_bound", "within_bound", "circuit_max_torque_N_m",
           "circuit_fidelity", "circuit_relative_error", "circuit_error_bound",
           "circuit_within_bound")  # fmt: skip


@dataclass(frozen=True)
class VerifiedRow:
    design_id: int
    objective_value: float
    fast_torque: float  # N·m, the sweep's (the reluctance network)
    fem_torque: float  # N·m, the FEM's at fem_size
    bound: float  # the row's torque_error_bound (inf: off the map)
    circuit_torque: float  # N·m, the single loop's (yield + the same drag)
    circuit_bound: float  # its measured error map's bound (inf: off the map)

    @property
    def error(self) -> float:
        """Relative error of the fast torque against the FEM's."""
        return self.fast_torque / self.fem_torque - 1

    @property
    def circuit_error(self) -> float:
        """Relative error of the circuit's torque against the FEM's."""
        return self.circuit_torque / self.fem_torque - 1

    @property
    def circuit_within_bound(self) -> bool:
        return abs(self.circuit_error) <= self.circuit_bound

    @property
    def within_bound(self) -> bool:
        return abs(self.error) <= self.bound


def verified_path(out: str | Path) -> Path:
    """The sidecar ``<out>.verified.csv``."""
    out = Path(out)
    return out.with_name(out.name + ".verified.csv")


def top_rows(results: dict[str, np.ndarray], key: str, n: int, maximize: bool) -> np.ndarray:
    """Indices into ``results`` of the ``n`` best valid rows by column ``key`` (fewer when
    fewer rows have a finite value), best first; ties by design id."""
    if key not in results:
        raise ParameterError(f"--objective {key}: not a column of the results "
                             f"({', '.join(k for k in results if k != 'design_id')})")  # fmt: skip
    v = results[key]
    ok = np.isfinite(v) & (results.get("valid", np.ones_like(v)) == 1)
    idx = np.flatnonzero(ok)
    order = np.lexsort((results["design_id"][idx], -v[idx] if maximize else v[idx]))
    return idx[order[:n]]


def design_of(spec: SweepSpec, base: ClutchDesign, design_id: int) -> ClutchDesign:
    """The sweep's design number ``design_id``: its chunk regenerated (SI fields, and the
    materials of a material axis)."""
    if not 0 <= design_id < spec.n_designs:
        raise ParameterError(f"design id {design_id}: not in the sweep (0..{spec.n_designs - 1})")
    ids, fields = spec.design_fields(design_id // spec.chunk_size)
    row = int(design_id - ids[0])
    mats = {k: str(v[row]) for k, v in fields.items() if k in SLOTS}
    dims = {k: (int(v[row]) if v.dtype.kind == "i" else float(v[row]))
            for k, v in fields.items() if k not in SLOTS}  # fmt: skip
    return replace(base, clutch=replace(base.clutch, **dims),
                   materials=replace(base.materials, **mats))  # fmt: skip


def fem_max_torque(design: ClutchDesign, fem_size: float,
                   materials: Sequence[MaterialFile] = ()) -> float:  # fmt: skip
    """Max torque (yield + drag, N·m) at the current limit with the FEM's yield torque at
    ``fem_size`` (m) on the uniform grid (the error map's reference mesh); runs in a
    worker, which first registers the user's ``materials`` files it may not have read."""
    for m in materials:
        m.ensure()
    return _max_torque(design, "fem", fem_size)


def _max_torque(design: ClutchDesign, method: str, fem_size: float | None = None) -> float:
    """Yield torque by ``method`` plus the drag, at the current limit and input speed."""
    op = design.operating
    curve = torque_curve(build_section(design.clutch, design.materials),
                         [design.current_limit], method=method,
                         fem_size=fem_size, speed_rpm=op.input_speed_rpm,
                         temperature=op.fluid_temperature, support=design.support)  # fmt: skip
    return float(curve.torque[0])


def verify_top(
    spec: SweepSpec,
    base: ClutchDesign,
    results_path: str | Path,
    n: int,
    key: str,
    maximize: bool,
    fem_size: float,
    executor: Executor | None = None,
) -> list[VerifiedRow]:
    """The ``n`` best rows of the sweep's results by ``key``, each re-solved by the FEM at
    ``fem_size`` (m) on ``executor`` (in this process when None), best first."""
    if not (isinstance(n, int) and n >= 1):
        raise ParameterError(f"--verify-top = {n!r}: must be an integer >= 1")
    if not (math.isfinite(fem_size) and fem_size > 0):
        raise ParameterError(f"FEM size = {fem_size!r} m: must be finite and > 0")
    res = read_results(results_path)
    for col in (TORQUE, BOUND):
        if col not in res:
            raise ParameterError(f"{results_path}: no {col} column; cannot verify")
    rows = top_rows(res, key, n, maximize)
    designs = [design_of(spec, base, int(res["design_id"][i])) for i in rows]
    ids = [int(res["design_id"][i]) for i in rows]
    keys, fast, bounds = (res[c][rows].astype(float).tolist() for c in (key, TORQUE, BOUND))
    return verify_designs(designs, ids, keys, fast, bounds, fem_size, executor,
                          spec.material_files)  # fmt: skip


def verify_designs(
    designs: Sequence[ClutchDesign],
    ids: Sequence[int],
    values: Sequence[float],
    fast: Sequence[float],
    bounds: Sequence[float],
    fem_size: float,
    executor: Executor | None = None,
    materials: Sequence[MaterialFile] = (),
) -> list[VerifiedRow]:
    """Designs (with their ids, objective values, fast max torques and torque error bounds)
    re-solved by the FEM at ``fem_size`` (m) on ``executor`` (in this process when None),
    beside the single loop's torque: the sweep's and the optimiser's --verify-top.
    ``materials``: the user's material files the designs name (shipped to the workers)."""
    if not (math.isfinite(fem_size) and fem_size > 0):
        raise ParameterError(f"FEM size = {fem_size!r} m: must be finite and > 0")
    if executor is None:
        fem = [fem_max_torque(d, fem_size) for d in designs]
    else:
        mats = tuple(materials)
        futures = [executor.submit(fem_max_torque, d, fem_size, mats) for d in designs]
        fem = [f.result() for f in futures]
    circ = [_max_torque(d, "circuit") for d in designs]
    circ_bound = [circuit_error(d.clutch).bound for d in designs]
    rows_ = zip(ids, values, fast, fem, bounds, circ, circ_bound, strict=True)
    return [VerifiedRow(*row) for row in rows_]


def write_verified(path: str | Path, rows: Sequence[VerifiedRow], key: str, fem_size: float
                   ) -> Path:  # fmt: skip
    """The sidecar CSV: one row a design, each torque with the fidelity it came from."""
    fem = f"fem@{fem_size * 1e3:g}mm uniform"
    with atomic_path(path) as tmp, tmp.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in rows:
            w.writerow([r.design_id, key, repr(r.objective_value), repr(r.fast_torque),
                        "network (sweep fast path)", repr(r.fem_torque), fem, repr(r.error),
                        repr(r.bound), int(r.within_bound), repr(r.circuit_torque),
                        "circuit (single loop)", repr(r.circuit_error),
                        repr(r.circuit_bound), int(r.circuit_within_bound)])  # fmt: skip
    return Path(path)
