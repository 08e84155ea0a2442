"""FEM speed against accuracy, old against new, in one run (issue 12).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fem_speed.py [--rounds 3]

Torque of the paper preset at 2, 4 and 7 A. Reference: Richardson extrapolation of the
uniform grid at 0.25, 0.125 and 0.0625 mm with the observed order per current (printed).
"old": the FEM as it was before the speed-up (kept here verbatim as ``_old_newton``):
scikit-fem's generic assembly every Newton step, SuperLU with its default ordering and a
fresh factorisation every step, one grid for the curve, each current warm-started.
"new": ``torque_curve(method="fem")`` — the grid's forms assembled once per grid, CG on the
last factorised Jacobian, currents in increasing order each warm-started, on the uniform
grid (same numbers as old) or the graded one. Times are per current, grid building
included, the median of the interleaved rounds (a shared machine: read the ratios).
Goals: ≤ 0.5 s per current at 0.2 % and ≤ 0.3 s at 1 %.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from geometry.params import preset
from geometry.section import build_section
from magnetics.fem import build_grid
from magnetics.fem.post import post_process
from magnetics.materials import MRF_132DG
from magnetics.torque import torque_curve

CURRENTS = (2.0, 4.0, 7.0)


def _old_newton(grid, current, j_element, psi0, tol=1e-8, max_iter=40):  # type: ignore[no-untyped-def]
    """magnetics/fem/newton.py before the speed-up (commit e29d0a4), for the timing."""
    import skfem

    from magnetics.fem.forms import forms, nu_terms

    jac, resid, load = forms()
    basis, D = grid.basis, grid.fixed
    jq = j_element[:, None] * np.ones_like(grid.r_qp)
    f = skfem.asm(load, basis, j=jq)
    free = np.setdiff1d(np.arange(basis.N), D)
    fnorm = max(np.linalg.norm(f[free]), 1e-300)

    def residual(psi):  # type: ignore[no-untyped-def]
        g, nu, dnu = nu_terms(grid, psi)
        rv = skfem.asm(resid, basis, nu=nu, g=g, j=jq)
        return rv, np.linalg.norm(rv[free]), (g, nu, dnu)

    psi = np.zeros(basis.N) if psi0 is None else psi0
    rv, rn, terms = residual(psi)
    it = 0
    while rn > tol * fnorm and it < max_iter:
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
    return psi, it, float(rn / fnorm)


def _old_solve(size: float) -> tuple[np.ndarray, int]:
    """Old torque_curve: one grid, each current's Newton started from the last field."""
    s = build_section(preset("paper"))
    out, psi = [], None
    g = build_grid(s, size)
    for i in CURRENTS:
        j = np.where(g.coil_mask, s.clutch.coil_turns * i / g.coil_area, 0.0)
        psi, it, res = _old_newton(g, i, j, psi)
        out.append(post_process(g, i, psi, it, res).gap_yield_torque(MRF_132DG).sum())
    return np.array(out), g.basis.N


def _new_solve(size: float, mesh: str) -> tuple[np.ndarray, int]:
    c = torque_curve(preset("paper"), CURRENTS, method="fem", fem_size=size, fem_mesh=mesh)
    n = build_grid(build_section(preset("paper")), size, mesh=mesh).basis.N
    return c.yield_torque, n


def reference() -> np.ndarray:
    t = [_new_solve(h, "uniform")[0] for h in (0.25e-3, 0.125e-3, 0.0625e-3)]
    order = np.log2((t[0] - t[1]) / (t[1] - t[2]))
    ref = t[2] + (t[2] - t[1]) / (2**order - 1)
    print(f"reference (Richardson, uniform 0.25/0.125/0.0625 mm): {np.round(ref, 6)} N·m, "
          f"observed order {np.round(order, 2)}; 0.0625 mm is "
          f"{np.round(100 * (t[2] / ref - 1), 3)} % off it")  # fmt: skip
    return ref


CASES = [("old", "uniform", h) for h in (0.5e-3, 0.25e-3, 0.125e-3, 0.09e-3)] + [
    ("new", m, h)
    for m, hs in (("uniform", (0.5e-3, 0.25e-3, 0.125e-3, 0.09e-3)),
                  ("graded", (0.25e-3, 0.18e-3, 0.125e-3, 0.09e-3, 0.08e-3)))
    for h in hs
]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    _new_solve(1e-3, "graded")  # imports out of the timings
    ref = reference()
    times: dict[tuple[str, str, float], list[float]] = {c: [] for c in CASES}
    res: dict[tuple[str, str, float], tuple[np.ndarray, int]] = {}
    for _ in range(a.rounds):  # interleaved: load on a shared machine hits all alike
        for c in CASES:
            t0 = time.perf_counter()
            res[c] = _old_solve(c[2]) if c[0] == "old" else _new_solve(c[2], c[1])
            times[c].append((time.perf_counter() - t0) / len(CURRENTS))
    med = {c: statistics.median(v) for c, v in times.items()}
    err = {c: float(np.max(np.abs(res[c][0] / ref - 1))) for c in CASES}
    print(f"\n{'code':5}{'mesh':9}{'size mm':>8}{'unknowns':>10}{'s/current':>11}"
          f"{'max |err|':>11}{'old/this':>10}")  # fmt: skip
    for c in CASES:
        old = med.get(("old", "uniform", c[2]))
        ratio = f"{old / med[c]:10.2f}" if old and c[1] == "uniform" else f"{'':10}"
        print(f"{c[0]:5}{c[1]:9}{c[2] * 1e3:8.3f}{res[c][1]:10d}{med[c]:11.3f}"
              f"{100 * err[c]:10.3f}%{ratio}")  # fmt: skip
    print()
    for target, goal in ((0.002, 0.5), (0.01, 0.3)):
        best = {}
        for code in ("old", "new"):
            ok = [c for c in CASES if c[0] == code and err[c] <= target]
            best[code] = min(ok, key=med.get) if ok else None
        o, n = best["old"], best["new"]
        fmt = lambda c: "none" if c is None else f"{c[1]} {c[2] * 1e3:g} mm {med[c]:.3f} s"  # noqa: E731
        ratio = f", {med[o] / med[n]:.1f}× faster" if o and n else ""
        print(
            f"within {target:.1%}: old fastest {fmt(o)}; new fastest {fmt(n)}{ratio} "
            f"(goal ≤ {goal} s: {'met' if n and med[n] <= goal else 'NOT met'})"
        )


if __name__ == "__main__":
    main()
