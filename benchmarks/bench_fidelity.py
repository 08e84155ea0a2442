"""Speed against accuracy, to compare releases: every method's time ratio to the fastest of
its quantity and its error; then the accuracy-target acceptance — `evaluate(accuracy=0.01)`
against the reference fidelity on the paper preset (time ratio, errors), all in one run.

    python benchmarks/bench_fidelity.py [--accuracy 0.01] [--repeats 3]
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


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--accuracy", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    d = design_preset("paper")
    evaluate(d, "reference")  # warm the imports (build123d, skfem) out of the timings

    rows = measure(d, repeats=a.repeats)
    qs = {r.quantity for r in rows}
    fastest = {q: min(r.time_s for r in rows if r.quantity == q) for q in qs}
    print(f"{'quantity':<10}{'method':<20}{'setting':<20}{'t/fastest':>10}{'error':>10}")
    for r in rows:
        print(f"{r.quantity:<10}{r.method:<20}{r.setting:<20}"
              f"{r.time_s / fastest[r.quantity]:>10.3g}{r.error_rel:>10.2e}")  # fmt: skip

    t_ref, ref = _median_time(lambda: evaluate(d, "reference"), a.repeats)
    t_acc, acc = _median_time(lambda: evaluate(d, accuracy=a.accuracy), a.repeats)
    t_fast, fast = _median_time(lambda: evaluate(d, "fast"), a.repeats)
    print(f"\nevaluate on the paper preset (median of {a.repeats}):")
    for name, t, ev in (("fast", t_fast, fast), (f"accuracy={a.accuracy:g}", t_acc, acc)):
        e_i = abs(ev.clutch.rotor_inertia / ref.clutch.rotor_inertia - 1)
        e_t = abs(ev.clutch.max_torque / ref.clutch.max_torque - 1)
        e_b = abs(ev.haptic["bandwidth_hz"] / ref.haptic["bandwidth_hz"] - 1)
        print(f"  {name:<16} {t * 1e3:8.1f} ms   {t_ref / t:7.1f}× faster than reference "
              f"({t_ref:.2f} s)   errors: inertia {e_i:.1e}, torque {e_t:.1e}, "
              f"bandwidth {e_b:.1e}")  # fmt: skip
    for n in acc.clutch.notes:
        print(f"  note: {n}")


if __name__ == "__main__":
    main()
