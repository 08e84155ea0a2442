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
