"""Geometry speed and speed-vs-accuracy.

    python -m pytest benchmarks/bench_geometry.py --benchmark-enable
    python benchmarks/bench_geometry.py [OUT.png]   # table, slope fit, log-log chart

Goals: build + STEP + STL of the paper preset < 1.5 s after import; analytic mass of 10⁵
designs < 50 ms; mesh inertia error falling with the chord-height theory's slope.

Chord-height theory: a circle of radius r cut into chords of sagitta δ loses the area
fraction ≈ (4/3)·δ/r (segment area (2/3)·c·δ per chord, c² ≈ 8rδ), so the relative
volume/inertia error of the mesh is ∝ δ: expected slope 1 in log(error) vs log(δ) while
the linear deflection, not the angular one, sets the chords.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from geometry.params import preset
from geometry.section import build_section

PAPER = preset("paper")
TOLERANCES_MM = (0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001)


def _designs(s: int = 100_000) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(1)
    return {
        "gap": rng.uniform(0.3e-3, 1.0e-3, s),
        "n_drums": rng.integers(1, 5, s),
        "drum_thickness": rng.uniform(0.1e-3, 0.5e-3, s),
        "zone_length": rng.uniform(4e-3, 8e-3, s),
    }


def build_and_export(out_dir: str) -> None:
    from geometry.export import export_clutch

    export_clutch(PAPER, out_dir, 1e-5, check=False)


def test_build_step_stl_paper(benchmark, tmp_path):  # goal < 1.5 s
    import build123d  # noqa: F401  (import time is not part of the goal)

    benchmark.pedantic(build_and_export, args=(str(tmp_path),), rounds=3, iterations=1)
    assert (tmp_path / "rotor.stl").exists()


def test_analytic_batch_1e5(benchmark):  # goal < 50 ms
    from geometry.mass import analytic_batch

    f = _designs()
    res = benchmark.pedantic(analytic_batch, args=(f,), rounds=10, iterations=1, warmup_rounds=1)
    assert res["rotor_inertia"].shape == (100_000,)


def error_vs_time() -> list[tuple[str, float, float, float]]:
    """(method, tolerance mm or nan, relative rotor-inertia error vs B-rep, seconds)."""
    from geometry.cad import material_solids
    from geometry.mass import analytic_mass, brep_mass, mesh_mass

    s = build_section(PAPER)
    t0 = time.perf_counter()
    solids = material_solids(PAPER, s)
    t_build = time.perf_counter() - t0
    t0 = time.perf_counter()
    exact = brep_mass(PAPER, solids).rotor_inertia
    rows = [("brep", float("nan"), 0.0, time.perf_counter() - t0 + t_build)]
    t0 = time.perf_counter()
    a = analytic_mass(s).rotor_inertia
    rows.append(("analytic", float("nan"), abs(a / exact - 1), time.perf_counter() - t0))
    for tol in TOLERANCES_MM:
        t0 = time.perf_counter()
        m = mesh_mass(PAPER, tol * 1e-3, guard=False, solids=solids).rotor_inertia
        rows.append(("mesh", tol, abs(m / exact - 1), time.perf_counter() - t0 + t_build))
    return rows


def _time(fn, *args, rounds: int = 5) -> float:
    fn(*args)
    best = np.inf
    for _ in range(rounds):
        t0 = time.perf_counter()
        fn(*args)
        best = min(best, time.perf_counter() - t0)
    return best


def main(out_png: str | None = None) -> None:
    import build123d  # noqa: F401

    from geometry.mass import analytic_batch

    with tempfile.TemporaryDirectory() as d:
        t_export = _time(build_and_export, d, rounds=3)
    t_batch = _time(analytic_batch, _designs(), rounds=10)
    print(f"build + STEP + STL (paper, 0.01 mm): {t_export * 1e3:.0f} ms   (goal < 1500 ms)")
    print(f"analytic_batch, 1e5 designs:        {t_batch * 1e3:.1f} ms   (goal < 50 ms)")

    rows = error_vs_time()
    print(f"\n{'method':<9} {'tol mm':>8} {'rel. error':>11} {'time s':>8}")
    for m, tol, err, t in rows:
        print(f"{m:<9} {tol:>8.3g} {err:>11.3e} {t:>8.3f}")
    mesh = [(tol, err) for m, tol, err, _ in rows if m == "mesh" and err > 0]
    tol, err = np.array(mesh).T
    slope, _ = np.polyfit(np.log(tol), np.log(err), 1)
    coef = np.exp(np.mean(np.log(err) - np.log(tol)))
    print(f"\nfitted slope of log(error) vs log(tolerance): {slope:.3f} (chord-height theory: 1)")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 4))
    ax0.loglog(tol, err, "o-", label=f"mesh (fit slope {slope:.2f})")
    ax0.loglog(tol, coef * tol, "k--", label="∝ δ (chord-height theory)")
    ax0.set_xlabel("mesh tolerance δ (mm)")
    ax0.set_ylabel("rotor inertia error vs B-rep")
    ax0.legend()
    times = [t for m, _, _, t in rows if m == "mesh" and _ > 0]
    ax1.loglog(times, err, "o-", label="mesh")
    for m, _, e, t in rows:
        if m != "mesh":
            ax1.loglog([t], [max(e, 1e-16)], "s", label=f"{m} (error {e:.0e})")
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("rotor inertia error vs B-rep")
    ax1.legend()
    fig.tight_layout()
    out = Path(out_png or Path(__file__).parent / "out" / "geometry_error_vs_time.png")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"chart: {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
