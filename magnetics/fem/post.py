"""The FEM's field after the solve: B at element centres, the gaps' |B| profiles along z,
and the gaps' yield torque (``FEMSolution``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from geometry.validation import ParameterError
from magnetics.fem.grid import Grid
from magnetics.fluid import MRFluid
from magnetics.materials import Magnetic, magnetic

FloatArray = NDArray[np.float64]


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
    #: the node field ψ (a warm start for a nearby current on the same grid)
    psi: FloatArray | None = None
    #: per gap, on every grid line r_i across it (walls included) and every row j of
    #: cells along z: (r (I,), dz (J,), B_r (I, J), B_z (I, J)); B_r exact on the line
    #: (the normal component, from ψ at its two nodes), B_z the adjacent gap cells' mean
    gap_lines: tuple[tuple[FloatArray, FloatArray, FloatArray, FloatArray], ...] = ()
    #: the coil's flux linkage λ = (N/A_coil)·∫_coil 2π ψ dA (Wb): each of its turns,
    #: spread uniformly over its section as the source is, links the flux 2π ψ inside it
    flux_linkage: float = float("nan")

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
        self,
        fluid: MRFluid,
        materials: Mapping[str, Magnetic] | None = None,
        convention: str = "mid-line",
    ) -> FloatArray:
        """T_k = 2π r_k² ∫ τy(H_r(z)) dz along each gap's mid-radius line (wetted length),
        |B| and |B_r| averaged over the gap's cells of each row (``convention``
        "mid-line"), or T_k = 2π ∫ min_i r_i²·τy(H_r(r_i, z)) dz over the grid lines r_i
        across the gap, both walls included ("weakest-layer": the layer that yields first,
        magnetics.torque._gap_torque).

        Only the field component across the gap (H_r, normal to the sheared walls) counts:
        chains along z lie on the shear's vorticity axis and are not tilted by the flow, so
        the axial leakage field in the band region adds (almost) no yield stress. The
        fluid is isotropic, so H_r = H(|B|)·|B_r|/|B|.
        """
        fl = magnetic(fluid.name, materials)
        out = []
        if convention == "weakest-layer":
            for r, dz, br, bz in self.gap_lines:
                b = np.hypot(br, bz)
                h_r = fl.h_of_b(b) * np.abs(br) / np.where(b > 0, b, 1.0)
                f = r[:, None] ** 2 * fluid.tau_y(h_r)  # (I, J)
                out.append(2 * np.pi * np.sum(f.min(axis=0) * dz))
            return np.array(out)
        if convention != "mid-line":
            raise ParameterError(f"convention = {convention!r}: mid-line or weakest-layer")
        for r, (_z, dz, b, br) in zip(self.gap_r_mid, self.gap_profiles, strict=True):
            h_r = fl.h_of_b(b) * br / np.where(b > 0, b, 1.0)
            out.append(2 * np.pi * r**2 * np.sum(fluid.tau_y(h_r) * dz))
        return np.array(out)


def post_process(grid: Grid, current: float, psi: FloatArray, iterations: int, residual: float
                 ) -> FEMSolution:  # fmt: skip
    """The FEMSolution of the field ψ on ``grid``."""
    mesh, cen, r_qp = grid.mesh, grid.centre, grid.r_qp
    field = grid.basis.interpolate(psi)
    g = field.grad
    # λ = ∂W'/∂I = ∫ (J/I)·2π ψ dA with J = N·I/A_coil on the coil's elements
    coil = grid.coil_mask
    linkage = (2 * np.pi * grid.section.clutch.coil_turns / grid.coil_area
               * float(np.sum((np.asarray(field) * grid.basis.dx)[coil])))  # fmt: skip
    br = (-g[1] / r_qp).mean(axis=1)
    bz = (g[0] / r_qp).mean(axis=1)
    bmag = np.hypot(br, bz)
    # Gap profiles: |B| averaged over the gap's radial cells, row by row along z.
    dz_el = np.ptp(mesh.p[1, mesh.t], axis=0)
    # ψ and the cells' B_z on the tensor grid's (r, z) indices
    rl, zl = grid.r_lines, grid.z_lines
    psi_g = np.empty((rl.size, zl.size))
    psi_g[np.searchsorted(rl, mesh.p[0]), np.searchsorted(zl, mesh.p[1])] = psi
    bz_g = np.zeros((rl.size - 1, zl.size - 1))
    bz_g[np.searchsorted(rl, cen[0]) - 1, np.searchsorted(zl, cen[1]) - 1] = bz
    lines = []
    for gp in grid.section.gaps:
        # the lines on the gap's edges (grid lines are region edges rounded to 1e-12 m)
        i0 = np.searchsorted(rl, gp.r_inner - 1e-11)
        i1 = np.searchsorted(rl, gp.r_outer + 1e-11) - 1
        j0, j1 = np.searchsorted(zl, gp.z0 - 1e-11), np.searchsorted(zl, gp.z1 + 1e-11) - 1
        r = rl[i0 : i1 + 1]
        dzj = np.diff(zl[j0 : j1 + 1])
        br_l = -np.diff(psi_g[i0 : i1 + 1, j0 : j1 + 1], axis=1) / (r[:, None] * dzj)
        cells = bz_g[i0:i1, j0:j1]  # (I - 1, J) gap cells
        bz_l = np.empty_like(br_l)
        bz_l[0], bz_l[-1] = cells[0], cells[-1]
        bz_l[1:-1] = 0.5 * (cells[:-1] + cells[1:])
        lines.append((r, dzj, br_l, bz_l))
    profiles, rmid = [], []
    for gp in grid.section.gaps:
        sel = (cen[0] > gp.r_inner) & (cen[0] < gp.r_outer) & (cen[1] > gp.z0) & (cen[1] < gp.z1)
        zc = np.round(cen[1][sel], 12)
        zu, inv = np.unique(zc, return_inverse=True)
        cnt = np.bincount(inv)
        bavg = np.bincount(inv, bmag[sel]) / cnt
        bravg = np.bincount(inv, np.abs(br[sel])) / cnt
        dzz = np.bincount(inv, dz_el[sel]) / cnt
        profiles.append((zu, dzz, bavg, bravg))
        rmid.append(gp.r_mean)
    return FEMSolution(float(current), grid.r_lines, grid.z_lines, cen[0], cen[1], br, bz,
                       grid.names, grid.material_index, iterations, residual, np.array(rmid),
                       tuple(profiles), psi, tuple(lines), linkage)  # fmt: skip
