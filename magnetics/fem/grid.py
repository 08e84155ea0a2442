"""The FEM's grid: a tensor grid of bilinear quadrilaterals whose lines include every
region edge of the section (no element straddles two materials), refined to the target
size inside the clutch and graded (×1.5) outwards to an air box 3× the clutch's size; each
element's material and the coil's smeared current density."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from magnetics.materials import MATERIALS, Magnetic, magnetic

FloatArray = NDArray[np.float64]
DEFAULT_SIZE = 0.25e-3  # m, element size inside the clutch (< 5 s per current, paper preset)


def _axis(edges: list[float], lo: float, hi: float, size: float, inner: tuple[float, float]):  # type: ignore[no-untyped-def]
    """Grid lines through every edge; cells ≤ size inside ``inner``, graded (×1.5) outside."""
    e = np.unique(np.round(np.array([lo, hi, *edges]), 12))
    out = [e[0]]
    for a, b in itertools.pairwise(e):
        if b <= inner[0] + 1e-12 or a >= inner[1] - 1e-12:  # air outside the clutch: grade
            n = max(1, math.ceil(math.log1p((b - a) / size * 0.5) / math.log(1.5)))
            n = min(n, 12)
            w = 1.5 ** np.arange(n)
            w = w if a >= inner[1] - 1e-12 else w[::-1]
            out.extend(a + (b - a) * np.cumsum(w) / w.sum())
        else:
            n = max(1, math.ceil((b - a) / size - 1e-9))
            out.extend(a + (b - a) * np.arange(1, n + 1) / n)
    return np.array(out)


@dataclass(frozen=True)
class Grid:
    """Mesh, basis and per-element data of one section at one element size."""

    section: Section
    r_lines: FloatArray
    z_lines: FloatArray
    mesh: Any  # skfem.MeshQuad
    basis: Any  # skfem.Basis (bilinear, 2nd-order quadrature)
    names: tuple[str, ...]  # material of index k
    material_index: NDArray[np.int64]  # per element
    materials: tuple[Magnetic, ...]  # index k's B–H
    centre: FloatArray  # (2, elements): element centres (r, z)
    r_qp: FloatArray  # r at the quadrature points, (elements, points)
    coil_mask: NDArray[np.bool_]  # elements of the coil
    coil_area: float  # m²
    fixed: NDArray[np.int64]  # Dirichlet dofs (ψ = 0: axis and box)


def build_grid(
    section: Section, size: float | None = None, materials: Mapping[str, Magnetic] | None = None
) -> Grid:
    """The grid of ``section`` at target element ``size`` (m) inside the clutch."""
    import skfem

    mats = MATERIALS if materials is None else materials
    h = DEFAULT_SIZE if size is None else float(size)
    R, z0, z1 = section.r_max, section.z_min, section.z_max
    pad = 2.0 * max(R, z1 - z0)
    rs = _axis([x for g in section.regions for x in (g.r0, g.r1)], 0.0, R + pad, h, (0.0, R))
    zs = _axis([x for g in section.regions for x in (g.z0, g.z1)], z0 - pad, z1 + pad, h, (z0, z1))
    mesh = skfem.MeshQuad.init_tensor(rs, zs)
    basis = skfem.Basis(mesh, skfem.ElementQuad1(), intorder=2)

    # Material and source per element (centroid lookup; every region edge is a grid line).
    cen = mesh.p[:, mesh.t].mean(axis=1)
    names = ["air", *sorted({g.material for g in section.regions})]
    idx = np.zeros(mesh.t.shape[1], dtype=np.int64)
    for g in section.regions:
        inside = (cen[0] > g.r0) & (cen[0] < g.r1) & (cen[1] > g.z0) & (cen[1] < g.z1)
        idx[inside] = names.index(g.material)
    coil = section.region("coil")
    in_coil = (cen[0] > coil.r0) & (cen[0] < coil.r1) & (cen[1] > coil.z0) & (cen[1] < coil.z1)
    return Grid(
        section, rs, zs, mesh, basis, tuple(names), idx, tuple(magnetic(n, mats) for n in names),
        cen, np.asarray(basis.global_coordinates())[0], in_coil, coil.area,
        basis.get_dofs().all(),
    )  # fmt: skip
