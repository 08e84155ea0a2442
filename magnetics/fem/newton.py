"""Damped Newton on the FEM's residual: exact Jacobian of ν(|B|), backtracking line search
on the residual norm (Armijo factor 1e-4, halving down to 1/256); converged when
‖R‖ ≤ tol·‖load‖, else FEMConvergenceError. A warm start ψ0 (the solution at a nearby
current on the same grid) saves iterations along a torque curve."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from magnetics.fem.forms import forms, nu_terms
from magnetics.fem.grid import Grid

FloatArray = NDArray[np.float64]


class FEMConvergenceError(RuntimeError):
    """Newton did not reach the residual tolerance."""


def newton(
    grid: Grid,
    current: float,
    j_element: FloatArray,
    psi0: FloatArray | None = None,
    max_iter: int = 40,
    tol: float = 1e-8,
) -> tuple[FloatArray, int, float]:
    """(ψ, iterations, relative residual) of the field driven by ``j_element`` [A/m²]."""
    import skfem

    jac, resid, load = forms()
    basis, D = grid.basis, grid.fixed
    jq = j_element[:, None] * np.ones_like(grid.r_qp)
    f = skfem.asm(load, basis, j=jq)
    free = np.setdiff1d(np.arange(basis.N), D)
    fnorm = max(np.linalg.norm(f[free]), 1e-300)

    def residual(psi: FloatArray):  # type: ignore[no-untyped-def]
        g, nu, dnu = nu_terms(grid, psi)
        rv = skfem.asm(resid, basis, nu=nu, g=g, j=jq)
        return rv, np.linalg.norm(rv[free]), (g, nu, dnu)

    psi = np.zeros(basis.N) if psi0 is None else np.array(psi0, dtype=float)
    rv, rn, terms = residual(psi)
    it = 0
    while rn > tol * fnorm and current != 0:
        if it >= max_iter:
            raise FEMConvergenceError(
                f"FEM at {current:.6g} A: Newton did not converge in {max_iter} iterations "
                f"(relative residual {rn / fnorm:.3g} > {tol:g})"
            )
        g, nu, dnu = terms
        K = skfem.asm(jac, basis, nu=nu, dnu=dnu, g=g)
        delta = skfem.solve(*skfem.condense(K, -rv, D=D))
        alpha = 1.0
        while True:
            trial = psi + alpha * delta
            rv_t, rn_t, terms_t = residual(trial)
            if rn_t < (1 - 1e-4 * alpha) * rn or alpha < 1 / 256:
                break
            alpha *= 0.5
        psi, rv, rn, terms = trial, rv_t, rn_t, terms_t
        it += 1
    return psi, it, float(rn / fnorm)
