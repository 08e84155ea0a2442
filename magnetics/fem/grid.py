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

import ctypes
import functools
import itertools
import math
import os
import resource
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from geometry.validation import ParameterError, check_choice
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


def _lines(section: Section, h: float, mesh: str) -> tuple[FloatArray, FloatArray]:
    """The grid's r and z lines at target size ``h`` (cheap: no mesh is built)."""
    R, z0, z1 = section.r_max, section.z_min, section.z_max
    pad = 2.0 * max(R, z1 - z0)
    fr, fz = _fine_sets(section) if mesh == "graded" else (None, None)
    rs = _axis([x for g in section.regions for x in (g.r0, g.r1)], 0.0, R + pad, h, (0.0, R), fr)
    zs = _axis([x for g in section.regions for x in (g.z0, g.z1)], z0 - pad, z1 + pad, h,
               (z0, z1), fz)  # fmt: skip
    return rs, zs


#: bytes a solve needs per grid node and its fixed part: measured peak RSS of one Newton
#: solve of the paper preset at 0.5/0.25/0.12/0.08 mm (3.6e3 … 7.1e4 nodes: 81 … 376 MB,
#: 4.4 kB a node; SuperLU's fill grows slowly with the size), with a 35 % margin.
BYTES_PER_NODE = 6000
BYTES_FIXED = 100e6


#: s of one Newton solve per grid node: the same measurement (10 005 nodes: 2.0 s,
#: 70 884 nodes: 15.5 s, grid included, one core of a loaded 2-core machine).
SECONDS_PER_NODE = 2.2e-4


def time_estimate(section: Section, size: float, solves: int, mesh: str = "uniform") -> float:
    """s for ``solves`` FEM solves of ``section`` at element ``size`` (SECONDS_PER_NODE)."""
    return solves * SECONDS_PER_NODE * memory_estimate(section, size, mesh)[0]


#: GiB the whole process may hold while one FEM solve runs (``MRCLUTCH_FEM_MEMORY_GB``):
#: issue 44's limit for any accepted single-design command
DEFAULT_MEMORY_GB = 1.0


def memory_budget() -> float:
    """Bytes the process may hold while one FEM solve runs, what it already holds included
    (``check_memory``): ``MRCLUTCH_FEM_MEMORY_GB`` (default DEFAULT_MEMORY_GB), never more
    than half the machine's memory nor more than an address-space limit (RLIMIT_AS) allows."""
    default = DEFAULT_MEMORY_GB * 2**30
    try:
        budget = float(os.environ.get("MRCLUTCH_FEM_MEMORY_GB", str(DEFAULT_MEMORY_GB))) * 2**30
    except ValueError:
        budget = default
    if not math.isfinite(budget) or budget <= 0:
        budget = default
    try:
        budget = min(budget, 0.5 * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        pass
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    if soft != resource.RLIM_INFINITY:
        budget = min(budget, 0.6 * soft)
    return budget


def held_memory() -> float:
    """Bytes this process holds now: its resident set (``/proc/self/statm``; shared
    libraries' pages included, as the peak RSS a user measures counts them) once the C
    heap's free pages went back to the system (glibc ``malloc_trim``: what an earlier step
    freed is not counted as held), 0 where the system does not say."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass  # not glibc: the resident set as it is
    try:
        with open("/proc/self/statm", encoding="ascii") as f:
            return float(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError, AttributeError):
        return 0.0


def memory_estimate(section: Section, size: float, mesh: str = "uniform") -> tuple[int, float]:
    """(grid nodes, bytes) of one FEM solve of ``section`` at element ``size`` (m)."""
    rs, zs = _lines(section, size, mesh)
    nodes = rs.size * zs.size
    return nodes, BYTES_FIXED + BYTES_PER_NODE * nodes


def check_memory(
    section: Section, size: float, mesh: str = "uniform", held: float | None = None
) -> None:
    """Refuse, before any mesh is built, a size whose solve would not fit the budget
    (``memory_budget``) beside the ``held`` bytes the process holds already (default: its
    resident set now, ``held_memory``), naming the smallest size that fits."""
    budget = memory_budget()
    held = held_memory() if held is None else float(held)
    room = budget - held
    if not (math.isfinite(size) and size > 0):
        raise ParameterError(f"FEM element size = {size!r} m: must be finite and > 0")
    nodes, need = memory_estimate(section, size, mesh)
    if need <= room:
        return
    beside = f" beside the {held / 2**30:.2g} GiB this process holds" if held > 0 else ""
    lo, hi = size, max(size, 5e-3)  # bisection in log size: fits at hi, not at lo
    if memory_estimate(section, hi, mesh)[1] > room:
        raise ParameterError(
            f"the FEM needs {memory_estimate(section, hi, mesh)[1] / 2**30:.2g} GiB at any "
            f"element size here{beside}, above the {budget / 2**30:.2g} GiB budget "
            f"(MRCLUTCH_FEM_MEMORY_GB)"
        )
    for _ in range(30):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if memory_estimate(section, mid, mesh)[1] <= room else (mid, hi)
    raise ParameterError(
        f"FEM element size {size * 1e3:g} mm: {nodes:.3g} grid nodes need about "
        f"{need / 2**30:.2g} GiB{beside}, above the {budget / 2**30:.2g} GiB budget "
        f"(MRCLUTCH_FEM_MEMORY_GB); the smallest size that fits is "
        f"{math.ceil(hi * 1e6) / 1e3:g} mm"
    )


def build_grid(
    section: Section,
    size: float | None = None,
    materials: Mapping[str, Magnetic] | None = None,
    *,
    mesh: str = "uniform",
    lines: tuple[FloatArray, FloatArray] | None = None,
) -> Grid:
    """The grid of ``section`` at target element ``size`` (m) inside the clutch, ``mesh``
    "uniform" (cells ≤ size everywhere inside) or "graded" (module docstring).
    ``lines``: the (r, z) grid lines to use instead (each must include every region edge;
    ``magnetics.fem.gap_shape`` moves a grid's lines with the edges for a shape derivative)."""
    check_choice("mesh", mesh, MESHES)
    mats = MATERIALS if materials is None else materials
    h = DEFAULT_SIZE if size is None else float(size)
    check_memory(section, h, mesh)
    import skfem

    rs, zs = _lines(section, h, mesh) if lines is None else lines
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
        self.wr = wr  # (the ν term's ∇φ_i·∇φ_j/r is summed per step, not stored: a
        # (4, 4, E, Q) array was 0.5 kB a grid node, 11 % of a solve's peak, issue 44)
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
        k = np.einsum("ikeq,jkeq,eq->ije", self.grads, self.grads, nu * self.wr)
        k += np.einsum("ieq,jeq,eq->ije", gi, gi, dnu * self.wr)
        data = np.bincount(self._slot, k[self._keep], self._nnz)
        return self._csr((data, *self._pattern[:2]), shape=self._pattern[2])
