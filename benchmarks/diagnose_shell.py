"""Where the shell's flux goes on one design, network against the FEM: the flux through the
poles, the back iron, the air outside the shell and the coil window, and the back iron's
flux density and MMF.

    python benchmarks/diagnose_shell.py [--drums 1] [--zone-mm 9] [--gap-mm 0.7]
        [--thickness-mm 0.3] [--bore-mm 18] [--current 7] [--fem-mm 0.25]

The rest of the design is the paper preset (``diagnose_zones``' options). FEM fluxes are
2π·ψ differences across the back iron's mid-plane (``diagnose_zones._psi``): inside the
pole's radius (the drums and gaps), the window (pole radius to the back iron), the back
iron, and outside it to the domain's edge. Network: the shell's loop flux x_{m−1} + x_w,
the outer air's x_o, the back iron's share (the shell's less the air's) and the window's
x_w. The back iron's MMF in the FEM: ∫H_z dz along the shell's outer face, H_z = B_z/μ0 in
the first air cell outside it (tangential H is continuous), over the band and over the
network's span (zone centre to zone centre). Used for docs/magnetics.md's "The shell,
traced".
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnose_zones import _psi, design_from_args

from geometry.section import build_section
from magnetics.fem import build_grid, solve_fem
from magnetics.materials import MU0, magnetic
from magnetics.network import network_from_regions, solve_network


def main() -> None:
    a, kw, c, rg, at = design_from_args(9.0, 18.0, 7.0)
    net = network_from_regions(rg)
    m = net.m
    x = solve_network(net, [[c.coil_turns * a.current]])[0, 0]
    shell, window, air = abs(x[m - 1] + x[m]), abs(x[m]), abs(x[m + 1])
    back = shell - air
    steel = magnetic(net.steel)
    # the back iron's MMF, w·H(k·Φ) (one Gauss point), as the network's kernel reads it
    mmf = float(net.back_w[0, 0] * steel.h_dh(np.array([net.back_k[0, 0] * back]))[0][0])
    spec = {sp.name: sp for sp in rg}
    b, pole = spec["shell_back"], spec["shell_A"]
    r_p, r0, r1 = at[pole.r0], at[b.r0], at[b.r1]
    area = np.pi * (r1**2 - r0**2)
    sec = build_section(c)
    grid = build_grid(sec, a.fem_mm * 1e-3)
    flux = _psi(grid, solve_fem(sec, a.current, grid=grid))
    zm = 0.5 * (at[b.z0] + at[b.z1])
    edge = 0.999 * float(grid.r_lines.max())
    f_in, f_p, f_b, f_out = (abs(flux(r, zm)) for r in (r_p, r0, r1, edge))
    fem = {"window": abs(f_p - f_in), "back": abs(f_b - f_p), "air": abs(f_out - f_b)}
    r2 = grid.r_lines[np.searchsorted(grid.r_lines, r1 + 1e-9)]  # the first air cell
    z = np.linspace(at[pole.z0], at[spec["shell_B"].z1], 2001)
    hz = np.array([(flux(r2, zz) - flux(r1, zz)) / (np.pi * (r2**2 - r1**2)) for zz in z]) / MU0
    pot = np.concatenate([[0.0], np.cumsum(0.5 * (hz[1:] + hz[:-1]) * np.diff(z))])
    za, zb = 0.5 * (at["zone_A0"] + at["zone_A1"]), 0.5 * (at["zone_B0"] + at["zone_B1"])
    drop = {k: abs(np.interp(b1, z, pot) - np.interp(b0, z, pot))
            for k, (b0, b1) in (("band", (at[b.z0], at[b.z1])), ("span", (za, zb)))}  # fmt: skip
    print(f"{kw} at {a.current} A; back iron {r0 * 1e3:.2f}-{r1 * 1e3:.2f} mm over "
          f"{(at[b.z1] - at[b.z0]) * 1e3:.2f} mm (network's length "
          f"{net.back_w[0, 0] * 1e3:.2f} mm), its MMF in the network {mmf:.0f} of "
          f"{c.coil_turns * a.current:.0f} A; in the FEM {drop['span']:.0f} A over that span, "
          f"{drop['band']:.0f} A over the back iron")  # fmt: skip
    print("flux at the back iron's mid-plane (µWb) | network | FEM")
    print(f"back iron + outside air               | {shell * 1e6:7.1f} | "
          f"{(fem['back'] + fem['air']) * 1e6:7.1f}")  # fmt: skip
    print(f"back iron (B, T)                      | {back * 1e6:7.1f} ({back / area:.3f}) | "
          f"{fem['back'] * 1e6:7.1f} ({fem['back'] / area:.3f})")  # fmt: skip
    print(f"air outside the shell                 | {air * 1e6:7.1f} | {fem['air'] * 1e6:7.1f}")
    print(f"coil window                           | {window * 1e6:7.1f} | "
          f"{fem['window'] * 1e6:7.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
