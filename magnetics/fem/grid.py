"""The FEM's grid: a tensor grid of bilinear quadrilaterals whose lines include every
region edge of the section (no element straddles two materials), refined to the target
size inside the clutch and graded (×1.5) outwards to an air box 3× the clutch's size; each
element's material and the coil's smeared current density.

Two meshes of the clutch (``mesh=``):

- ``"uniform"`` (the default, the error map's reference): cells ≤ size everywhere inside
  the clutch.
- ``"graded"``: cells of ``size`` on a fine set, growing away from it. The target cell
  size at distance d (m) from the fine set is s(d) = size·min(GRADED_CAP, 1 + d/
  GRADED_LENGTH): neighbouring cells grow geometrically by ≈ 1 + size/GRADED_LENGTH, and
  the family is a fixed mapping of the uniform one (s ∝ size), so the error still falls
  with size at the uniform mesh's rate. A cell is its target averaged over its width (n
  equal steps of ∫ dx/s), so the one next to a fine point is ≤ size·(1 + size/ℓ).
  The fine set: in r, from the axis to the outer radius of the gap/drum stack — the
  core carries all the flux and saturates first (refining r in the core alone makes
  70–90 % of the torque's change from 0.25 to 0.125 mm at 4–7 A on the paper preset,
  the stack the rest at 2 A; the shell under 5 %);
  in z, every region edge inside the gaps' axial span (zone ends, band ends, drum tips),
  where the field turns. Every region edge stays a grid line.

``Grid.assembly`` (``Assembly``): the forms' current-independent parts on the grid, built
once and reused by every Newton step and every current.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from geometry.validation import check_choice
from magnetics.materials import MATERIALS, Magnetic, magnetic

FloatArray = NDArray[np.float64]
DEFAULT_SIZE = 0.25e-3  # m, element size inside the clutch (< 5 s per current, paper preset)
MESHES = ("uniform", "graded")
GRADED_LENGTH = 0.5e-3  # m: the graded cell size doubles 0.5 mm away from the fine set
GRADED_CAP = 4.0  # the graded cells are at most 4× size inside the clutch


def _graded_lines(a: float, b: float, size: float, fine: FloatArray) -> FloatArray:
    """Interior lines and b of [a, b], cells of target size(x) = size·min(cap, 1 + d/ℓ),
    d the distance from x to the nearest point of ``fine`` (points, or pairs of interval
    ends, see ``_axis``): n = ⌈∫ dx/size(x)⌉ cells, equal steps of that integral."""
    x = np.linspace(a, b, 257)
    d = np.min(np.abs(x[:, None] - fine[None, :]), axis=1) if fine.size else np.full_like(x, np.inf)
    target = size * np.minimum(GRADED_CAP, 1.0 + d / GRADED_LENGTH)
    w = 1.0 / target
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(x))])
    n = max(1, math.ceil(cum[-1] - 1e-9))
    return np.interp(np.linspace(0.0, cum[-1], n + 1)[1:], cum, x)


def _axis(edges: list[float], lo: float, hi: float, size: float, inner: tuple[float, float],
          fine: FloatArray | None = None):  # type: ignore[no-untyped-def]  # fmt: skip
    """Grid lines through every edge; cells ≤ size inside ``inner`` (or graded away from
    the points ``fine``, ``_graded_lines``), graded (×1.5) outside."""
    e = np.unique(np.round(np.array([lo, hi, *edges]), 12))
    out = [e[0]]
    for a, b in itertools.pairwise(e):
        if b <= inner[0] + 1e-12 or a >= inner[1] - 1e-12:  # air outside the clutch: grade
            n = max(1, math.ceil(math.log1p((b - a) / size * 0.5) / math.log(1.5)))
            n = min(n, 12)
            w = 1.5 ** np.arange(n)
            w = w if a >= inner[1] - 1e-12 else w[::-1]
            out.extend(a + (b - a) * np.cumsum(w) / w.sum())
        elif fine is not None:
            out.extend(_graded_lines(a, b, size, fine))
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
    mesh_kind: str = "uniform"  # "uniform" | "graded" (module docstring)

    @functools.cached_property
    def assembly(self):  # type: ignore[no-untyped-def]
        """The current-independent parts of the forms on this grid (``Assembly``),
        built on first use and kept: every Newton step and every current reuses them."""
        return Assembly(self)


def _fine_sets(section: Section) -> tuple[FloatArray, FloatArray]:
    """The graded mesh's fine points in r and in z (module docstring): r, a dense fill
    (10 µm, so d = 0 across it) of the axis to the gap/drum stack's outer radius; z, every
    region edge inside the gaps' axial span."""
    rb = max(g.r_outer for g in section.gaps)
    za = min(g.z0 for g in section.gaps)
    zb = max(g.z1 for g in section.gaps)
    r = np.linspace(0.0, rb, max(2, math.ceil(rb / 1e-5) + 1))
    zs = np.array([x for g in section.regions for x in (g.z0, g.z1)])
    return r, np.unique(zs[(zs >= za - 1e-12) & (zs <= zb + 1e-12)])


def build_grid(
    section: Section,
    size: float | None = None,
    materials: Mapping[str, Magnetic] | None = None,
    *,
    mesh: str = "uniform",
) -> Grid:
    """The grid of ``section`` at target element ``size`` (m) inside the clutch, ``mesh``
    "uniform" (cells ≤ size everywhere inside) or "graded" (module docstring)."""
    import skfem

    check_choice("mesh", mesh, MESHES)
    mats = MATERIALS if materials is None else materials
    h = DEFAULT_SIZE if size is None else float(size)
    R, z0, z1 = section.r_max, section.z_min, section.z_max
    pad = 2.0 * max(R, z1 - z0)
    fr, fz = _fine_sets(section) if mesh == "graded" else (None, None)
    rs = _axis([x for g in section.regions for x in (g.r0, g.r1)], 0.0, R + pad, h, (0.0, R), fr)
    zs = _axis([x for g in section.regions for x in (g.z0, g.z1)], z0 - pad, z1 + pad, h,
               (z0, z1), fz)  # fmt: skip
    quads = skfem.MeshQuad.init_tensor(rs, zs)
    basis = skfem.Basis(quads, skfem.ElementQuad1(), intorder=2)

    # Material and source per element (centroid lookup; every region edge is a grid line).
    cen = quads.p[:, quads.t].mean(axis=1)
    names = ["air", *sorted({g.material for g in section.regions})]
    idx = np.zeros(quads.t.shape[1], dtype=np.int64)
    for g in section.regions:
        inside = (cen[0] > g.r0) & (cen[0] < g.r1) & (cen[1] > g.z0) & (cen[1] < g.z1)
        idx[inside] = names.index(g.material)
    coil = section.region("coil")
    in_coil = (cen[0] > coil.r0) & (cen[0] < coil.r1) & (cen[1] > coil.z0) & (cen[1] < coil.z1)
    return Grid(
        section, rs, zs, quads, basis, tuple(names), idx, tuple(magnetic(n, mats) for n in names),
        cen, np.asarray(basis.global_coordinates())[0], in_coil, coil.area,
        basis.get_dofs().all(), mesh,
    )  # fmt: skip


class Assembly:
    """The forms of ``forms`` assembled without scikit-fem's generic loop, on one grid.

    Everything that does not depend on the field is computed once per grid (the grid and
    the forms' linear parts do not change with the current): the basis gradients times
    the quadrature weights over r, the load per unit current density, the sparsity
    pattern of the free–free block and the map of each element entry into it. A Newton
    step is then two einsums and one bincount. The same sums as ``skfem.asm`` of
    ``forms.forms()`` (tests/magnetics/test_fem.py checks them to 1e-12)."""

    def __init__(self, grid: Grid) -> None:
        from scipy import sparse

        basis = grid.basis
        self.grid = grid
        self.n = basis.N
        self.dofs = np.asarray(basis.element_dofs)  # (4, E)
        grads = np.stack([np.asarray(b[0].grad) for b in basis.basis])  # (4, 2, E, Q)
        self.grads = grads
        wr = np.asarray(basis.dx) / grid.r_qp  # dx/r, (E, Q)
        self.wr = wr
        #: ∫ (∇φ_i·∇φ_j)/r per quadrature point, (4, 4, E, Q): the ν term's fixed part
        self.gg_wr = np.einsum("ikeq,jkeq,eq->ijeq", grads, grads, wr)
        #: ∫ φ_i dr dz per element, (4, E): the load of a unit current density
        self.phi_dx = np.stack([(np.asarray(b[0]) * basis.dx).sum(1) for b in basis.basis])
        free = np.ones(self.n, dtype=bool)
        free[grid.fixed] = False
        self.free = np.flatnonzero(free)
        red = np.full(self.n, -1)
        red[self.free] = np.arange(self.free.size)
        rows = red[np.broadcast_to(self.dofs[:, None, :], (4, 4, self.dofs.shape[1]))]
        cols = red[np.broadcast_to(self.dofs[None, :, :], (4, 4, self.dofs.shape[1]))]
        keep = (rows >= 0) & (cols >= 0)
        self._keep = keep
        m = self.free.size
        key = rows[keep].astype(np.int64) * m + cols[keep]
        uniq, self._slot = np.unique(key, return_inverse=True)  # sorted: CSR order
        indptr = np.searchsorted(uniq // m, np.arange(m + 1))
        self._pattern = (uniq % m, indptr, (m, m))
        self._nnz = uniq.size
        self._csr = sparse.csr_matrix
        #: the last factorised Jacobian (newton._step's preconditioner), None until then
        self.factors: Any = None
        # elements of each material, for ν(|B|)
        self._by_material = [np.flatnonzero(grid.material_index == k)
                             for k in range(len(grid.materials))]  # fmt: skip

    def load(self, j_element: FloatArray) -> FloatArray:
        """∫ J φ_i (all dofs) of a current density constant per element (A/m²)."""
        return np.bincount(self.dofs.ravel(), (self.phi_dx * j_element).ravel(), self.n)

    def gradient(self, psi: FloatArray) -> FloatArray:
        """∇ψ at the quadrature points, (2, E, Q)."""
        return np.einsum("ie,ikeq->keq", psi[self.dofs], self.grads)

    def nu_terms(self, psi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``forms.nu_terms`` (same values), from the stored gradients."""
        g = self.gradient(psi)
        b = np.sqrt(g[0] ** 2 + g[1] ** 2) / self.grid.r_qp
        nu = np.empty_like(b)
        dnu = np.zeros_like(b)
        for m, sel in zip(self.grid.materials, self._by_material, strict=True):
            if not sel.size:
                continue
            bb = b[sel]
            hh = m.h_of_b(bb)
            dh = m.dh_db(bb)
            small = bb < 1e-12
            nu[sel] = np.where(small, dh, hh / np.where(small, 1.0, bb))
            dnu[sel] = np.where(small, 0.0, (dh * bb - hh) / np.where(small, 1.0, bb) ** 3)
        return g, nu, dnu / self.grid.r_qp**2

    def residual(self, g: FloatArray, nu: FloatArray, f: FloatArray) -> FloatArray:
        """∫ ν ∇ψ·∇φ_i / r − ∫ J φ_i (all dofs), ``f`` the load."""
        gi = np.einsum("keq,ikeq->ieq", g, self.grads)
        return np.bincount(self.dofs.ravel(), np.einsum("ieq,eq->ie", gi, nu * self.wr).ravel(),
                           self.n) - f  # fmt: skip

    def jacobian(self, g: FloatArray, nu: FloatArray, dnu: FloatArray) -> Any:
        """The Jacobian's free–free block (CSR), ``forms.forms()[0]`` condensed."""
        gi = np.einsum("keq,ikeq->ieq", g, self.grads)
        k = np.einsum("ijeq,eq->ije", self.gg_wr, nu)
        k += np.einsum("ieq,jeq,eq->ije", gi, gi, dnu * self.wr)
        data = np.bincount(self._slot, k[self._keep], self._nnz)
        return self._csr((data, *self._pattern[:2]), shape=self._pattern[2])
