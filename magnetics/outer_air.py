"""The air outside the shell: its permeance between the two poles, in parallel with the back
iron, from a solved exterior field problem (issue 12).

The shell (outer radius R) is a steel cylinder: pole A, the back iron over the band, pole B.
Outside it the air is linear, so its flux is the solution of Laplace's equation for the
magnetic scalar potential φ, ∇·(r ∇φ) = 0 in the axisymmetric (r, z) half-plane outside
the shell ([jackson1999] §5.9; the scalar potential in a current-free region), with φ set
on the shell's surface:

- on the outer face r = R: +½ along pole A, −½ along pole B, falling linearly between
  them over the back iron (the band, length b): the back iron's flux is uniform along the
  band, so its H and the potential's fall along it are too. The FEM puts 87–90 % of the
  surface's fall over the band on the two designs of docs/magnetics.md ("The shell,
  traced"), the rest in the poles' last millimetres;
- on each end face (z at the pole's outer face): the pole's ±½ over the pole ring
  (r from the pole's inner radius ρ to R), 0 inside it (the core, drums and fluid there sit
  between the two poles' potentials; the stainless end caps are air to the field);
- on the domain's far edges no flux crosses (∂φ/∂n = 0), as in the FEM, whose vector
  potential is 0 on an air box 2·max(R, length) beyond the clutch (``magnetics.fem.grid``):
  the same rule here on the shell's length. The open exterior carries ~2 % more (the
  table's ``open_boundary_ratio``).

The permeance is the flux through the band's mid-plane outside the shell per unit
potential difference, P = μ0·R·p(b/R, a_A/R, a_B/R, ρ/R) (a_A, a_B the poles' axial
lengths): p from a Q1 finite-element solve on a tensor grid graded away from the shell,
the flux as the reaction on the shell's nodes past the mid-plane (half on it).
``solve`` is that solve (scikit-fem, imported only there); ``permeance`` interpolates the
stored table (``DATA_FILE``, written by ``python benchmarks/build_outer_air.py``)
multilinearly in (ln b/R, ln a_A/R, ln a_B/R, ρ/R), clamped to the table's ranges. The
table's own checks (off-node solves against the interpolation, and the solve at half the
cell size) are stored with it and tested (tests/magnetics/test_outer_air.py).
"""

from __future__ import annotations

import functools
import itertools
import json
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.validation import ParameterError, check_choice
from magnetics.interpolation import interpolate
from magnetics.materials import MU0

FloatArray = NDArray[np.float64]
DATA_FILE = Path(__file__).parent / "data" / "outer_air.json"
#: The table's axes: the band (back iron) length, the poles' axial lengths (each from the
#: band's end to the pole's outer face), all over R, and the poles' inner radius over R.
AXES: Mapping[str, tuple[float, ...]] = MappingProxyType({
    "band": tuple(float(x) for x in np.geomspace(0.05, 4.0, 10)),
    "pole_a": tuple(float(x) for x in np.geomspace(0.05, 4.0, 10)),
    "pole_b": tuple(float(x) for x in np.geomspace(0.05, 4.0, 10)),
    "pole_radius": (0.2, 0.4, 0.6, 0.75, 0.85, 0.95),
})  # fmt: skip
_LOG_AXES = ("band", "pole_a", "pole_b")  # interpolated in ln
SIZE = 0.02  # the solve's cell size on the shell's surface, over R (module docstring)
GROWTH = 1.15  # the cells grow by this factor per cell away from the shell
BOXES = ("fem", "open")
BOX_PAD = {"fem": 2.0, "open": 20.0}  # the air box's margin, × max(R, the shell's length)


def _lines(breaks: FloatArray, size: float, lo: float, hi: float) -> FloatArray:
    """Grid lines: cells ≤ size between consecutive ``breaks``, growing by GROWTH per cell
    outwards to ``lo`` and ``hi``."""
    inner = [np.linspace(a, b, max(2, int(np.ceil((b - a) / size))) + 1)
             for a, b in itertools.pairwise(breaks)]  # fmt: skip
    x = np.unique(np.concatenate(inner))
    out = [x]
    for start, end, sign in ((x[-1], hi, 1.0), (x[0], lo, -1.0)):
        pts, step = [start], size
        while sign * (pts[-1] - end) < 0:
            step *= GROWTH
            pts.append(pts[-1] + sign * step)
        out.append(np.array(pts))
    return np.unique(np.concatenate(out))


def solve(
    band: float, pole_a: float, pole_b: float, pole_radius: float, size: float = SIZE,
    box: str = "fem",
) -> float:  # fmt: skip
    """p = P/(μ0·R) of one shell, all lengths over R (module docstring); ``size`` the cells
    on the shell's surface, ``box`` "fem" (the FEM's air box) or "open" (10× farther)."""
    import skfem
    from scipy.sparse.linalg import spsolve
    from skfem.helpers import dot, grad

    check_choice("box", box, BOXES)
    for name, v in (("band", band), ("pole_a", pole_a), ("pole_b", pole_b)):
        if not v > 0:
            raise ParameterError(f"outer air: {name} = {v} must be > 0 (a length over R)")
    if not 0 < pole_radius < 1:
        raise ParameterError(f"outer air: pole_radius = {pole_radius} must be in (0, 1) (over R)")
    h = min(size, band / 6, pole_a / 6, pole_b / 6)
    z0, z1 = -0.5 * band - pole_a, 0.5 * band + pole_b
    pad = BOX_PAD[box] * max(1.0, z1 - z0)
    rs = _lines(np.array([0.0, pole_radius, 1.0]), h, 0.0, 1.0 + pad)
    zs = _lines(np.array([z0, -0.5 * band, 0.0, 0.5 * band, z1]), h, z0 - pad, z1 + pad)
    mesh = skfem.MeshQuad.init_tensor(rs[rs >= 0.0], zs)
    c = mesh.p[:, mesh.t].mean(axis=1)
    air = np.flatnonzero(~((c[0] < 1.0) & (c[1] > z0) & (c[1] < z1)))
    basis = skfem.Basis(mesh, skfem.ElementQuad1(), intorder=2, elements=air)

    @skfem.BilinearForm
    def laplace(u, v, w):  # type: ignore[no-untyped-def]  # ∇·(r∇φ) = 0, axisymmetric
        return w.x[0] * dot(grad(u), grad(v))

    k = laplace.assemble(basis).tocsr()
    r, z = mesh.p
    tol = 1e-9
    shell = (r <= 1.0 + tol) & (z >= z0 - tol) & (z <= z1 + tol)
    end = (np.abs(z - z0) < tol) | (np.abs(z - z1) < tol)
    phi = np.zeros(mesh.nvertices)
    face = np.clip(-z / band, -0.5, 0.5)  # +½ pole A, linear over the band, −½ pole B
    ring = np.where(r >= pole_radius - tol, np.where(z < 0, 0.5, -0.5), 0.0)
    phi[shell] = np.where(end, ring, face)[shell]
    free, fixed = np.flatnonzero(~shell), np.flatnonzero(shell)
    phi[free] = spsolve(k[free][:, free].tocsc(), -(k[free][:, fixed] @ phi[fixed]))
    reaction = k @ phi  # the flux leaving each node of the shell's surface (over 2π·μ0)
    past = np.where(z > tol, 1.0, np.where(np.abs(z) <= tol, 0.5, 0.0))
    return float(-2.0 * np.pi * np.sum((reaction * past)[shell]))


@functools.lru_cache(maxsize=1)
def load() -> tuple[np.ndarray, Mapping[str, Any]]:
    """(the table p on AXES, its metadata) from DATA_FILE (read once)."""
    d = json.loads(DATA_FILE.read_text())
    axes = {k: tuple(v) for k, v in d["axes"].items()}
    if axes != {k: tuple(v) for k, v in AXES.items()}:
        raise RuntimeError(
            f"{DATA_FILE}: its axes are not magnetics.outer_air.AXES; rebuild it with "
            "python benchmarks/build_outer_air.py"
        )
    shape = tuple(len(v) for v in AXES.values())
    return np.asarray(d["p"], dtype=float).reshape(shape), MappingProxyType(d)


def _point(band: ArrayLike, pole_a: ArrayLike, pole_b: ArrayLike, pole_radius: ArrayLike):  # type: ignore[no-untyped-def]  # fmt: skip
    """The interpolation coordinates (ln of the length axes), clamped to the table."""
    raw = {"band": band, "pole_a": pole_a, "pole_b": pole_b, "pole_radius": pole_radius}
    out = {}
    for name, v in raw.items():
        a = AXES[name]
        v = np.clip(np.asarray(v, dtype=float), a[0], a[-1])
        out[name] = np.log(v) if name in _LOG_AXES else v
    return out


@functools.lru_cache(maxsize=1)
def _log_axes() -> Mapping[str, tuple[float, ...]]:
    return {k: tuple(np.log(v)) if k in _LOG_AXES else v for k, v in AXES.items()}


def unit_permeance(
    band: ArrayLike, pole_a: ArrayLike, pole_b: ArrayLike, pole_radius: ArrayLike
) -> FloatArray:
    """p = P/(μ0·R) from the stored table (lengths over R; clamped to AXES)."""
    table, _ = load()
    return np.asarray(
        interpolate(_log_axes(), table, _point(band, pole_a, pole_b, pole_radius), node_axes=0),
        dtype=float,
    )


def permeance(
    radius: ArrayLike, band: ArrayLike, pole_a: ArrayLike, pole_b: ArrayLike,
    pole_radius: ArrayLike,
) -> FloatArray:  # fmt: skip
    """Permeance (H) of the air outside a shell of outer ``radius`` (m) between its poles,
    at the band's mid-plane (module docstring); ``band``, ``pole_a``, ``pole_b`` (the
    poles' axial lengths) and ``pole_radius`` (their inner radius) in m."""
    r = np.asarray(radius, dtype=float)
    return MU0 * r * unit_permeance(
        np.asarray(band) / r, np.asarray(pole_a) / r, np.asarray(pole_b) / r,
        np.asarray(pole_radius) / r,
    )  # fmt: skip
