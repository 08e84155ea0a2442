"""Where the saturating circuit can be trusted: its torque error against the FEM, measured on
a grid over the design space (the data file `magnetics/data/circuit_error_map.json`, written
by `python benchmarks/measure_circuit_map.py`) and interpolated to any design.

The estimate is the multilinear interpolation of the signed error in gap, zone length,
drum bore and drum thickness at the design's drum count (no interpolation across drum
counts). Its bound adds a margin RANGE_FACTOR × v × 4·t(1 − t): v is the local variation
of the map (the range of the errors at the corners of the design's cell), t the design's
fractional position in the cell along the worst axis (the linear-interpolation remainder,
which vanishes at the nodes: a node is a measurement), and RANGE_FACTOR the largest miss
over v measured at off-grid designs. A design whose dimensions off the map's axes (shell,
coil, …) differ from the paper preset's is off the map, as is one outside the grid: its
error is unknown (NaN estimate, infinite bound, a note naming the fields), since those
dimensions move the error by tens of percent (shell 0.7 mm instead of 1.4: −34 %).

The reluctance network's error (``model="network"``) is not read off a grid: its bound covers
every section dimension and the ampere-turns, from a design of experiments with a stated
coverage (magnetics.network_bound); ``error_bound`` and ``circuit_error`` hand it over there
and need the current. The network's grid map (data/network_error_map.json) stays a
measurement of the model on the circuit's grid (benchmarks/measure_network_map.py).
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.params import preset
from magnetics.interpolation import _interp
from magnetics.network_bound import DEFAULT_MATERIALS, network_bound
from magnetics.network_bound import load as load_bound

#: The measured maps (data, not code), one per fast torque model: the circuit's written by
#: benchmarks/measure_circuit_map.py, the reluctance network's by
#: benchmarks/measure_network_map.py (from the stored FEM reference).
DATA_FILES = {
    "circuit": Path(__file__).parent / "data" / "circuit_error_map.json",
    "network": Path(__file__).parent / "data" / "network_error_map.json",
}
#: How each model is named in the notes.
LABELS = {"circuit": "saturating circuit", "network": "reluctance network"}


@dataclass(frozen=True)
class ErrorMap:
    """The stored map: signed circuit/FEM − 1 on a grid over ``axes`` (row-major, n_drums
    slowest), the coarse FEMs' error bounds, the off-grid checks and the interpolation
    margin factor (module docstring)."""

    base_preset: str
    reference_fem_size: float  # m
    axes: Mapping[str, tuple[float, ...]]
    errors: tuple[float, ...]
    fem_error_bound: Mapping[float, float]  # FEM size (m) -> largest error vs reference
    checks: tuple[tuple[float, ...], ...]  # (n_drums, gap, zone, bore, drum t, error)
    range_factor: float


@functools.lru_cache(maxsize=2)
def load(model: str = "circuit") -> ErrorMap:
    """The map of ``model`` ("circuit" | "network") from DATA_FILES (read once)."""
    d = json.loads(DATA_FILES[model].read_text())
    return ErrorMap(
        base_preset=d["base_preset"],
        reference_fem_size=float(d["reference_fem_size_m"]),
        axes=MappingProxyType({k: tuple(v) for k, v in d["axes"].items()}),
        errors=tuple(math.nan if e is None else float(e) for e in d["errors"]),
        fem_error_bound=MappingProxyType(
            {float(k): float(v) for k, v in d["fem_error_bound"].items()}
        ),
        checks=tuple(tuple(c) for c in d["checks"]),
        range_factor=float(d["range_factor"]),
    )


#: Fields neither the circuit nor the axisymmetric FEM sees (the hub holes).
AXISYMMETRIC_IGNORED = ("hub_holes", "hub_hole_diameter", "hub_hole_pitch_radius")


@dataclass(frozen=True)
class CircuitError:
    """The circuit's expected torque error on one design (relative, signed estimate)."""

    estimate: float  # circuit/FEM − 1 from the map; NaN outside it
    bound: float  # |estimate| + interpolation margin; inf outside the map
    notes: tuple[str, ...] = ()


@functools.lru_cache(maxsize=2)
def _grid(model: str = "circuit") -> tuple[Mapping[str, tuple[float, ...]], np.ndarray]:
    m = load(model)
    grid = np.array(m.errors, dtype=float).reshape([len(v) for v in m.axes.values()])
    grid.flags.writeable = False
    return m.axes, grid


@functools.lru_cache(maxsize=1)
def _base_off_axes() -> dict[str, Any]:
    """The base preset's fields that are not axes of the map (nor ignored by the solvers)."""
    m = load()
    base = preset(m.base_preset)
    skip = set(m.axes) | set(AXISYMMETRIC_IGNORED)
    return {f.name: getattr(base, f.name) for f in fields(base) if f.name not in skip}


def error_bound(
    p: Mapping[str, Any], model: str = "circuit", current: Any = None,
    material_set: str = DEFAULT_MATERIALS, features: Mapping[str, Any] | None = None,
) -> tuple[Any, Any, tuple[str, ...]]:  # fmt: skip
    """Vectorised core of :func:`circuit_error` over DrumClutch fields ``p`` (scalars or
    arrays, e.g. geometry.params.broadcast_fields): (estimate, bound, names of the fields
    off the map's axes that differ from the base preset somewhere), by ``model``'s map.
    The network's ("network") comes from magnetics.network_bound at ``current`` [A]
    (required there) and ``material_set``: (estimate, bound, the inputs outside its ranges
    or ("unmeasured",)); ``features``: the network's solution features at that current
    if the caller solved it (``solution_features``), else it is solved there."""
    if model == "network":
        if current is None:
            raise ValueError("error_bound(model='network') needs the current (A)")
        return network_bound(p, current, material_set, features)
    return map_bound(p, model)


def map_bound(p: Mapping[str, Any], model: str = "circuit") -> tuple[Any, Any, tuple[str, ...]]:
    """:func:`error_bound` by ``model``'s grid map (data/<model>_error_map.json): the
    circuit's bound; for the network, its grid measurement (the bound it reports is
    magnetics.network_bound's)."""
    m = load(model)
    axes, grid = _grid(model)
    est, spread, rng = _interp(axes, grid, {k: p[k] for k in axes})
    off = np.zeros(np.shape(est), bool)
    names = []
    for name, value in _base_off_axes().items():
        # off the map: the map holds these at the base preset's values; a shell of 0.7 mm
        # instead of 1.4 mm moves the error from +0.5 % to −34 % (issue 16), so no margin
        # stands for them: the error is unknown there
        differs = ~np.isclose(np.asarray(p[name], dtype=float), value, rtol=1e-9, atol=0.0)
        if np.any(differs):
            off = off | differs
            names.append(name)
    margin = m.range_factor * rng * spread
    est = np.where(off, np.nan, est)
    bound = np.where(np.isfinite(est), np.abs(est) + margin, np.inf)
    if np.ndim(est) == 0:
        return float(est), float(bound), tuple(names)
    return est, bound, tuple(names)


def circuit_error(
    clutch: Any, model: str = "circuit", current: float | None = None,
    material_set: str = DEFAULT_MATERIALS, features: Mapping[str, Any] | None = None,
) -> CircuitError:  # fmt: skip
    """The map's estimate and bound of ``model``'s torque error on ``clutch`` (the
    saturating circuit by default; "network": the reluctance network's bound over every
    dimension at ``current`` [A] and ``material_set``, magnetics.network_bound, with the
    network's ``features`` at that current if the caller solved it, as in ``error_bound``)."""
    if model == "network":
        return _network_error(clutch, current, material_set, features)
    m = load(model)
    label = LABELS[model]
    est, bound, off = error_bound({f.name: getattr(clutch, f.name) for f in fields(clutch)},
                                  model)  # fmt: skip
    if off and not math.isfinite(est):
        return CircuitError(
            math.nan,
            math.inf,
            (
                f"{label}: off the measured error map — the map holds "
                f"{', '.join(off)} at the {m.base_preset} preset's values and this design "
                f"differs; its error is unknown (check it with --fidelity reference)",
            ),
        )
    if not math.isfinite(est):
        axes = _grid(model)[0]
        where = ", ".join(
            f"{k} = {v:g}" if k == "n_drums" else f"{k} = {v * 1e3:g} mm"
            for k, v in ((k, getattr(clutch, k)) for k in axes)
        )
        return CircuitError(
            math.nan,
            math.inf,
            (
                f"{label}: {where} is outside the measured error map "
                f"(benchmarks/measure_{model}_map.py); its error is unknown",
            ),
        )
    notes: tuple[str, ...] = ()
    return CircuitError(est, bound, notes)


def _network_error(
    clutch: Any, current: float | None, material_set: str,
    features: Mapping[str, Any] | None = None,
) -> CircuitError:  # fmt: skip
    """The network's error estimate and bound on ``clutch`` at ``current`` (notes say why
    it is unknown: inputs outside the measured ranges, or a material set never measured)."""
    if current is None:
        raise ValueError("circuit_error(model='network') needs the current (A)")
    p = {f.name: getattr(clutch, f.name) for f in fields(clutch)}
    est, bound, why = network_bound(p, current, material_set, features)
    label = LABELS["network"]
    if why == ("unmeasured",):
        note = (f"{label}: unmeasured — its error was never measured with the materials "
                f"{material_set} (benchmarks/measure_fem_doe.py measures "
                f"{DEFAULT_MATERIALS}); check it with --fidelity reference")  # fmt: skip
        return CircuitError(math.nan, math.inf, (note,))
    if why:
        from_doe = network_bound_ranges()
        where = ", ".join(_in_range(k, p, current, from_doe[k]) if k in from_doe else k
                          for k in why)  # fmt: skip
        note = (f"{label}: off the measured error map — {where}; its error is unknown "
                f"(check it with --fidelity reference)")  # fmt: skip
        return CircuitError(math.nan, math.inf, (note,))
    return CircuitError(est, bound, ())


def network_bound_ranges(
    material_set: str = DEFAULT_MATERIALS,
) -> Mapping[str, tuple[float, float]]:
    """The inputs' ranges the network's bound was measured over (SI; ampere_turns in A)."""
    m = load_bound(material_set)
    return {} if m is None else m.ranges


def _in_range(name: str, p: Mapping[str, Any], current: float, rng: tuple[float, float]) -> str:
    lo, hi = rng
    if name == "ampere_turns":
        v = float(p["coil_turns"]) * float(current)
        return f"N·I = {v:g} A outside [{lo:g}, {hi:g}] A"
    if name == "n_drums":
        return f"n_drums = {p[name]} outside [{lo:g}, {hi:g}]"
    return f"{name} = {p[name] * 1e3:g} mm outside [{lo * 1e3:g}, {hi * 1e3:g}] mm"
