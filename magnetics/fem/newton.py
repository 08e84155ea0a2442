"""Damped Newton on the FEM's residual: exact Jacobian of ν(|B|), backtracking line search
on the residual norm (Armijo factor 1e-4, halving down to 1/256); converged when
‖R‖ ≤ tol·‖load‖, else FEMConvergenceError. A warm start ψ0 (the solution at a nearby
current on the same grid) saves iterations along a torque curve.

The forms are assembled by the grid's ``Assembly`` (its current-independent parts built
once per grid) and each step's linear system, symmetric positive definite, is factorised
by SuperLU with the minimum-degree ordering of AᵀA+A (about 1.5× faster than its default
COLAMD on these grids, and sparser factors)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from magnetics.fem.grid import Grid

FloatArray = NDArray[np.float64]


class FEMConvergenceError(RuntimeError):
    """Newton did not reach the residual tolerance."""


#: a step by CG preconditioned with a factorised earlier Jacobian: its relative residual
#: target (an inexact Newton step, Eisenstat & Walker 1996), and the CG iterations after
#: which the factors are judged stale and the current Jacobian is factorised instead
PCG_RTOL = 1e-3
PCG_MAX_ITER = 12


def _step(asm, K, rhs: FloatArray, rtol: float) -> FloatArray:  # type: ignore[no-untyped-def]
    """Solve K x = rhs (K symmetric positive definite: ν > 0 and dH/dB > 0) by CG
    preconditioned with the last factorised Jacobian of this grid (kept on its Assembly,
    across Newton steps and currents); refactorise (SuperLU, minimum-degree ordering of
    AᵀA+A) when CG does not reach ``rtol`` in PCG_MAX_ITER iterations or no factors exist."""
    from scipy.sparse.linalg import LinearOperator, cg, splu

    lu = asm.factors
    if lu is not None:
        m = LinearOperator(K.shape, matvec=lu.solve, dtype=float)
        x, info = cg(K, rhs, x0=lu.solve(rhs), rtol=rtol, atol=0.0, maxiter=PCG_MAX_ITER, M=m)
        if info == 0:
            return x
    asm.factors = splu(K.T, permc_spec="MMD_AT_PLUS_A")  # K.T: the same matrix, as CSC
    return asm.factors.solve(rhs)


def newton(
    grid: Grid,
    current: float,
    j_element: FloatArray,
    psi0: FloatArray | None = None,
    max_iter: int = 40,
    tol: float = 1e-8,
    source: FloatArray | None = None,
) -> tuple[FloatArray, int, float]:
    """(ψ, iterations, relative residual) of the field driven by ``j_element`` [A/m²] and,
    where given, a further load ``source`` on every dof (a remanent magnetisation's,
    ``magnetics.fem.remanence``: it drives the field at 0 A)."""
    asm = grid.assembly
    free = asm.free
    f = asm.load(j_element) if source is None else asm.load(j_element) + source
    fnorm = max(np.linalg.norm(f[free]), 1e-300)

    def residual(psi: FloatArray):  # type: ignore[no-untyped-def]
        g, nu, dnu = asm.nu_terms(psi)
        rv = asm.residual(g, nu, f)
        return rv, np.linalg.norm(rv[free]), (g, nu, dnu)

    psi = np.zeros(asm.n) if psi0 is None else np.array(psi0, dtype=float)
    rv, rn, terms = residual(psi)
    it = 0
    while rn > tol * fnorm and (current != 0 or source is not None):
        if it >= max_iter:
            raise FEMConvergenceError(
                f"FEM at {current:.6g} A: Newton did not converge in {max_iter} iterations "
                f"(relative residual {rn / fnorm:.3g} > {tol:g})"
            )
        g, nu, dnu = terms
        K = asm.jacobian(g, nu, dnu)
        delta = np.zeros_like(psi)
        delta[free] = _step(asm, K, -rv[free], min(PCG_RTOL, rn / fnorm))
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
