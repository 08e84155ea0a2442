"""The weak form of axisymmetric magnetostatics in the flux function ψ = r·A_φ and its
Newton linearisation (Meunier, *The Finite Element Method for Electromagnetic Modeling*,
2008, §5.3):

    ∫ ν(|B|) (1/r) ∇ψ·∇v dr dz = ∫ J_φ v dr dz,   |B| = |∇ψ|/r,

with ν = H(B)/B per material; the Jacobian adds the anisotropic term of ∂ν/∂(|B|²)."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from magnetics.fem.grid import Grid

FloatArray = NDArray[np.float64]


def nu_terms(grid: Grid, psi: FloatArray) -> tuple[Any, FloatArray, FloatArray]:
    """(∇ψ, ν, ∂ν/∂(b²)·2/r²) at the quadrature points for the field ψ."""
    r_qp, idx = grid.r_qp, grid.material_index
    g = grid.basis.interpolate(psi).grad
    b = np.sqrt(g[0] ** 2 + g[1] ** 2) / r_qp
    nu = np.empty_like(b)
    dnu = np.zeros_like(b)
    for k, m in enumerate(grid.materials):
        sel = idx == k
        if not sel.any():
            continue
        bb = b[sel]
        hh = m.h_of_b(bb)
        small = bb < 1e-12
        nu_k = np.where(small, m.dh_db(bb), hh / np.where(small, 1.0, bb))
        nu[sel] = nu_k
        # ∂ν/∂(b²)·2/r² = (H'b − H)/(b³ r²): the Jacobian's anisotropic term
        num = m.dh_db(bb) * bb - hh
        dnu[sel] = np.where(small, 0.0, num / np.where(small, 1.0, bb) ** 3)
    return g, nu, dnu / r_qp**2


@cache
def forms() -> tuple[Any, Any, Any]:
    """(Jacobian bilinear form, residual linear form, load linear form), built once."""
    import skfem
    from skfem.helpers import dot, grad

    @skfem.BilinearForm
    def jac(u, v, w):  # type: ignore[no-untyped-def]
        return (w.nu * dot(grad(u), grad(v)) + w.dnu * dot(w.g, grad(u)) * dot(w.g, grad(v))) / w.x[
            0
        ]

    @skfem.LinearForm
    def resid(v, w):  # type: ignore[no-untyped-def]
        return w.nu * dot(w.g, grad(v)) / w.x[0] - w.j * v

    @skfem.LinearForm
    def load(v, w):  # type: ignore[no-untyped-def]
        return w.j * v

    return jac, resid, load


class Assembly:
    """The forms above assembled without scikit-fem's generic loop, on one grid.

    Everything that does not depend on the field is computed once per grid (the grid and
    the forms' linear parts do not change with the current): the basis gradients times
    the quadrature weights over r, the load per unit current density, the sparsity
    pattern of the free–free block and the map of each element entry into it. A Newton
    step is then two einsums and one bincount. The same sums as ``skfem.asm`` of
    ``forms()`` (tests/magnetics/test_fem.py checks them to 1e-12)."""

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
        """``nu_terms`` of the module (same values), from the stored gradients."""
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
        """The Jacobian's free–free block (CSR), ``forms()[0]`` condensed."""
        gi = np.einsum("keq,ikeq->ieq", g, self.grads)
        k = np.einsum("ijeq,eq->ije", self.gg_wr, nu)
        k += np.einsum("ieq,jeq,eq->ije", gi, gi, dnu * self.wr)
        data = np.bincount(self._slot, k[self._keep], self._nnz)
        return self._csr((data, *self._pattern[:2]), shape=self._pattern[2])
