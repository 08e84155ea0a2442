"""Cost of the robust verdicts (mrclutch.robust, docs/verdicts.md), ratios in one run. Run
from the repository root: ``python -m benchmarks.bench_robust [--designs N] [--json]``.

* one design: ``evaluate(paper, "fast")`` against ``evaluate`` + ``robust_verdicts`` (the
  nominal evaluation, then the box over the default ranges: four more fast-path
  evaluations at the geometry corners, the searches, the thresholds), median of 3;
* a sweep: ``BatchEvaluator`` (the default columns) against ``RobustBatchEvaluator`` with
  the three robust columns (``sweep --with max_stable_K_worst_N_per_m --with
  max_passive_K_worst_N_per_m --with bandwidth_worst_hz``) on N random designs (seed 0,
  the ranges of examples/random_sweep.toml), median of 3 for the default, 1 for the robust.

``--against-search`` instead compares the sweep's three worst-case columns with what they
were before issue 40 (the worst largest stable K by ``box_search`` over (m1, b1, τ), 3
points, six grids; the worst bandwidth by ``box_search`` over (m1, b1, τ, K), 3 points,
five grids) on the same hand boxes: N designs of the paper preset over its ranges and N
random boxes (tests/mrclutch/test_robust.py's ``_random_boxes``, seed 29), printing the
largest relative change of each column and the CPU time of each.

Set OPENBLAS_NUM_THREADS=1 on a shared machine."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from mrclutch.design import design_preset
from mrclutch.hot_range import resolved_ranges
from mrclutch.pipeline import BatchEvaluator, evaluate
from mrclutch.robust import ROBUST_COLUMNS, RobustBatchEvaluator, robust_verdicts

sys.path.insert(0, str(Path(__file__).resolve().parent))  # a sibling script's timer
from bench_zwidth import median_time


def fields(n: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(0)
    return {
        "gap": rng.uniform(0.2e-3, 1.0e-3, n),
        "drum_thickness": rng.uniform(0.1e-3, 0.5e-3, n),
        "n_drums": rng.integers(1, 5, n).astype(float),
        "drum_inner_diameter": rng.uniform(8e-3, 16e-3, n),
        "zone_length": rng.uniform(4e-3, 8e-3, n),
    }


def _searched_worst(box) -> dict[str, np.ndarray]:  # type: ignore[no-untyped-def]
    """The worst-case columns as the searches gave them before issue 40."""
    from mrclutch.haptics.model import bandwidth, max_passive_stiffness
    from mrclutch.robust_search import box_search, stable_stiffness_batch

    (_, mlo, mhi), (_, blo, bhi), (_, tlo, thi), (_, klo, khi) = box.m1, box.b1, box.delay, box.K
    s, _ = box_search(
        lambda x: stable_stiffness_batch(box.params(x[..., 0], x[..., 1], x[..., 2])),
        np.stack([mlo, blo, tlo], 1), np.stack([mhi, bhi, thi], 1), sense=-1, points=3, zooms=5,
    )  # fmt: skip
    b, _ = box_search(
        lambda x: bandwidth(box.params(x[..., 0], x[..., 1], x[..., 2]), x[..., 3]),
        np.stack([mlo, blo, tlo, klo], 1), np.stack([mhi, bhi, thi, khi], 1), sense=-1,
        points=3, zooms=4,
    )  # fmt: skip
    p = max_passive_stiffness(box.params(mhi, blo, thi))
    return {"max_stable_K_worst": s, "max_passive_K_worst": p, "bandwidth_worst": b}


def against_search(n: int) -> None:
    """Print the largest relative change of each worst-case column against the searches."""
    import time

    from mrclutch.hand_box import hand_box_batch
    from mrclutch.robust_columns import robust_limits

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "mrclutch"))
    from test_robust import _random_boxes

    d = design_preset("paper")
    f = fields(n)
    ranges = resolved_ranges(d)
    boxes = {
        f"{n} designs of the paper preset over its ranges": hand_box_batch(f, d, ranges),
        f"{n} random boxes (_random_boxes, seed 29)": _random_boxes(np.random.default_rng(29), n),
    }
    for name, box in boxes.items():
        c = time.process_time()
        new = robust_limits(box, cases=("worst",))
        t_new = time.process_time() - c
        c = time.process_time()
        old = _searched_worst(box)
        t_old = time.process_time() - c
        print(f"{name}: now {t_new:.2f} s CPU, the searches {t_old:.2f} s CPU")
        for q, v in old.items():
            r = new[q] / v - 1
            print(f"  {q}: now/before - 1 from {np.nanmin(r):+.2e} to {np.nanmax(r):+.2e}; "
                  f"largest |change| {np.nanmax(np.abs(r)):.2e}")  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", type=int, default=300, help="sweep designs (default 300)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--against-search", action="store_true",
                    help="the worst-case columns against the searches before issue 40")  # fmt: skip
    args = ap.parse_args(argv)
    if args.against_search:
        against_search(args.designs)
        return
    d = design_preset("paper")
    evaluate(d)  # warm the caches (numba kernel, tables) before timing
    one = median_time(lambda: evaluate(d), 3)
    both = median_time(lambda: robust_verdicts(evaluate(d)), 3)
    f = fields(args.designs)
    plain = BatchEvaluator(d)
    robust = RobustBatchEvaluator(d, ROBUST_COLUMNS)
    plain(f)
    t_plain = median_time(lambda: plain(f), 3)
    t_robust = median_time(lambda: robust(f), 1)
    res = {
        "one_design_nominal_s": one,
        "one_design_robust_s": both,
        "one_design_ratio": both / one,
        "sweep_designs": args.designs,
        "sweep_default_s": t_plain,
        "sweep_robust_s": t_robust,
        "sweep_ratio": t_robust / t_plain,
        "sweep_robust_ms_per_design": 1e3 * t_robust / args.designs,
    }
    if args.json:
        print(json.dumps(res, indent=2))
        return
    print(f"one design (paper, fast): nominal {one:.3f} s, robust {both:.3f} s "
          f"(median of 3): ratio {both / one:.1f}x")  # fmt: skip
    print(f"sweep of {args.designs} designs: default columns {t_plain:.3f} s (median of 3), "
          f"with the robust columns {t_robust:.3f} s: ratio {t_robust / t_plain:.1f}x "
          f"({res['sweep_robust_ms_per_design']:.1f} ms a design)")  # fmt: skip


if __name__ == "__main__":
    main()
