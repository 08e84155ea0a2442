"""The FEM's check of the residual torque (issue 41, item 1): the steel's remanence as a
source of the axisymmetric field, solved at 0 A after a peak current.

**The model** is ``magnetics.hysteresis``'s shifted curve, written per element instead of
per circuit branch: on the falling branch reached from a peak, each steel element's
constitutive law is the library's single-valued curve shifted by its coercivity,

    H = H_lib(|B|)·B/|B| − M_c,   M_c = Hc(Hm)·e,

with Hc(Hm) the Takács coercivity of the loop reached from the element's own peak field
Hm = H_lib(|B_peak|) [takacs2001] (``Hysteresis.coercivity_after``) and e = B_peak/|B_peak|
the peak field's direction (the remanent polarisation stays where the peak put it). M_c is
a magnetisation (A/m) constant on each element, 0 outside the steels. Put into the weak
form ∫ H·B_v dV = ∫ J·A_v dV (Meunier 2008, §5.3; B_v = curl(v φ̂/r)), it moves to the
right-hand side as a load, as a permanent magnet's does:

    ∫ ν(|B|) (1/r) ∇ψ·∇v dr dz = ∫ J v dr dz + ∫ (M_z ∂v/∂r − M_r ∂v/∂z) dr dz,

(B_v = (−∂v/∂z, ∂v/∂r)/r and dV = 2π r dr dz, the 2π common to both sides). By the
divergence theorem a uniform M on a region is the same load as the Amperian sheet current
K = M × n on the region's boundary (``tests/magnetics/test_fem_remanence.py`` checks the
assembled load against that line integral, exactly).

**The residual torque** is the gaps' yield torque of the 0 A field (``FEMSolution.
gap_yield_torque``, the fluid not hysteretic), set beside the circuit/network answer of
``magnetics.hysteresis`` (the single-valued torque at the coercive current I_c = Σ Hc,m·l/N,
the lengths and peak fields of the magnetic circuit's branches). Where they differ: the
FEM takes each element's own peak field (so a lightly-worked corner of the shell holds
less coercivity than its branch's mean), the field's own paths (leakage included) and the
peak field's direction; the circuit lumps the loop into branches.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from magnetics.fem import solve_fem
from magnetics.fem.grid import Grid, build_grid
from magnetics.fem.newton import newton
from magnetics.fem.post import FEMSolution, post_process
from magnetics.hysteresis import HYSTERESIS
from magnetics.materials import FLUIDS, Magnetic

FloatArray = NDArray[np.float64]


def coercive_magnetisation(grid: Grid, peak: FEMSolution) -> tuple[FloatArray, FloatArray]:
    """(M_r, M_z) per element, A/m: Hc(Hm)·B_peak/|B_peak| on the steel elements (those
    whose material has a loop, ``magnetics.hysteresis.HYSTERESIS``), Hm = H_lib(|B_peak|)
    at the element's centre; 0 elsewhere and where the peak left no field."""
    m_r = np.zeros_like(peak.b_r)
    m_z = np.zeros_like(peak.b_z)
    b = peak.b
    for k, name in enumerate(grid.names):
        if name not in HYSTERESIS:
            continue
        sel = (grid.material_index == k) & (b > 0)
        hm = grid.materials[k].h_of_b(b[sel])
        hc = HYSTERESIS[name].coercivity_after(hm)
        m_r[sel] = hc * peak.b_r[sel] / b[sel]
        m_z[sel] = hc * peak.b_z[sel] / b[sel]
    return m_r, m_z


def magnetisation_load(grid: Grid, m_r: FloatArray, m_z: FloatArray) -> FloatArray:
    """∫ (M_z ∂φ_i/∂r − M_r ∂φ_i/∂z) dr dz on every dof, M constant per element (A/m):
    the weak form's load of a magnetisation (module docstring)."""
    asm = grid.assembly
    dx = asm.wr * grid.r_qp  # dr dz at the quadrature points (wr = dx/r)
    per = (asm.grads[:, 0] * m_z[:, None] - asm.grads[:, 1] * m_r[:, None]) * dx  # (4, E, Q)
    return np.bincount(asm.dofs.ravel(), per.sum(-1).ravel(), asm.n)


@dataclass(frozen=True)
class Remanent:
    """The FEM after a peak: the field at the peak current and at 0 A with the steel's
    coercive magnetisation, and the 0 A field's residual yield torque (N·m, all gaps)."""

    peak: FEMSolution
    residual: FEMSolution
    magnetisation: tuple[FloatArray, FloatArray]  # (M_r, M_z) per element, A/m
    residual_torque: float


def solve_remanent(section: Section, peak_current: float,
                   materials: Mapping[str, Magnetic] | None = None, size: float | None = None,
                   *, mesh: str = "uniform", convention: str = "mid-line") -> Remanent:  # fmt: skip
    """Solve ``section`` at ``peak_current`` (A), then at 0 A with the coercive
    magnetisation that peak leaves in the steel (module docstring); the residual torque
    is the gaps' yield torque of the 0 A field (``convention`` as ``gap_yield_torque``)."""
    grid = build_grid(section, size, materials, mesh=mesh)
    peak = solve_fem(section, peak_current, materials, grid=grid)
    m = coercive_magnetisation(grid, peak)
    load = magnetisation_load(grid, *m)
    zero = np.zeros(grid.material_index.shape)
    psi, it, res = newton(grid, 0.0, zero, peak.psi, source=load)
    rest = post_process(grid, 0.0, psi, it, res)
    fluid = FLUIDS[section.region(f"gap{section.gaps[0].index}").material]  # the gaps' fluid
    torque = float(np.sum(rest.gap_yield_torque(fluid, materials, convention)))
    return Remanent(peak, rest, m, torque)
