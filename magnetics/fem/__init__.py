"""Axisymmetric non-linear magnetostatic FEM (scikit-fem), the circuit's accuracy reference.

Unknown: the flux function ψ = r·A_φ (2π ψ is the flux through the circle of radius r),
so B_r = −(1/r) ∂ψ/∂z, B_z = (1/r) ∂ψ/∂r. Weak form (Meunier, *The Finite Element
Method for Electromagnetic Modeling*, 2008, §5.3 axisymmetric magnetostatics):

    ∫ ν(|B|) (1/r) ∇ψ·∇v dr dz = ∫ J_φ v dr dz      for all v,  ψ = 0 on r = 0 and the box,

with ν = H(B)/B per material. Bilinear quadrilaterals on a tensor grid whose lines include
every region edge of the section (so no element straddles two materials), refined to the
target ``size`` inside the clutch (uniformly, or graded away from the core and the gap/drum
stack: ``mesh="graded"``) and graded outwards to an air box 3× the clutch's size.
Newton's method with the exact Jacobian of ν(|B|) and a backtracking line search on the
residual norm; converged when ‖R‖ ≤ 1e-8·‖load‖, else FEMConvergenceError.

One module per step: ``grid`` (tensor grid, materials, source), ``forms`` (weak form and
its Jacobian), ``newton`` (damped Newton, optional warm start ψ0), ``post`` (B, gap
profiles, yield torque). scikit-fem is imported only when a solve runs.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from magnetics.fem.grid import DEFAULT_SIZE, MESHES, Grid, build_grid
from magnetics.fem.newton import FEMConvergenceError, newton
from magnetics.fem.post import FEMSolution, post_process
from magnetics.materials import Magnetic

__all__ = ["DEFAULT_SIZE", "MESHES", "FEMConvergenceError", "FEMSolution", "Grid",
           "build_grid", "solve_fem"]  # fmt: skip


def solve_fem(
    section: Section,
    current: float,
    materials: Mapping[str, Magnetic] | None = None,
    size: float | None = None,
    max_iter: int = 40,
    tol: float = 1e-8,
    psi0: NDArray[np.float64] | None = None,
    grid: Grid | None = None,
    *,
    mesh: str = "uniform",
) -> FEMSolution:
    """Solve the clutch's field at ``current`` (A) on a grid of target element ``size`` (m).
    ``grid`` reuses a grid built for this section (``build_grid``); ``psi0`` starts Newton
    from a field on that grid (e.g. the previous current's ``FEMSolution.psi``); without
    ``grid``, one of kind ``mesh`` ("uniform" | "graded", magnetics.fem.grid) is built."""
    g = build_grid(section, size, materials, mesh=mesh) if grid is None else grid
    j_coil = section.clutch.coil_turns * current / g.coil_area  # smeared ampere-turns per m²
    psi, it, res = newton(g, current, np.where(g.coil_mask, j_coil, 0.0), psi0, max_iter, tol)
    return post_process(g, current, psi, it, res)
