"""The continuous rating's chords against the exact fixed point, on many random designs.

    python benchmarks/bench_chords.py [--designs 2000] [--seed 7]
    python benchmarks/bench_chords.py --timing [--designs 20000] [--rounds 7]

``continuous_torque`` (three chords through the network's curve, ``network_yield_at``: what
the sweep's rows and ``evaluate`` report) against the exact root of
I² = I_cont²(ω·(T_off + T(I))) by bisection on [0, I_a] with a network solve at every step
(45 halvings: 2.8e-14 of I_a), on random designs of 1–4 drums (bench_against's ranges),
the same networks, thermal networks and drag as ``evaluate_batch`` builds (captured from
one call of it). Prints, per drum count, the largest and the 99th-percentile relative
error of the rating's current and torque (rows with a rating > 0), and the share of rows
whose torque error exceeds the row's own ``torque_error_bound``.

``--timing`` (no errors) times, on the same captured inputs, each started from the sweep's
peak state, the rating (``continuous_torque`` on ``network_yield_at``: the secant on the
slope, ``slope_rating``) against the three chords it replaced (kept here as ``chords``:
three solves, the first two at rtol 1e-6), interleaved, CPU seconds per call over every
drum count: the median and the least of ``--rounds`` (the sweep's stage alone, which
bench_against.py's whole-row rate shows only through the machine's noise).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from geometry.numerics import illinois
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


def chords(net, w, off, wire, limit, at):  # type: ignore[no-untyped-def]
    """The rating as it was before ``slope_rating``: three chords through the curve, each
    at the last one's fixed point (the first two solved to rtol 1e-6), the current."""
    w, off = abs(w), np.asarray(off, dtype=float)
    i_sq = continuous_current_sq(net, wire, limit)
    i_a = np.sqrt(np.maximum(i_sq(off * w), 0.0))

    def fixed_point(c1, rtol):  # type: ignore[no-untyped-def]
        x_all = i_a.copy()

        def h(act, x):  # type: ignore[no-untyped-def]
            x_all[act] = x
            return (x_all * x_all - i_sq((off + c1 * x_all) * w))[act]

        rows, lo = np.arange(i_a.size), np.zeros_like(i_a)
        h_hi = h(rows, i_a.copy())
        return illinois(h, lo, i_a, h(rows, lo), h_hi, rtol)

    i = i_a
    for k in range(3):
        t = at(i) if k == 2 else at(i, rtol=1e-6)
        c1 = np.where(i > 0, t / np.where(i > 0, i, 1.0), 0.0)
        i = fixed_point(c1, 1e-9 if k == 2 else 1e-4)
    return i


def timing(calls, rounds: int) -> None:  # type: ignore[no-untyped-def]
    """``--timing``: CPU seconds of the rating and of the three chords on ``calls``."""
    cpu: dict[str, list[float]] = {"secant on the slope (now)": [], "three chords (before)": []}
    for _ in range(rounds):
        for name in cpu:
            t = time.process_time()
            for net, path, w, off, wire, limit, ladder, seed in calls:
                at = network_yield_at(ladder, seed=seed)  # from the peak, as in the sweep
                if name.startswith("three"):
                    chords(net, w, off, wire, limit, at)
                else:
                    continuous_torque(net, path, w, off, wire, limit, torque_at=at)
            cpu[name].append(time.process_time() - t)
    for name, v in cpu.items():
        print(f"  {name:<28} median {np.median(v):.3f} s, least {min(v):.3f} s CPU")
    now, before = (np.median(v) for v in cpu.values())
    print(f"  ratio now/before {now / before:.2f} (medians of {rounds} interleaved rounds)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--timing", action="store_true", help="time the rating (no errors)")
    ap.add_argument("--rounds", type=int, default=7, help="--timing's rounds")
    a = ap.parse_args()
    import mrclutch.fast_batch as fb

    calls, inputs = [], []

    def captured(net, path, w, off, wire, limit, torque_at=None, **kw):  # type: ignore[no-untyped-def]
        seed = (torque_at._state["i"][:, 0].copy(), torque_at.flux.copy())  # the peak's
        inputs.append((net, path, w, off, wire, limit, torque_at._net, seed))
        got = continuous_torque(net, path, w, off, wire, limit, torque_at=torque_at, **kw)
        calls.append((net, w, off, wire, limit, torque_at._net, got))
        return got

    fb.continuous_torque = captured  # the evaluator's own arguments, unchanged
    if a.timing:
        fb.evaluate_batch(fields(a.designs, a.seed))  # imports, kernels loaded
        print(f"continuous rating, {a.designs} designs (seed {a.seed}), CPU per call:")
        timing(inputs, a.rounds)
        return
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
