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


def test_fem_energy_converges_at_second_order_in_air():
    """All-air clutch (no corners in μ): the co-energy ∫Jψ converges as h² (bilinear)."""
    air = {k: LinearMaterial(k, 1.0) for k in MATERIALS}
    s = build_section(PAPER)
    sizes = np.array([2.0e-3, 1.0e-3, 0.5e-3])
    energy = []
    for h in [*sizes, 0.25e-3]:
        sol = solve_fem(s, 1.0, materials=air, size=h)
        # W = π ∫ J ψ dr dz ∝ flux linkage; use the mean |B| in the coil window as proxy
        coil = s.region("coil")
        m = ((sol.centre_r > coil.r0) & (sol.centre_r < coil.r1)
             & (sol.centre_z > coil.z0) & (sol.centre_z < coil.z1))  # fmt: skip
        energy.append(sol.b[m].mean())
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
