"""Where the network's torque goes wrong on one design: each gap's flux and torque in zone A
and zone B, over the walls' overlap and in the fringes, network against the FEM.

    python benchmarks/diagnose_zones.py [--drums 1] [--zone-mm 3] [--gap-mm 0.7]
        [--thickness-mm 0.3] [--bore-mm 11.5] [--current 2] [--fem-mm 0.25]

The rest of the design is the paper preset. FEM fluxes are 2π·ψ differences (ψ the FEM's
flux function on its grid lines): a gap's radial flux between two heights is
2π·[ψ(r, z1) − ψ(r, z0)] at its mid radius; the core's axial flux at a height is 2π·ψ just
inside its radius. FEM torque per gap section: 2π r²·τy(H_r)·dz summed over the gap's rows
(the FEM's mid-line torque, split at the walls' overlap in each zone, as the network has
it, and at the band's mid-plane). Network:
the zone's film flux x_k − e_z, its share L/L_eff over the overlap, and the torque with and
without the fringe tubes (``network_gap_torque``). Used for docs/magnetics.md's "what the
end leak gets wrong".
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from geometry.materials import MRF
from geometry.params import broadcast_fields, preset
from geometry.regions import evaluate
from geometry.section import build_section
from magnetics.fem import build_grid, solve_fem
from magnetics.materials import FLUIDS, magnetic
from magnetics.network import network_from_regions, solve_network
from magnetics.torque import network_gap_torque


def _psi(grid, sol):  # type: ignore[no-untyped-def]
    """2π·ψ(r, z) by bilinear interpolation on the FEM's tensor grid."""
    rl, zl = grid.r_lines, grid.z_lines
    p = np.empty((rl.size, zl.size))
    p[np.searchsorted(rl, grid.mesh.p[0]), np.searchsorted(zl, grid.mesh.p[1])] = sol.psi

    def flux(r: float, z: float) -> float:
        i = int(np.clip(np.searchsorted(rl, r), 1, rl.size - 1))
        j = int(np.clip(np.searchsorted(zl, z), 1, zl.size - 1))
        tr = (r - rl[i - 1]) / (rl[i] - rl[i - 1])
        tz = (z - zl[j - 1]) / (zl[j] - zl[j - 1])
        v = (p[i - 1, j - 1] * (1 - tr) * (1 - tz) + p[i, j - 1] * tr * (1 - tz)
             + p[i - 1, j] * (1 - tr) * tz + p[i, j] * tr * tz)  # fmt: skip
        return float(2 * np.pi * v)

    return flux


def design_from_args(zone_mm: float, bore_mm: float | None, current: float):  # type: ignore[no-untyped-def]
    """(options, the changes to the paper preset, the clutch, its region table, its
    stations) from the command line: the options both diagnostics take, with their
    defaults for the zone, the bore and the current."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--drums", type=int, default=1)
    ap.add_argument("--zone-mm", type=float, default=zone_mm)
    ap.add_argument("--gap-mm", type=float, default=None)
    ap.add_argument("--thickness-mm", type=float, default=None)
    ap.add_argument("--bore-mm", type=float, default=bore_mm)
    ap.add_argument("--current", type=float, default=current)
    ap.add_argument("--fem-mm", type=float, default=0.25)
    a = ap.parse_args()
    kw = {"n_drums": a.drums, "zone_length": a.zone_mm * 1e-3}
    for key, val in (("gap", a.gap_mm), ("drum_thickness", a.thickness_mm),
                     ("drum_inner_diameter", a.bore_mm)):  # fmt: skip
        if val is not None:
            kw[key] = val * 1e-3
    c = replace(preset("paper"), **kw)
    rg = evaluate(broadcast_fields({k: np.array([v], float) for k, v in vars(c).items()}),
                  c.n_drums)  # fmt: skip
    at = {k: float(np.ravel(v)[0]) for k, v in rg.at.items()}
    return a, kw, c, rg, at


def main() -> None:
    a, kw, c, rg, at = design_from_args(3.0, None, 2.0)
    net = network_from_regions(rg)
    m = net.m
    x = solve_network(net, [[c.coil_turns * a.current]])[0, 0]
    e = x[net.leaks]
    t = network_gap_torque(net, [[a.current]])[0, 0]
    t_overlap = network_gap_torque(replace(net, fringe_h=0 * net.fringe_h), [[a.current]])[0, 0]
    sec = build_section(c)
    grid = build_grid(sec, a.fem_mm * 1e-3)
    sol = solve_fem(sec, a.current, grid=grid)
    flux = _psi(grid, sol)
    fluid = FLUIDS[MRF]
    za0, za1, zb0, zb1 = (at[k] for k in ("zone_A0", "zone_A1", "zone_B0", "zone_B1"))
    mid = 0.5 * (za1 + zb0)
    t_fem = sol.gap_yield_torque(fluid)
    print(f"{kw} at {a.current} A: torque network {t.sum():.4f} N·m, FEM {t_fem.sum():.4f} "
          f"({t.sum() / t_fem.sum() - 1:+.1%}); end leaks (network) "
          f"{np.round(np.abs(e) * 1e6, 2)} µWb")  # fmt: skip
    rc = at["rho0"] * (1 - 1e-4)
    print("core's axial flux (FEM, µWb) at zone A's start, band mid-plane, zone B's end: "
          f"{abs(flux(rc, za0)) * 1e6:.2f}, {abs(flux(rc, mid)) * 1e6:.2f}, "
          f"{abs(flux(rc, zb1)) * 1e6:.2f}")  # fmt: skip
    print(
        "\ngap | flux over the overlap, A / B (µWb)   | torque mN·m: overlap A, fringe A, "
        "overlap B, fringe B"
    )
    print("    | network        FEM                  | network                    | FEM")
    bh = magnetic(MRF)
    for k, (gp, (z, dz, b, br)) in enumerate(zip(sec.gaps, sol.gap_profiles, strict=True)):
        r = gp.r_mean
        share = net.gap_len[0, k] / np.where(net.gap_eff[0, k] > 0, net.gap_eff[0, k], 1.0)
        over = np.abs(x[k] - e) * share
        # the walls' overlap in each zone, as the network has it (it ends at the band)
        oa0, ob1 = za1 - net.gap_len[0, k, 0], zb0 + net.gap_len[0, k, 1]
        f_a, f_b = abs(flux(r, za1) - flux(r, oa0)), abs(flux(r, ob1) - flux(r, zb0))
        h_r = bh.h_of_b(b) * br / np.where(b > 0, b, 1.0)
        tau = 2 * np.pi * r**2 * fluid.tau_y(h_r) * dz
        ov_a, ov_b = tau[(z >= oa0) & (z <= za1)].sum(), tau[(z >= zb0) & (z <= ob1)].sum()
        fr_a, fr_b = tau[z < mid].sum() - ov_a, tau[z >= mid].sum() - ov_b
        net_t = (t_overlap[k], t[k] - t_overlap[k], t_overlap[m + k], t[m + k] - t_overlap[m + k])
        print(f"{k:3d} | {over[0] * 1e6:6.2f} / {over[1] * 1e6:6.2f}  {f_a * 1e6:6.2f} / "
              f"{f_b * 1e6:6.2f}     | " + " ".join(f"{1e3 * v:6.2f}" for v in net_t)
              + " | " + " ".join(f"{1e3 * v:6.2f}" for v in (ov_a, fr_a, ov_b, fr_b)))  # fmt: skip


if __name__ == "__main__":
    main()
