"""How far the mid-line torque convention is above the weakest-layer one, and what the
band's fluid adds (issue 12, "Torque convention"; docs/magnetics.md).

1. Circuit over the stored error map's 648 designs (magnetics/data/circuit_error_map.json
   axes, the paper preset elsewhere, each at its current limit): mid-line/weakest − 1 per
   drum count (min / median / max).
2. FEM (0.25 mm) on the paper preset and a handful of designs: the same ratio from one
   solve, both conventions.
3. The band on the paper preset at 7 A: the FEM's mean |H| and |H_r| in each gap's band
   fluid over the zone's, and the torque with and without the band (active zones only),
   circuit and FEM, both conventions; the paper's Fig. 2b gives ~0.4 N·m at 7 A.

    python benchmarks/measure_torque_convention.py [--skip-map] [--skip-fem]   # ~1 min
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from geometry.regions import ZONES  # noqa: E402
from geometry.section import build_section  # noqa: E402
from geometry.validation import ParameterError  # noqa: E402
from magnetics.circuit import path_from_section, solve_path  # noqa: E402
from magnetics.fem import build_grid, solve_fem  # noqa: E402
from magnetics.materials import FLUIDS  # noqa: E402
from magnetics.torque import _gap_torque, torque_curve  # noqa: E402
from mrclutch.design import design_preset  # noqa: E402

MAP = ROOT / "magnetics" / "data" / "circuit_error_map.json"
FEM_SIZE = 0.25e-3
CONV = ("mid-line", "weakest-layer")


def _designs():  # type: ignore[no-untyped-def]
    base = design_preset("paper")
    axes = json.loads(MAP.read_text())["axes"]
    for v in itertools.product(*axes.values()):
        kw = {k: (int(x) if k == "n_drums" else x) for k, x in zip(axes, v, strict=True)}
        try:
            c = replace(base.clutch, **kw)
        except ParameterError:
            continue
        yield kw, c, replace(base, clutch=c).current_limit


def circuit_map() -> None:
    rows: dict[int, list[float]] = {}
    for kw, c, i in _designs():
        t = [
            float(torque_curve(c, [i], method="circuit", convention=cv).yield_torque[0])
            for cv in CONV
        ]
        rows.setdefault(kw["n_drums"], []).append(t[0] / t[1] - 1)
    print("circuit, map designs at the current limit: mid-line / weakest-layer - 1 (%)")
    print("drums  n    min   median   max")
    allv = []
    for n, v in sorted(rows.items()):
        a = 100 * np.array(v)
        allv += v
        print(f"{n:5d} {a.size:4d} {a.min():6.2f} {np.median(a):6.2f} {a.max():6.2f}")
    a = 100 * np.array(allv)
    print(f"  all {a.size:4d} {a.min():6.2f} {np.median(a):6.2f} {a.max():6.2f}")


def _fem_both(c, i):  # type: ignore[no-untyped-def]
    s = build_section(c)
    fl = FLUIDS[s.region(f"gap{s.gaps[0].index}").material]
    sol = solve_fem(s, float(i), grid=build_grid(s, FEM_SIZE))
    return s, fl, sol, [float(sol.gap_yield_torque(fl, convention=cv).sum()) for cv in CONV]


def fem_designs() -> None:
    base = design_preset("paper")
    cases = {
        "paper": {},
        "1 drum": {"n_drums": 1},
        "3 drums": {"n_drums": 3},
        "6 drums": {"n_drums": 6},
        "gap 0.2 mm": {"gap": 0.2e-3},
        "gap 1.0 mm": {"gap": 1.0e-3},
        "bore 6 mm": {"drum_inner_diameter": 6e-3},
    }
    print(f"\nFEM {FEM_SIZE * 1e3} mm and circuit at the current limit: mid/weakest - 1 (%)")
    for name, kw in cases.items():
        c = replace(base.clutch, **kw)
        i = replace(base, clutch=c).current_limit
        *_, t = _fem_both(c, i)
        tc = [
            float(torque_curve(c, [i], method="circuit", convention=cv).yield_torque[0])
            for cv in CONV
        ]
        print(f"{name:12s} I={i:.2f} A  FEM {t[0]:.4f}/{t[1]:.4f} N·m "
              f"{100 * (t[0] / t[1] - 1):5.2f}  circuit {tc[0]:.4f}/{tc[1]:.4f} "
              f"{100 * (tc[0] / tc[1] - 1):5.2f}")  # fmt: skip


def band(current: float = 7.0) -> None:
    c = design_preset("paper").clutch
    s, fl, sol, t_all = _fem_both(c, current)
    at = s.table.at
    zones = [(float(np.ravel(at[a])[0]), float(np.ravel(at[b])[0])) for _, a, b in ZONES]
    h = sol.h()
    print(f"\nBand on the paper preset at {current} A (FEM {FEM_SIZE * 1e3} mm)")
    print("gap  |H| band/zone  |H_r| band/zone  (means over the gap's cells)")
    hr_all = h * np.abs(sol.b_r) / np.where(sol.b > 0, sol.b, 1.0)
    fem_zone = {cv: 0.0 for cv in CONV}
    for gp, (r, dz, br, bz), (zc, _dz, bav, brav) in zip(
        s.gaps, sol.gap_lines, sol.gap_profiles, strict=True
    ):
        inz = np.zeros(zc.shape, bool)
        for z0, z1 in zones:
            inz |= (zc > z0) & (zc < z1)
        cell = (sol.centre_r > gp.r_inner) & (sol.centre_r < gp.r_outer)
        cell &= (sol.centre_z > gp.z0) & (sol.centre_z < gp.z1)
        zin = np.zeros(cell.shape, bool)
        for z0, z1 in zones:
            zin |= (sol.centre_z > z0) & (sol.centre_z < z1)
        hz, hb = h[cell & zin].mean(), h[cell & ~zin].mean()
        hrz, hrb = hr_all[cell & zin].mean(), hr_all[cell & ~zin].mean()
        print(f"gap{gp.index}   {hb / hz:6.3f}         {hrb / hrz:6.3f}   "
              f"(zone |H| {hz / 1e3:.0f} kA/m)")  # fmt: skip
        # zone-only torques: the same rows, band rows dropped
        bmag = np.hypot(br, bz)
        h_r = fl_mag(fl).h_of_b(bmag) * np.abs(br) / np.where(bmag > 0, bmag, 1.0)
        f = r[:, None] ** 2 * fl.tau_y(h_r)
        fem_zone["weakest-layer"] += 2 * np.pi * np.sum((f.min(axis=0) * dz)[inz])
        hm = fl_mag(fl).h_of_b(bav) * brav / np.where(bav > 0, bav, 1.0)
        rm = 0.5 * (gp.r_inner + gp.r_outer)
        fem_zone["mid-line"] += 2 * np.pi * rm**2 * np.sum((fl.tau_y(hm) * dz)[inz])
    path = path_from_section(s)
    res = solve_path(path, np.array([[current]]))
    nob = dataclasses.replace(path, band_len=np.zeros_like(path.band_len))
    visc = float(torque_curve(c, [current]).off_state_torque)
    print(f"\nyield torque at {current} A (N·m), + viscous {visc * 1e3:.2f} mN·m for the paper's"
          " ~0.4 N·m (Fig. 2b)")  # fmt: skip
    print("convention       circuit all  circuit zones  FEM all  FEM zones")
    for k, cv in enumerate(CONV):
        args = (np.abs(res.flux), res.radial_mmf, None, None, cv)
        ca = float(_gap_torque(path, *args).sum())
        cz = float(_gap_torque(nob, *args).sum())
        print(f"{cv:15s} {ca:10.4f} {cz:13.4f} ({100 * (cz / ca - 1):+.1f} %) {t_all[k]:8.4f}"
              f" {fem_zone[cv]:9.4f} ({100 * (fem_zone[cv] / t_all[k] - 1):+.1f} %)")  # fmt: skip


def fl_mag(fl):  # type: ignore[no-untyped-def]
    from magnetics.materials import magnetic

    return magnetic(fl.name)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-map", action="store_true")
    ap.add_argument("--skip-fem", action="store_true")
    a = ap.parse_args()
    if not a.skip_map:
        circuit_map()
    if not a.skip_fem:
        fem_designs()
    band()


if __name__ == "__main__":
    main()
