"""Where a sweep row's time goes: the CPU-time shares of ``evaluate_batch``'s stages, in one run.

    python benchmarks/bench_sweep_profile.py [--designs 20000] [--seed 1] [--out PROF]

Profiles (cProfile on CPU time, ``time.process_time``: the machine is shared) one call of
the sweep's evaluator on random designs of 1–4 drums (bench_against's ranges), after a
warm-up call on the same designs so no import, compile or kernel load is in it, and
prints each stage's CPU seconds and share of the call, and the rows per CPU-second of the
profiled call (cProfile's overhead included: bench_against.py gives the unprofiled rate).
The stages do not overlap; "other" is the call less their sum (geometry, drag, mass, the
fields' checks). ``--out`` keeps the raw profile for ``python -m pstats``.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # a sibling script's designs
from bench_chords import fields  # bench_against.py's random designs

#: (stage, [(file suffix, function), ...]): cumulative times summed; the network's calls
#: (``YieldAt.__call__``) are split by caller: the peak (``fast_batch``'s ``clutch``) and
#: the continuous torque's chords (``continuous_torque``)
STAGES = (
    ("network build (network_from_regions, packing)",
     [("network/build.py", "network_from_regions"), ("network/torque.py", "network_yield_at")]),
    ("network peak solve + torque reading", [("peak", "__call__")]),
    ("network continuous-torque chords (3 solves + readings)", [("chords", "__call__")]),
    ("continuous torque's fixed points (thermal closed form)", [("torque.py", "fixed_point")]),
    ("thermal network", [("magnetics/thermal.py", "network")]),
    ("magnetic circuit (path, peak flux: the network's start)",
     [("circuit.py", "path_from_regions"), ("circuit.py", "solve_flux"),
      ("circuit.py", "linear_flux")]),
    ("torque response (torque_response)", [("dynamics.py", "torque_response")]),
    ("error bound (features, error_bound)",
     [("network_bound.py", "solution_features"), ("fast_batch.py", "_material_bounds")]),
    ("haptic metrics (metrics_batch, backdrive, mr_at_hand)",
     [("haptics/model.py", "metrics_batch"), ("hand.py", "backdrive_force"),
      ("at_hand.py", "mr_at_hand")]),
)  # fmt: skip


def shares(stats: pstats.Stats) -> tuple[float, dict[str, float]]:
    """(the call's CPU seconds, {stage: CPU seconds}) from a profile of one
    ``evaluate_batch``."""
    st = stats.stats  # type: ignore[attr-defined]
    total = next(v[3] for k, v in st.items() if k[2] == "evaluate_batch")
    out = {}
    for name, keys in STAGES:
        t = 0.0
        for where, fn in keys:
            for (path, _, func), (_, _, _, ct, callers) in st.items():
                if func != fn:
                    continue
                if where in ("peak", "chords"):
                    if not path.endswith("network/torque.py"):
                        continue
                    want = "continuous_torque" if where == "chords" else "clutch"
                    t += sum(v[3] for c, v in callers.items() if c[2] == want)
                elif path.endswith(where):
                    t += ct
        out[name] = t
    out["other"] = total - sum(out.values())
    return total, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=20_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=None, help="write the raw profile here")
    a = ap.parse_args()
    from mrclutch.pipeline import evaluate_batch

    f = fields(a.designs, a.seed)
    # warm-up on the same designs: imports, and every compiled kernel loaded (a small call
    # runs them as Python, magnetics.network.compiled.uncompiled, and loads none)
    evaluate_batch(f)
    prof = cProfile.Profile(time.process_time)
    prof.runcall(evaluate_batch, f)
    if a.out:
        prof.dump_stats(a.out)
    total, parts = shares(pstats.Stats(prof))
    print(f"evaluate_batch, {a.designs} designs: {total:.3f} CPU s profiled, "
          f"{a.designs / total:.0f} rows per CPU-second")  # fmt: skip
    for name, t in sorted(parts.items(), key=lambda kv: -kv[1]):
        print(f"  {name:<58} {t:7.3f} s  {100 * t / total:5.1f} %")


if __name__ == "__main__":
    main()
