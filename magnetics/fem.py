"""Axisymmetric non-linear magnetostatic FEM (scikit-fem), the circuit's accuracy reference.

Unknown: the flux function ψ = r·A_φ (2π ψ is the flux through the circle of radius r),
so B_r = −(1/r) ∂ψ/∂z, B_z = (1/r) ∂ψ/∂r. Weak form (Meunier, *The Finite Element
Method for Electromagnetic Modeling*, 2008, §5.3 axisymmetric magnetostatics):

    ∫ ν(|B|) (1/r) ∇ψ·∇v dr dz = ∫ J_φ v dr dz      for all v,  ψ = 0 on r = 0 and the box,

with ν = H(B)/B per material. Bilinear quadrilaterals on a tensor grid whose lines include
every region edge of the section (so no element straddles two materials), refined to the
target ``size`` inside the clutch and graded outwards to an air box 3× the clutch's size.
Newton's method with the exact Jacobian of ν(|B|) and a backtracking line search on the
residual norm; converged when ‖R‖ ≤ 1e-8·‖load‖, else FEMConvergenceError.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from magnetics.materials import MATERIALS, Magnetic, MRFluid, magnetic

FloatArray = NDArray[np.float64]
DEFAULT_SIZE = 0.25e-3  # m, element size inside the clutch (< 5 s per current, paper preset)


class FEMConvergenceError(RuntimeError):
    """Newton did not reach the residual tolerance."""


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
class FEMSolution:
    """Field of one FEM solve. Element-centre arrays have one entry per element."""

    current: float
    r_nodes: FloatArray
    z_nodes: FloatArray
    centre_r: FloatArray
    centre_z: FloatArray
    b_r: FloatArray
    b_z: FloatArray
    material: tuple[str, ...]  # material of each element (index into names)
    material_index: NDArray[np.int64]
    iterations: int
    residual: float
    gap_r_mid: FloatArray  # (K,)
    #: per gap: (z, dz, |B|, |B_r|) averaged over the gap's radial cells, row by row
    gap_profiles: tuple[tuple[FloatArray, FloatArray, FloatArray, FloatArray], ...]

    @property
    def b(self) -> FloatArray:
        return np.hypot(self.b_r, self.b_z)

    def h(self, materials: Mapping[str, Magnetic] | None = None) -> FloatArray:
        """|H| at every element centre, A/m."""
        out = np.empty_like(self.b_r)
        for k, name in enumerate(self.material):
            m = self.material_index == k
            out[m] = magnetic(name, materials).h_of_b(self.b[m])
        return out

    def gap_yield_torque(
        self, fluid: MRFluid, materials: Mapping[str, Magnetic] | None = None
    ) -> FloatArray:
        """T_k = 2π r_k² ∫ τy(H_r(z)) dz along each gap's mid-radius line (wetted length).

        Only the field component across the gap (H_r, normal to the sheared walls) counts:
        chains along z lie on the shear's vorticity axis and are not tilted by the flow, so
        the axial leakage field in the band region adds (almost) no yield stress. The
        fluid is isotropic, so H_r = H(|B|)·|B_r|/|B|.
        """
        fl = magnetic(fluid.name, materials)
        out = []
        for r, (_z, dz, b, br) in zip(self.gap_r_mid, self.gap_profiles, strict=True):
            h_r = fl.h_of_b(b) * br / np.where(b > 0, b, 1.0)
            out.append(2 * np.pi * r**2 * np.sum(fluid.tau_y(h_r) * dz))
        return np.array(out)


def solve_fem(
    section: Section,
    current: float,
    materials: Mapping[str, Magnetic] | None = None,
    size: float | None = None,
    max_iter: int = 40,
    tol: float = 1e-8,
) -> FEMSolution:
    """Solve the clutch's field at ``current`` (A) on a grid of target element ``size`` (m)."""
    import skfem
    from skfem.helpers import dot, grad

    mats = MATERIALS if materials is None else materials
    h = DEFAULT_SIZE if size is None else float(size)
    c = section.clutch
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
    j_coil = c.coil_turns * current / coil.area  # smeared ampere-turns per m²
    jel = np.where(
        (cen[0] > coil.r0) & (cen[0] < coil.r1) & (cen[1] > coil.z0) & (cen[1] < coil.z1),
        j_coil, 0.0,
    )  # fmt: skip
    mat_objs = [magnetic(n, mats) for n in names]
    r_qp = np.asarray(basis.global_coordinates())[0]
    D = basis.get_dofs().all()

    def nu_terms(psi: FloatArray):  # type: ignore[no-untyped-def]
        g = basis.interpolate(psi).grad
        b = np.sqrt(g[0] ** 2 + g[1] ** 2) / r_qp
        nu = np.empty_like(b)
        dnu = np.zeros_like(b)
        for k, m in enumerate(mat_objs):
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

    jq = jel[:, None] * np.ones_like(r_qp)
    f = skfem.asm(load, basis, j=jq)
    free = np.setdiff1d(np.arange(basis.N), D)
    fnorm = max(np.linalg.norm(f[free]), 1e-300)

    def residual(psi: FloatArray):  # type: ignore[no-untyped-def]
        g, nu, dnu = nu_terms(psi)
        rv = skfem.asm(resid, basis, nu=nu, g=g, j=jq)
        return rv, np.linalg.norm(rv[free]), (g, nu, dnu)

    psi = np.zeros(basis.N)
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

    g = basis.interpolate(psi).grad
    br = (-g[1] / r_qp).mean(axis=1)
    bz = (g[0] / r_qp).mean(axis=1)
    bmag = np.hypot(br, bz)
    # Gap profiles: |B| averaged over the gap's radial cells, row by row along z.
    dz_el = np.ptp(mesh.p[1, mesh.t], axis=0)
    profiles, rmid = [], []
    for gp in section.gaps:
        sel = (cen[0] > gp.r_inner) & (cen[0] < gp.r_outer) & (cen[1] > gp.z0) & (cen[1] < gp.z1)
        zc = np.round(cen[1][sel], 12)
        zu, inv = np.unique(zc, return_inverse=True)
        cnt = np.bincount(inv)
        bavg = np.bincount(inv, bmag[sel]) / cnt
        bravg = np.bincount(inv, np.abs(br[sel])) / cnt
        dzz = np.bincount(inv, dz_el[sel]) / cnt
        profiles.append((zu, dzz, bavg, bravg))
        rmid.append(gp.r_mean)
    return FEMSolution(float(current), rs, zs, cen[0], cen[1], br, bz, tuple(names), idx, it,
                       float(rn / fnorm), np.array(rmid), tuple(profiles))  # fmt: skip
