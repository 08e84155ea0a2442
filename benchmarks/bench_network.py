"""Speed of the reluctance network against the single loop: yield torque of 10⁵ random
designs (the sweep's ranges, 1–6 drums) at 3 currents, designs per second on one core, and
the ratios, measured in one run (alternating rounds; the best of each). The loop is timed
two ways: solved at each current (``max_torque_batch``, its fastest path, the issue's
"~6·10⁴/s") and through its torque table (``torque_grid_batch``, what sweeps used).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_network.py [--designs 100000] [--rounds 3]
        [--skip-table] [--breakdown] [--compile]

``--skip-table`` leaves the torque table out (it takes 30× the others' time). The network's
compiled kernels are loaded (or compiled, once per machine) before the clock starts.
``--breakdown``: instead, per drum count (5000 designs each, 3 currents), µs per design of
the network's three stages — building the ladder from the region table (NumPy), the
Newton solve (the compiled kernel) and the torque reading (compiled) — against the loop's
whole time, and the loop's share that building and reading alone take (where the network
stands if its solve cost nothing).
``--compile``: instead, a machine's first compile of the solver (``compiled._entry``) in a
fresh process with an empty numba cache, ``--rounds`` times: each kernel's compile (CPU s
since the kernel before it ended, the first's with the imports and numba's start; "beside":
loaded from the second process's cache), this
process's CPU (the critical path when the second process keeps pace), the second process's,
the wall time and the LLVM level it compiled at (``compiled.opt_level``: ``NUMBA_OPT`` if
set, else the project's).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def designs(n: int, seed: int = 1) -> dict[str, np.ndarray]:
    from mrclutch.design import design_preset

    base = vars(design_preset("paper").clutch)
    rng = np.random.default_rng(seed)
    f = {k: np.full(n, float(v)) for k, v in base.items()}
    f["n_drums"] = rng.integers(1, 7, n).astype(float)
    f["gap"] = rng.uniform(0.2e-3, 1.0e-3, n)
    f["zone_length"] = rng.uniform(3e-3, 9e-3, n)
    f["drum_inner_diameter"] = rng.uniform(6e-3, 18e-3, n)
    f["drum_thickness"] = rng.uniform(0.1e-3, 0.6e-3, n)
    return f


def breakdown(n: int = 5000, rounds: int = 3) -> None:
    """Print the network's stage times per drum count against the loop's (module doc)."""
    from geometry.params import broadcast_fields, valid
    from geometry.regions import per_topology
    from magnetics.network.build import network_from_regions
    from magnetics.network.solve import solve_network
    from magnetics.network.torque import network_film_torque, network_torque_batch
    from magnetics.torque import max_torque_batch

    cur = np.array([[2.0, 4.0, 7.0]])
    network_torque_batch(designs(10, 2), cur[0])  # the kernels loaded
    print("drums  build_us  solve_us  read_us  network_us  loop_us  (build+read)/loop")
    shares = []
    for nd in range(1, 7):
        f = designs(n)
        f["n_drums"][:] = nd
        p = broadcast_fields(f)
        best = {k: np.inf for k in ("build", "solve", "read", "loop")}
        for _ in range(rounds):

            def one(rg, rows, best=best):  # type: ignore[no-untyped-def]
                t0 = time.perf_counter()
                net = network_from_regions(rg)
                t1 = time.perf_counter()
                x = solve_network(net, net.turns[:, None] * cur)
                t2 = time.perf_counter()
                t = network_film_torque(net, x)
                t3 = time.perf_counter()
                for k, v in (("build", t1 - t0), ("solve", t2 - t1), ("read", t3 - t2)):
                    best[k] = min(best[k], v)
                return {"t": t.sum(-1)}

            per_topology(p, valid(p), one)
            t0 = time.perf_counter()
            for c in cur[0]:
                max_torque_batch(f, c)
            best["loop"] = min(best["loop"], time.perf_counter() - t0)
        us = {k: 1e6 * v / n for k, v in best.items()}
        net = us["build"] + us["solve"] + us["read"]
        shares.append((us["build"] + us["read"]) / us["loop"])
        print(f"{nd:5d}  {us['build']:8.2f}  {us['solve']:8.2f}  {us['read']:7.2f}  "
              f"{net:10.2f}  {us['loop']:7.2f}  {shares[-1]:.2f}")  # fmt: skip
    print(f"build + read over the loop: min {min(shares):.2f} max {max(shares):.2f}")


#: A first compile of the solver with each kernel's compile timed (CPU), ``--compile``.
COMPILE = """
import resource, time
c0, w0 = time.process_time(), time.perf_counter()
from magnetics.network import compiled
compiled.numba_module()  # numba imported as the project imports it: its cache and LLVM level
from numba.core.event import Listener, install_listener
ends = []
class Ends(Listener):
    def on_start(self, ev): pass
    def on_end(self, ev):
        name = compiled._name(ev.data["dispatcher"])
        if name in compiled._SIGNATURES:
            ends.append((name, time.process_time() - c0))
with install_listener("numba:compile", Ends()):
    compiled._entry("_solve_rows", 10**9)
child = resource.getrusage(resource.RUSAGE_CHILDREN)
last, parts = 0.0, []
for name, t in ends:
    parts.append(f"{name} {t - last:.2f}")
    last = t
parts += [f"{n} beside" for n in compiled._BESIDE if n not in dict(ends)]
print("  ".join(parts))
print(f"this process {time.process_time() - c0:.2f} s CPU, the second "
      f"{child.ru_utime + child.ru_stime:.2f} s CPU, wall {time.perf_counter() - w0:.2f} s "
      f"(LLVM level {compiled.opt_level()})")
"""


def first_compile(rounds: int) -> None:
    """Print a first compile of the solver, ``rounds`` times (module doc, ``--compile``)."""
    for _ in range(rounds):
        with tempfile.TemporaryDirectory(prefix="mrclutch-compile-") as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            run = subprocess.run([sys.executable, "-c", COMPILE], env=env, check=True,
                                 capture_output=True, text=True)  # fmt: skip
            print(run.stdout.strip())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--designs", type=int, default=100_000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--skip-table", action="store_true", help="leave the torque table out")
    ap.add_argument("--breakdown", action="store_true",
                    help="per drum count: the network's stages against the loop")  # fmt: skip
    ap.add_argument("--compile", action="store_true",
                    help="a first compile of the solver, each kernel timed")  # fmt: skip
    a = ap.parse_args()
    if a.compile:
        first_compile(a.rounds)
        return
    if a.breakdown:
        breakdown()
        return
    from magnetics.torque import max_torque_batch, network_torque_batch, torque_grid_batch

    f = designs(a.designs)
    cur = [2.0, 4.0, 7.0]
    network_torque_batch(designs(10, 2), cur)  # the kernels loaded (compiled once a machine)

    def loop_solved(fields, currents):  # type: ignore[no-untyped-def]
        return np.stack([max_torque_batch(fields, c) for c in currents], axis=1)

    runs = (("network", network_torque_batch), ("loop, solved per current", loop_solved),
            ("loop, torque table", torque_grid_batch))[: 2 if a.skip_table else 3]  # fmt: skip
    best = {name: np.inf for name, _ in runs}
    for _ in range(a.rounds):
        for name, fn in runs:
            t0 = time.perf_counter()
            out = fn(f, cur)
            best[name] = min(best[name], time.perf_counter() - t0)
            assert np.isfinite(out).mean() > 0.9
    for name, t in best.items():
        print(f"{name}: {t:.2f} s, {a.designs / t:.0f} designs/s (× 3 currents)")
    for name, _ in runs[1:]:
        print(f"ratio network/{name} time: {best['network'] / best[name]:.2f}")


if __name__ == "__main__":
    main()
