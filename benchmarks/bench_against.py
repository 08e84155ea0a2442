"""The fast sweep path against an earlier revision, measured in one run (ratios, not times).

    python benchmarks/bench_against.py --base c8c990d [--designs 100000] [--rounds 5]

Checks the base revision out into a temporary git worktree and times, alternately in fresh
subprocesses of each tree, the sweep's evaluator (``evaluate_batch`` on random designs of
1–4 drums, the spec of examples/random_sweep.toml's ranges) and ``mrclutch --help``.
Prints the median time of each and the ratio current/base (< 1: faster now). Alternating
rounds keep the ratio honest on a shared, noisy machine. Each run of the sweep's evaluator
also hashes every column of every row it computed (SHA-256, after its timing): the line
``rows: ... bit-identical to base`` compares the two trees' rows, and a tree whose rounds
disagree with each other is named; where they differ, each column's largest relative
difference is printed, alone and over the row's ``torque_error_bound``. ``--base`` may
also be a folder where a tree is already checked out (used as it is).

``--robust-designs N`` (default 300; 0: skip) also times, in each tree, the sweep's robust
columns (``RobustBatchEvaluator`` with the three worst-case columns, what ``sweep --with
max_stable_K_worst_N_per_m …`` runs) against the default columns (``BatchEvaluator``) on
the same N designs (bench_robust's), and prints robust/default of each tree (issue 40's
goal: ≤ 10×), CPU time (the machine is shared): medians of three interleaved rounds.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

SWEEP = r"""
import sys, time
import numpy as np
from mrclutch.pipeline import evaluate_batch
rng = np.random.default_rng(1)
S = int(sys.argv[1])
f = {"n_drums": rng.integers(1, 5, S), "gap": rng.uniform(0.2e-3, 1.0e-3, S),
     "drum_thickness": rng.uniform(0.1e-3, 0.6e-3, S),
     "zone_length": rng.uniform(3e-3, 9e-3, S),
     "drum_inner_diameter": rng.uniform(6e-3, 18e-3, S)}
chunk = 20000  # the sweep's chunk size
# warm-up on a whole chunk: imports, caches, and the compiled kernels loaded (a small call
# runs them as Python, magnetics.network.compiled.uncompiled; a fresh worktree compiles)
evaluate_batch({k: v[:chunk] for k, v in f.items()})
t, c = time.perf_counter(), time.process_time()
outs = [evaluate_batch({k: v[i:i + chunk] for k, v in f.items()}) for i in range(0, S, chunk)]
t, c = time.perf_counter() - t, time.process_time() - c
import hashlib  # every column of every row, in column order, after the timing
h = hashlib.sha256()
for out in outs:
    for k, v in out.items():
        h.update(k.encode())
        h.update(np.ascontiguousarray(v, dtype=float).tobytes())
print(f"rows {S} columns {len(outs[0])} sha256 {h.hexdigest()}")
if len(sys.argv) > 2:  # the rows themselves, for the per-column comparison
    np.savez(sys.argv[2], **{k: np.concatenate([o[k] for o in outs]) for k in outs[0]})
print(t, c)
"""

ROBUST = r"""
import sys, time
sys.path.insert(0, "benchmarks")
from bench_robust import fields
from mrclutch.design import design_preset
from mrclutch.pipeline import BatchEvaluator
from mrclutch.robust import ROBUST_COLUMNS, RobustBatchEvaluator
d = design_preset("paper")
f = fields(int(sys.argv[1]))
plain, robust = BatchEvaluator(d), RobustBatchEvaluator(d, ROBUST_COLUMNS)
plain(f)  # warm-up (imports, caches)
def cpu(fn):
    c = time.process_time()
    fn(f)
    return time.process_time() - c
# three rounds, each the default (median of 3) then the robust once: medians of each (the
# two interleaved, so a change of load on a shared machine moves both)
rounds = [(sorted(cpu(plain) for _ in range(3))[1], cpu(robust)) for _ in range(3)]
print(*(sorted(x)[1] for x in zip(*rounds)))
"""

HELP = r"""
import subprocess, sys, time
t = time.perf_counter()
subprocess.run([sys.executable, "-m", "mrclutch", "--help"], check=True, capture_output=True)
print(time.perf_counter() - t)
"""


def _time(tree: Path, code: str, *args: str, rows: list[str] | None = None) -> list[float]:
    """The script's last line's figures (wall[, CPU] s); ``rows`` gets its row digest line
    (the sweep's), if given."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run(
        [sys.executable, "-c", code, *args], cwd=tree, env=env, check=True,
        capture_output=True, text=True,
    )  # fmt: skip
    lines = out.stdout.strip().splitlines()
    if rows is not None:
        rows.append(next(x for x in lines if x.startswith("rows ")))
    return [float(v) for v in lines[-1].split()]


@contextlib.contextmanager
def base_tree(rev: str) -> Iterator[Path]:
    """The revision ``rev`` checked out in a temporary git worktree (removed afterwards), or
    ``rev`` itself where it names a folder (a tree already checked out, used as it is)."""
    if Path(rev).is_dir():
        yield Path(rev).resolve()
        return
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        subprocess.run(["git", "worktree", "add", "--detach", str(base), rev], cwd=ROOT,
                       check=True, capture_output=True)  # fmt: skip
        try:
            yield base
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT,
                           check=False, capture_output=True)  # fmt: skip


def _rows_line(digests: dict[str, list[str]]) -> str:
    """Whether the two trees' sweeps gave the same rows, bit for bit (their digests)."""
    for label, seen in digests.items():
        if len(set(seen)) > 1:
            return f"rows: the {label} tree's rounds differ from each other: {sorted(set(seen))}"
    now, base = digests["now"][0], digests["base"][0]
    verdict = "bit-identical to base" if now == base else f"DIFFER from base ({base})"
    return f"rows: {now} — {verdict}"


def compare_rows(now: Path, base: Path) -> None:
    """Where the two trees' rows differ: per column, the largest relative difference
    |now/base − 1| over the rows, and the largest of it over the row's own
    ``torque_error_bound`` (the network's error bound, the scale a row may move within)."""
    a, b = np.load(now), np.load(base)
    bound = b["torque_error_bound"]
    print("rows differ; per column: max |now/base - 1|, max of it / the row's torque_error_bound")
    for k in b.files:
        x, y = a[k], b[k]
        same = (x == y) | (np.isnan(x) & np.isnan(y))
        if same.all():
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(same, 0.0, np.abs(x / y - 1))
        print(
            f"  {k:<28} {np.nanmax(rel):.2e} ({int((~same).sum())} rows)   "
            f"{np.nanmax(rel / bound):.2e} of the bound"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--base", required=True, help="git revision (or a tree's folder) to compare with"
    )
    ap.add_argument("--designs", type=int, default=100_000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--robust-designs", type=int, default=300)
    a = ap.parse_args()
    with base_tree(a.base) as base, tempfile.TemporaryDirectory() as tmp:
        for name, code, args in (
            (f"fast sweep path, {a.designs} designs", SWEEP, (str(a.designs),)),
            ("mrclutch --help", HELP, ()),
        ):
            now, then = [], []
            digests: dict[str, list[str]] = {"now": [], "base": []}
            keep = {t: Path(tmp) / f"{t}.npz" for t in ("now", "base")}
            for r in range(a.rounds):
                sweep = code is SWEEP
                save = {t: (str(keep[t]),) if sweep and r == 0 else () for t in keep}
                then.append(_time(base, code, *args, *save["base"],
                                  rows=digests["base"] if sweep else None))  # fmt: skip
                now.append(_time(ROOT, code, *args, *save["now"],
                                 rows=digests["now"] if sweep else None))  # fmt: skip
            mn, mb = (statistics.median(t[0] for t in x) for x in (now, then))
            print(f"{name:<38} now {mn:8.3f} s   base {mb:8.3f} s   ratio {mn / mb:5.2f}")
            if code is SWEEP:  # one core's rate: rows per second of the sweep's evaluator
                cn, cb = (statistics.median(t[1] for t in x) for x in (now, then))
                print(
                    f"{'':<38} rows/s now {a.designs / mn:.0f}, base {a.designs / mb:.0f}; "
                    f"per CPU second now {a.designs / cn:.0f}, base {a.designs / cb:.0f}"
                )
                print(_rows_line(digests))
                if digests["now"][0] != digests["base"][0]:
                    compare_rows(keep["now"], keep["base"])
        if a.robust_designs > 0:  # the robust columns against the default, in each tree
            ratio = {}
            for tree, label in ((ROOT, "now"), (base, "base")):
                t_plain, t_robust = _time(tree, ROBUST, str(a.robust_designs))
                ratio[label] = t_robust / t_plain
                print(
                    f"robust columns, {a.robust_designs} designs ({label}): default "
                    f"{t_plain:.3f} s, robust {t_robust:.3f} s CPU: ratio {ratio[label]:.1f}x"
                )
            print(
                f"robust/default now {ratio['now']:.1f}x, base {ratio['base']:.1f}x (goal <= 10x)"
            )


if __name__ == "__main__":
    main()
