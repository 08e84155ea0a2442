"""Speed against accuracy, to compare releases: every method's time ratio to the fastest of
its quantity and its error; then the accuracy-target acceptance — `evaluate(accuracy=0.01)`
against the reference fidelity on the paper preset (time ratio, errors), all in one run.

    python benchmarks/bench_fidelity.py [--accuracy 0.01] [--repeats 3] [--no-timing]

``--no-timing``: the accuracy target's errors alone (one reference and one target
evaluation, the same line without its times): what docs/figures.toml reads of it, without
the table's timed methods and the timed rounds (≈ 3× the CPU).
"""

from __future__ import annotations

import argparse
import statistics
import time

from mrclutch.design import design_preset
from mrclutch.fidelity import measure
from mrclutch.pipeline import evaluate


def _median_time(fn, n):  # type: ignore[no-untyped-def]
    ts, out = [], None
    for _ in range(n):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), out


def _errors(ev, ref) -> str:  # type: ignore[no-untyped-def]
    """The target's relative errors against the reference evaluation, as printed."""
    e_i = abs(ev.clutch.rotor_inertia / ref.clutch.rotor_inertia - 1)
    e_t = abs(ev.clutch.max_torque / ref.clutch.max_torque - 1)
    e_b = abs(ev.haptic["bandwidth_hz"] / ref.haptic["bandwidth_hz"] - 1)
    return f"errors: inertia {e_i:.1e}, torque {e_t:.1e}, bandwidth {e_b:.1e}"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--accuracy", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-timing", action="store_true", help="the target's errors alone")
    a = ap.parse_args()
    d = design_preset("paper")
    if a.no_timing:
        ref, acc = evaluate(d, "reference"), evaluate(d, accuracy=a.accuracy)
        print(f"  accuracy={a.accuracy:g}  {_errors(acc, ref)}")
        return
    evaluate(d, "reference")  # warm the imports (build123d, skfem) out of the timings

    rows = measure(d, repeats=a.repeats)
    qs = {r.quantity for r in rows}
    fastest = {q: min(r.time_s for r in rows if r.quantity == q) for q in qs}
    print(f"{'quantity':<10}{'method':<20}{'setting':<20}{'t/fastest':>10}{'error':>10}")
    for r in rows:
        print(f"{r.quantity:<10}{r.method:<20}{r.setting:<20}"
              f"{r.time_s / fastest[r.quantity]:>10.3g}{r.error_rel:>10.2e}")  # fmt: skip

    # Interleaved so that load on a shared machine hits both sides alike: each reference
    # run is followed by the cheap paths, each timed as the median of `inner` calls.
    inner = 25
    t_ref, t_acc, t_fast = [], [], []
    for _ in range(a.repeats):
        t, ref = _median_time(lambda: evaluate(d, "reference"), 1)
        t_ref.append(t)
        t, acc = _median_time(lambda: evaluate(d, accuracy=a.accuracy), inner)
        t_acc.append(t)
        t, fast = _median_time(lambda: evaluate(d, "fast"), inner)
        t_fast.append(t)
    med = statistics.median
    print(f"\nevaluate on the paper preset ({a.repeats} rounds: 1 reference run, then the "
          f"median of {inner} calls of each cheap path; ratio = median over rounds):")  # fmt: skip
    for name, ts, ev in (("fast", t_fast, fast), (f"accuracy={a.accuracy:g}", t_acc, acc)):
        ratios = [r / t for r, t in zip(t_ref, ts, strict=True)]
        print(f"  {name:<16} {med(ts) * 1e3:8.2f} ms   {med(ratios):7.1f}× faster than "
              f"reference ({med(t_ref):.2f} s; rounds {min(ratios):.0f}–{max(ratios):.0f}×)   "
              f"{_errors(ev, ref)}")  # fmt: skip
    for n in acc.clutch.notes:
        print(f"  note: {n}")


if __name__ == "__main__":
    main()
