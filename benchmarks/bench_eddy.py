"""The eddy lag: the 1-D diffusion model (magnetics.dynamics) against the time-harmonic FEM
(magnetics.fem.eddy) on the paper preset and variants, at torque_response's operating point
(half the peak gap flux at 7 A). Prints the delay, each part's share and the phase at
50/100/200 Hz (docs/dynamics.md, "The eddy lag against the FEM").

    python benchmarks/bench_eddy.py [--size 0.25] [--current 7]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from geometry.params import preset
from geometry.section import build_section
from magnetics.fem.eddy import (
    FREQUENCIES,
    WITH_STAINLESS,
    bias_current,
    diffusion_eddy,
    eddy_response,
)
from magnetics.laminations import Laminations

PARTS = ("core", "poles", "back_iron", "drums")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=float, default=0.25, help="FEM element size, mm")
    ap.add_argument("--current", type=float, default=7.0, help="peak current, A")
    a = ap.parse_args()
    p = preset("paper")
    lam = Laminations(shell=0.5e-3)
    variants = [
        ("paper", p, None, None),
        ("shell 1.0 mm", replace(p, shell_thickness=1.0e-3), None, None),
        ("shell 2.0 mm", replace(p, shell_thickness=2.0e-3), None, None),
        ("core Ø8.1 mm", replace(p, drum_inner_diameter=9.5e-3), None, None),
        ("core Ø12.1 mm", replace(p, drum_inner_diameter=13.5e-3), None, None),
        ("shell laminated 0.5 mm", p, lam, None),
        ("core laminated 0.5 mm", p, Laminations(core=0.5e-3), None),
        ("paper + stainless σ", p, None, WITH_STAINLESS),
    ]
    f = FREQUENCIES
    print(f"FEM {a.size:g} mm, operating point: half the peak gap flux at {a.current:g} A\n")
    head = "".join(f"{q:>10}" for q in PARTS)
    print(f"{'variant':<24}{'I_b':>6}{'τ 1-D':>8}{'τ FEM':>8}{'err':>7} | parts 1-D / FEM [ms]"
          + head)  # fmt: skip
    rows = []
    for name, c, lm, sig in variants:
        s = build_section(c)
        ib = bias_current(s, a.current)
        d = diffusion_eddy(s, ib, f, lm)
        t0 = time.perf_counter()
        fem = eddy_response(s, ib, f, size=a.size * 1e-3, laminations=lm, conductivity=sig)
        dt = time.perf_counter() - t0
        parts = "".join(f"{1e3 * d.parts[q]:>5.2f}/{1e3 * fem.parts[q]:<4.2f}" for q in PARTS)
        other = f"  other {1e3 * fem.parts['other']:.3f}" if fem.parts["other"] else ""
        print(f"{name:<24}{ib:>6.2f}{1e3 * d.delay:>8.3f}{1e3 * fem.delay:>8.3f}"
              f"{d.delay / fem.delay - 1:>+7.0%} | {'':<21}{parts}{other}")  # fmt: skip
        rows.append((name, d, fem, dt))
    print(f"\nphase [°] at {', '.join(f'{x:g}' for x in f)} Hz: first-order lag (torque_response) "
          "/ full 1-D diffusion / FEM")  # fmt: skip
    for name, d, fem, dt in rows:
        ph = lambda z: np.degrees(np.angle(z))  # noqa: E731
        trip = zip(ph(d.lag), ph(d.transfer), fem.phase_deg, strict=True)
        cells = "  ".join(f"{x:6.1f}/{y:6.1f}/{z:6.1f}" for x, y, z in trip)
        print(f"{name:<24}{cells}   (FEM {dt:.2f} s, {fem.dofs} dofs)")


if __name__ == "__main__":
    main()
