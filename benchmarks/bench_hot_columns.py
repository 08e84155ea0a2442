"""The sweep's hot columns (issue 41 item 3: the torque and b1 after the hot peak hold and
the duty hold): design by design (``mrclutch.duty.hot_batch``, the reference) against the
whole batch marched at once (``mrclutch.hot_rows.hot_batch``, what the sweep runs), on the
same rows in one run: rows/s of each, their ratio, and the largest relative difference of
the figures. Both are warmed first (the network's compiled kernels), then timed in
alternating rounds.

``--hot-corner``: the cost of a ``fluid_temperature_C = "duty"`` range taken per row (each
design's own duty hold, ``mrclutch.hot_rows.duty_hot_ends``) in the hand box a robust
sweep or the optimiser's worst case builds (``hand_box_batch``), against the same box with
the base design's range typed (what every row took before): rows/s of each, their ratio.

    python benchmarks/bench_hot_columns.py                # 200 rows, 2 rounds
    python benchmarks/bench_hot_columns.py --rows 400 --rounds 2
    python benchmarks/bench_hot_columns.py --hot-corner
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mrclutch import duty, hot_rows
from mrclutch.at_hand import mr_at_hand
from mrclutch.design import design_preset
from mrclutch.fast_batch import evaluate_batch
from mrclutch.hot_range import resolved_ranges


def batch(rows: int, seed: int = 0):  # type: ignore[no-untyped-def]
    """A varied batch around the paper preset with the docs' duty (0.2 N·m for 60 s): gap,
    drum count, zone length and coil turns drawn; the evaluated rows and the pair at the
    hand of the valid ones."""
    base = replace(design_preset("paper"), duty=duty.Duty(torque=0.2, time=60.0))
    rng = np.random.default_rng(seed)
    fields = {"gap": rng.uniform(0.3e-3, 1.0e-3, rows), "n_drums": rng.integers(1, 6, rows),
              "zone_length": rng.uniform(4e-3, 8e-3, rows),
              "coil_turns": rng.integers(100, 147, rows)}  # fmt: skip
    r = evaluate_batch(fields, base)
    ok = r["valid"] > 0
    mr = mr_at_hand(base, r["rotor_inertia_kg_m2"][ok] + r["fluid_inertia_kg_m2"][ok],
                    r["drag_damping_N_m_s"][ok], r["max_torque_N_m"][ok],
                    r["clutch_mass_kg"][ok], r["torque_delay_s"][ok])  # fmt: skip
    return fields, base, r, mr


def hot_corner(rows: int, rounds: int) -> dict[str, object]:
    """hand_box_batch rows/s with the base's range typed and with "duty" per row."""
    from mrclutch.hand_box import hand_box_batch

    fields, base, r, _ = batch(rows)
    # the base's hot end resolved
    unc = replace(resolved_ranges(base), fluid_temperature_from="duty")
    typed = replace(unc, fluid_temperature_from="range")
    small = {k: v[:4] for k, v in fields.items()}
    hand_box_batch(small, base, unc)
    hand_box_batch(small, base, typed)
    t_typed, t_duty = [], []
    for _ in range(rounds):
        t = time.perf_counter()
        hand_box_batch(fields, base, typed, nominal=r)
        t_typed.append(time.perf_counter() - t)
        t = time.perf_counter()
        hand_box_batch(fields, base, unc, nominal=r)
        t_duty.append(time.perf_counter() - t)
    ratio = [d / t for d, t in zip(t_duty, t_typed, strict=True)]
    return {"rows": rows, "rounds": rounds,
            "typed_range_rows_per_s": rows / float(np.median(t_typed)),
            "duty_per_row_rows_per_s": rows / float(np.median(t_duty)),
            "cost_factor_median": float(np.median(ratio)),
            "cost_factor_rounds": [round(x, 1) for x in ratio]}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--hot-corner", action="store_true", help=hot_corner.__doc__)
    args = ap.parse_args()
    if args.hot_corner:
        print(json.dumps(hot_corner(args.rows, args.rounds), indent=2))
        return
    fields, base, r, mr = batch(args.rows)
    warm = {k: v[:4] for k, v in fields.items()}
    rw = {k: v[:4] for k, v in r.items()}
    n_ok = int(np.sum(r["valid"][:4] > 0))
    mw = mr if not mr.shape else type(mr)(**{f: np.asarray(getattr(mr, f))[:n_ok]
                                             if np.ndim(getattr(mr, f)) else getattr(mr, f)
                                             for f in mr.__dataclass_fields__})  # fmt: skip
    duty.hot_batch(warm, base, rw, mw)
    hot_rows.hot_batch(warm, base, rw, mw)
    valid = int(np.sum(r["valid"] > 0))
    before, after, ratios = [], [], []
    for _ in range(args.rounds):
        t = time.perf_counter()
        ref = duty.hot_batch(fields, base, r, mr)
        t_ref = time.perf_counter() - t
        t = time.perf_counter()
        new = hot_rows.hot_batch(fields, base, r, mr)
        t_new = time.perf_counter() - t
        before.append(args.rows / t_ref)
        after.append(args.rows / t_new)
        ratios.append(t_ref / t_new)
    diff = max(float(np.nanmax(np.abs(new[k] / ref[k] - 1))) for k in duty.HOT_COLUMNS)
    print(json.dumps({"rows": args.rows, "valid_rows": valid, "rounds": args.rounds,
                      "per_design_rows_per_s": float(np.median(before)),
                      "batched_rows_per_s": float(np.median(after)),
                      "speedup_median": float(np.median(ratios)),
                      "speedup_rounds": [round(x, 1) for x in ratios],
                      "largest_relative_difference": diff}, indent=2))  # fmt: skip


if __name__ == "__main__":
    main()
