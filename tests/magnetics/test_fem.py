from dataclasses import replace

import numpy as np
import pytest

from geometry.params import preset
from geometry.section import build_section
from magnetics.fem import solve_fem
from magnetics.materials import MATERIALS, MRF_132DG, MU0, LinearMaterial, linear_materials

PAPER = preset("paper")


def test_fem_linear_limit_within_3_percent_mid_zone():
    """Permeable linear steel, long zones: mid-zone gap B vs μ N I / (r Σ ln(ro/ri))."""
    c = replace(PAPER, zone_length=12e-3, gap=0.5e-3)
    s = build_section(c)
    mats = linear_materials(1e5, 5.0)
    sol = solve_fem(s, 1.0, materials=mats, size=0.5e-3)
    lsum = 2 * sum(np.log(g.r_outer / g.r_inner) for g in s.gaps)
    za = s.zones[0]
    zm = 0.5 * (za.z0 + za.z1)
    for g, (z, _dz, _b, br) in zip(s.gaps, sol.gap_profiles, strict=True):
        expected = MU0 * 5.0 * c.coil_turns * 1.0 / (g.r_mean * lsum)
        got = br[np.argmin(np.abs(z - zm))]
        assert got == pytest.approx(expected, rel=0.03)


@pytest.mark.parametrize(
    ("mesh", "sizes"),
    [("uniform", (2.0e-3, 1.0e-3, 0.5e-3)), ("graded", (1.0e-3, 0.5e-3, 0.25e-3))],
)
def test_fem_energy_converges_at_second_order_in_air(mesh, sizes):
    """All-air clutch (no corners in μ): the co-energy ∫Jψ converges as h² (bilinear).
    Proxy: the area-weighted mean |B| over the coil window (on the uniform grid the coil's
    cells are equal, the plain mean of before). The graded grid's sizes are a fixed
    multiple of h everywhere (magnetics.fem.grid), so it keeps the rate once its largest
    cells (4h) resolve the clutch: from 1 mm on (at 2 mm they are 8 mm, coarser than the
    coil window; measured slope 0.5 from 2 mm, 2.4 from 1 mm)."""
    air = {k: LinearMaterial(k, 1.0) for k in MATERIALS}
    s = build_section(PAPER)
    coil = s.region("coil")
    energy = []
    for h in [*sizes, sizes[-1] / 2]:
        sol = solve_fem(s, 1.0, materials=air, size=h, mesh=mesh)
        i = np.searchsorted(sol.r_nodes, sol.centre_r)
        j = np.searchsorted(sol.z_nodes, sol.centre_z)
        area = np.diff(sol.r_nodes)[i - 1] * np.diff(sol.z_nodes)[j - 1]
        m = ((sol.centre_r > coil.r0) & (sol.centre_r < coil.r1)
             & (sol.centre_z > coil.z0) & (sol.centre_z < coil.z1))  # fmt: skip
        energy.append(np.sum(sol.b[m] * area[m]) / np.sum(area[m]))
    err = np.abs(np.array(energy[:-1]) - energy[-1])
    slope = np.polyfit(np.log(sizes), np.log(err), 1)[0]
    assert 1.5 < slope < 2.6


def test_fem_deep_saturation_converges():
    sol = solve_fem(build_section(PAPER), 100.0, size=0.5e-3)
    assert sol.residual < 1e-8 and np.all(np.isfinite(sol.b))
    steel = sol.material_index == sol.material.index("steel_1018")
    assert sol.b[steel].max() > 2.1  # the steel is deep in saturation


def test_a_warm_start_on_a_reused_grid_gives_the_same_field_in_fewer_iterations() -> None:
    """Newton from the field at 6 A reaches the 7 A field of a cold start (to the
    residual tolerance) in fewer iterations; the torque curve uses this."""
    from magnetics.fem import build_grid

    s = build_section(preset("paper"))
    grid = build_grid(s, 1e-3)
    cold = solve_fem(s, 7.0, size=1e-3)
    warm = solve_fem(s, 7.0, grid=grid, psi0=solve_fem(s, 6.0, grid=grid).psi)
    t_cold, t_warm = cold.gap_yield_torque(MRF_132DG), warm.gap_yield_torque(MRF_132DG)
    np.testing.assert_allclose(t_warm, t_cold, rtol=1e-6)
    assert warm.iterations < cold.iterations


def test_importing_the_fem_does_not_import_scikit_fem() -> None:
    import subprocess
    import sys

    code = "import sys, magnetics.fem; assert 'skfem' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_the_grids_assembly_equals_scikit_fems_forms() -> None:
    """The stored-parts assembly (every Newton step) sums the same integrals as skfem.asm
    of forms(): Jacobian (free block), residual and load, at a saturated field."""
    import skfem

    from magnetics.fem import build_grid
    from magnetics.fem.forms import forms, nu_terms

    s = build_section(PAPER)
    g = build_grid(s, 1e-3, mesh="graded")
    psi = solve_fem(s, 7.0, grid=g).psi
    asm, (jac, resid, load) = g.assembly, forms()
    gq, nu, dnu = nu_terms(g, psi)
    np.testing.assert_allclose(asm.nu_terms(psi)[1], nu, rtol=1e-13)
    j = np.where(g.coil_mask, 1e6, 0.0)
    jq = j[:, None] * np.ones_like(g.r_qp)
    f = skfem.asm(load, g.basis, j=jq)
    np.testing.assert_allclose(asm.load(j), f, rtol=1e-12, atol=1e-12 * np.abs(f).max())
    rv = skfem.asm(resid, g.basis, nu=nu, g=gq, j=jq)
    np.testing.assert_allclose(asm.residual(gq, nu, f), rv, atol=1e-12 * np.abs(rv).max())
    k = skfem.asm(jac, g.basis, nu=nu, dnu=dnu, g=gq)[asm.free][:, asm.free]
    diff = (asm.jacobian(gq, nu, dnu) - k).toarray()
    assert np.abs(diff).max() < 1e-12 * abs(k).max()


def test_the_graded_grid_keeps_every_edge_is_fine_where_it_must_be_and_smaller() -> None:
    from magnetics.fem import build_grid
    from magnetics.fem.grid import GRADED_CAP, GRADED_LENGTH

    s = build_section(PAPER)
    h = 0.25e-3
    g = build_grid(s, h, mesh="graded")
    u = build_grid(s, h)
    for lines, edges in ((g.r_lines, [e for r in s.regions for e in (r.r0, r.r1)]),
                         (g.z_lines, [e for r in s.regions for e in (r.z0, r.z1)])):  # fmt: skip
        assert np.min(np.abs(lines[None, :] - np.array(edges)[:, None]), axis=1).max() < 1e-12
    dr = np.diff(g.r_lines)
    r_stack = max(gp.r_outer for gp in s.gaps)
    assert dr[g.r_lines[1:] <= r_stack + 1e-12].max() <= h * (1 + 1e-9)  # axis … stack: fine
    inside = g.r_lines[1:] <= s.r_max + 1e-12
    assert dr[inside].max() > 2 * h  # graded in the shell
    zc = 0.5 * (g.z_lines[1:] + g.z_lines[:-1])
    dz = np.diff(g.z_lines)
    z_edges = [e for r in s.regions for e in (r.z0, r.z1)]
    near = np.min(np.abs(zc[:, None] - np.array(z_edges)[None, :]), axis=1) < h
    in_gap = (zc > s.gaps[0].z0) & (zc < s.gaps[0].z1)
    # the cell at each edge in the gap span: the size there, grown over its own width
    assert dz[near & in_gap].max() <= h * (1 + h / GRADED_LENGTH)
    assert dz[in_gap].max() > 2 * h and dz[in_gap].max() <= GRADED_CAP * h * 1.01
    grow = dz[in_gap][1:] / dz[in_gap][:-1]
    assert np.all(grow < 1 + 1.6 * h / GRADED_LENGTH)  # geometric growth, no jumps
    assert g.basis.N < 0.5 * u.basis.N


def test_the_graded_grid_gives_the_uniform_torque_with_half_the_unknowns() -> None:
    """Same size, 0.25 mm: the graded grid's torque within 0.2 % of the uniform one's
    (both ~0.5 % off the extrapolated reference, benchmarks/bench_fem_speed.py)."""
    from magnetics.torque import torque_curve

    cur = [2.0, 7.0]
    u = torque_curve(PAPER, cur, method="fem", fem_size=0.25e-3).yield_torque
    g = torque_curve(PAPER, cur, method="fem", fem_size=0.25e-3, fem_mesh="graded").yield_torque
    np.testing.assert_allclose(g, u, rtol=2e-3)
    assert not np.allclose(g, u, rtol=1e-6)  # a different grid indeed


def test_a_torque_curve_solves_its_currents_in_increasing_order_whatever_their_order() -> None:
    from magnetics.torque import torque_curve

    kw = dict(method="fem", fem_size=1e-3, fem_mesh="graded")
    a = torque_curve(PAPER, [7.0, 0.0, 2.0, 4.0], **kw).yield_torque
    b = torque_curve(PAPER, [0.0, 2.0, 4.0, 7.0], **kw).yield_torque
    np.testing.assert_allclose(a, b[[3, 0, 1, 2]], rtol=1e-6)
    assert a[1] == 0 and np.all(np.diff(b) > 0)


@pytest.mark.parametrize("gap", [0.2, 0.5, 1.0, 1.7, 3.0, 9.0])
def test_air_cells_are_the_fewest_geometric_cells_of_first_size_h(gap):
    """Outside the clutch the grid grows ×1.5 a cell: an air interval of length L gets the
    fewest n cells (capped at 12, not reached here) whose first, next to the clutch, is
    ≤ h — by hand the first of n such cells is L/(1 + 1.5 + … + 1.5^(n−1)) =
    L/(2(1.5^n − 1)), so one cell while L ≤ h (a mutant that forced at least two
    survived the suite)."""
    from magnetics.fem.grid import _axis

    h = 0.5
    lines = _axis([0.0, 1.0, 1.0 + gap * h], 0.0, 1.0 + gap * h, h, (0.0, 1.0))
    air = np.diff(lines[lines >= 1.0 - 1e-12])
    n = next(k for k in range(1, 13) if gap * h / (2 * (1.5**k - 1)) <= h * (1 + 1e-12))
    assert air.size == n
    assert air[0] <= h * (1 + 1e-12)
    np.testing.assert_allclose(air[1:] / air[:-1], 1.5, rtol=1e-9)
    if gap <= 1.0:
        assert n == 1
