"""Where a sweep row's time goes: the CPU-time shares of ``evaluate_batch``'s stages, in one run.

    python benchmarks/bench_sweep_profile.py [--designs 20000] [--seed 1] [--out PROF]
    python benchmarks/bench_sweep_profile.py --chunks 1000,4000,16000,20000,64000

Profiles (cProfile on CPU time, ``time.process_time``: the machine is shared) one call of
the sweep's evaluator on random designs of 1–4 drums (bench_against's ranges), after a
warm-up call on the same designs so no import, compile or kernel load is in it, and
prints each stage's CPU seconds and share of the call, and the rows per CPU-second of the
profiled call (cProfile's overhead included: bench_against.py gives the unprofiled rate).
The stages do not overlap; "other" is the call less their sum (geometry, drag, mass, the
fields' checks). ``--out`` keeps the raw profile for ``python -m pstats``. It also prints
the compiled kernels' own time (the network's Newton, ``_solve_rows``, and its torque
reading, ``_read_rows``: no Python inside, so cProfile does not inflate them) and the rate
the call would reach if every other stage took no time at all: the ceiling of any cut
that leaves the kernels as they are.

``--chunks`` (no profile) times, unprofiled, the same designs (``--designs``, default
64000 there) passed to ``evaluate_batch`` in chunks of each size (what the sweep passes
per call: ``SweepSpec.chunk_size``, default 20000), the sizes interleaved over three
rounds, CPU time: rows per CPU-second of each (median) and whether its rows equal, bit
for bit, those of the first size's (a row's value must not depend on its batch).
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
#: the continuous rating's solves (``slope_rating``: two a row, a third on moved rows)
STAGES = (
    ("network build (network_from_regions, packing)",
     [("network/build.py", "network_from_regions"), ("network/torque.py", "network_yield_at")]),
    ("network peak solve + torque reading", [("peak", "__call__")]),
    ("network continuous-rating solves (2 + moved rows', readings)", [("chords", "__call__")]),
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
                    want = "slope_rating" if where == "chords" else "clutch"
                    t += sum(v[3] for c, v in callers.items() if c[2] == want)
                elif path.endswith(where):
                    t += ct
        out[name] = t
    out["other"] = total - sum(out.values())
    return total, out


#: The compiled kernels (file suffix, function) whose own time ``kernels`` sums.
KERNELS = (("network/kernels.py", "_solve_rows"), ("network/torque.py", "_read_rows"))


def kernels(stats: pstats.Stats) -> float:
    """CPU seconds spent inside the compiled kernels (``KERNELS``, their own time)."""
    st = stats.stats  # type: ignore[attr-defined]
    return sum(v[2] for (path, _, func), v in st.items()
               if any(path.endswith(f) and func == fn for f, fn in KERNELS))  # fmt: skip


def chunk_rates(n: int, seed: int, sizes: list[int], rounds: int = 3) -> None:
    """``--chunks``: rows per CPU-second of ``evaluate_batch`` on the same ``n`` designs
    in chunks of each size (median of ``rounds`` interleaved), and their rows' identity."""
    import numpy as np

    from mrclutch.pipeline import evaluate_batch

    f = fields(n, seed)
    evaluate_batch({k: v[:20_000] for k, v in f.items()})  # warm-up: kernels loaded
    cpu: dict[int, list[float]] = {c: [] for c in sizes}
    rows: dict[int, bytes] = {}
    for r in range(rounds):
        for c in sizes:
            t = time.process_time()
            outs = [evaluate_batch({k: v[i : i + c] for k, v in f.items()}) for i in range(0, n, c)]
            cpu[c].append(time.process_time() - t)
            if r == 0:
                rows[c] = b"".join(np.concatenate([o[k] for o in outs]).tobytes() for k in outs[0])
    for c in sizes:
        med = sorted(cpu[c])[len(cpu[c]) // 2]
        print(f"chunk {c:>7}: {n / med:7.0f} rows per CPU-second (median of {rounds}), rows "
              f"{'bit-identical to' if rows[c] == rows[sizes[0]] else 'DIFFER from'} "
              f"chunk {sizes[0]}'s")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=None, help="20000 (--chunks: 64000)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=None, help="write the raw profile here")
    ap.add_argument("--chunks", default=None, help="comma-separated chunk sizes: time those")
    a = ap.parse_args()
    if a.chunks:
        chunk_rates(a.designs or 64_000, a.seed, [int(c) for c in a.chunks.split(",")])
        return
    a.designs = a.designs or 20_000
    from mrclutch.pipeline import evaluate_batch

    f = fields(a.designs, a.seed)
    # warm-up on the same designs: imports, and every compiled kernel loaded (a small call
    # runs them as Python, magnetics.network.compiled.uncompiled, and loads none)
    evaluate_batch(f)
    prof = cProfile.Profile(time.process_time)
    prof.runcall(evaluate_batch, f)
    if a.out:
        prof.dump_stats(a.out)
    stats = pstats.Stats(prof)
    total, parts = shares(stats)
    print(f"evaluate_batch, {a.designs} designs: {total:.3f} CPU s profiled, "
          f"{a.designs / total:.0f} rows per CPU-second")  # fmt: skip
    k = kernels(stats)
    print(f"compiled kernels alone (_solve_rows, _read_rows): {k:.3f} CPU s; with every other "
          f"stage free: {a.designs / k:.0f} rows per CPU-second at most")  # fmt: skip
    for name, t in sorted(parts.items(), key=lambda kv: -kv[1]):
        print(f"  {name:<58} {t:7.3f} s  {100 * t / total:5.1f} %")


if __name__ == "__main__":
    main()
