"""The continuous rating's chords against the exact fixed point, on many random designs.

    python benchmarks/bench_chords.py [--designs 2000] [--seed 7]

``continuous_torque`` (three chords through the network's curve, ``network_yield_at``: what
the sweep's rows and ``evaluate`` report) against the exact root of
I² = I_cont²(ω·(T_off + T(I))) by bisection on [0, I_a] with a network solve at every step
(45 halvings: 2.8e-14 of I_a), on random designs of 1–4 drums (bench_against's ranges),
the same networks, thermal networks and drag as ``evaluate_batch`` builds (captured from
one call of it). Prints, per drum count, the largest and the 99th-percentile relative
error of the rating's current and torque (rows with a rating > 0), and the share of rows
whose torque error exceeds the row's own ``torque_error_bound``.
"""

from __future__ import annotations

import argparse

import numpy as np

from magnetics.thermal import continuous_current_sq
from magnetics.torque import continuous_torque, network_yield_at


def fields(n: int, seed: int) -> dict[str, np.ndarray]:
    """bench_against.py's random designs (SI)."""
    rng = np.random.default_rng(seed)
    return {"n_drums": rng.integers(1, 5, n), "gap": rng.uniform(0.2e-3, 1.0e-3, n),
            "drum_thickness": rng.uniform(0.1e-3, 0.6e-3, n),
            "zone_length": rng.uniform(3e-3, 9e-3, n),
            "drum_inner_diameter": rng.uniform(6e-3, 18e-3, n)}  # fmt: skip


def exact(net, w, off, wire, limit, ladder):  # type: ignore[no-untyped-def]
    """(current, torque) at the exact fixed point, by bisection (h(I) increasing)."""
    at = network_yield_at(ladder)
    w, off = abs(w), np.asarray(off, dtype=float)
    i_sq = continuous_current_sq(net, wire, limit)
    i_a = np.sqrt(np.maximum(i_sq(off * w), 0.0))
    lo, hi = np.zeros_like(i_a), i_a.copy()
    for _ in range(45):
        mid = 0.5 * (lo + hi)
        up = mid * mid <= i_sq((off + at(mid)) * w)
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    return lo, np.where(i_a > 0, off + at(lo), 0.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    import mrclutch.fast_batch as fb

    calls = []

    def captured(net, path, w, off, wire, limit, torque_at=None, **kw):  # type: ignore[no-untyped-def]
        got = continuous_torque(net, path, w, off, wire, limit, torque_at=torque_at, **kw)
        calls.append((net, w, off, wire, limit, torque_at._net, got))
        return got

    fb.continuous_torque = captured  # the evaluator's own arguments, unchanged
    out = fb.evaluate_batch(fields(a.designs, a.seed))
    n_drums = fields(a.designs, a.seed)["n_drums"]
    print(f"continuous rating against the exact fixed point, {a.designs} designs "
          f"(seed {a.seed}): relative error, max / 99th percentile")  # fmt: skip
    for net, w, off, wire, limit, ladder, (i_c, t_c) in calls:
        i_x, t_x = exact(net, w, off, wire, limit, ladder)
        rows = t_c > 0
        ei, et = (np.abs(u[rows] / v[rows] - 1) for u, v in ((i_c, i_x), (t_c, t_x)))
        # the rows of this drum count among the batch's valid ones, in order
        mine = (out["valid"] > 0) & (n_drums == (ladder.m // 2))
        over = float(np.mean(et > out["torque_error_bound"][mine][rows])) if rows.any() else 0
        print(f"  {ladder.m // 2} drum(s), {int(rows.sum())} rows: current {ei.max():.2e} / "
              f"{np.percentile(ei, 99):.2e}, torque {et.max():.2e} / "
              f"{np.percentile(et, 99):.2e}; torque error over the row's bound: "
              f"{100 * over:.1f} %")  # fmt: skip


if __name__ == "__main__":
    main()
