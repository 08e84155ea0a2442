"""Store the reluctance network's torques as the compiled kernel's reference (issue 31).

    python benchmarks/make_network_reference.py [--check]

Made from commit 76ddb7b (the NumPy Newton, before the numba kernel replaced it):
``network_torque_batch`` on 10⁴ random designs of ``bench_network.designs`` (seed 31)
at 2, 4 and 7 A, mid-line, written to tests/magnetics/data/network_reference.npz
(float64, compressed). tests/magnetics/test_network_kernel.py checks that today's network
gives the same torques within 1e-9 relative. To regenerate from the pinned code:
``git worktree add /tmp/ref 76ddb7b && PYTHONPATH=/tmp/ref python
benchmarks/make_network_reference.py``. ``--check`` compares instead of writing.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "tests" / "magnetics" / "data" / "network_reference.npz"
SEED, DESIGNS, CURRENTS = 31, 10_000, (2.0, 4.0, 7.0)


def fields() -> dict[str, np.ndarray]:
    sys.path.insert(0, str(HERE))
    try:
        from bench_network import designs
    finally:
        sys.path.remove(str(HERE))
    return designs(DESIGNS, SEED)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args()
    from magnetics.torque import network_torque_batch

    t = network_torque_batch(fields(), CURRENTS)
    if a.check:
        ref = np.load(DATA)["torque"]
        rel = np.abs(t / ref - 1)
        print(f"max relative difference: {np.nanmax(rel):.2e}")
        return
    np.savez_compressed(DATA, torque=t, currents=np.array(CURRENTS), seed=SEED)
    print(f"{DATA}: {t.shape}, {np.isnan(t).sum()} NaN, {DATA.stat().st_size} bytes")


if __name__ == "__main__":
    main()
