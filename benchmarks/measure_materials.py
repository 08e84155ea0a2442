"""The reluctance network against the FEM for every fluid of the library (steel 1018 in
core, drums and shell, the representative steel), and for Hiperco 50 in the core and the
shell with MRF-132DG: the signed error network/FEM − 1 of the yield torque at 7 A (the knee of Fig. 2b, where the materials differ most) on
the first N random designs of the stored FEM reference's sample (benchmarks/data/
fem_reference.json, the designs docs/magnetics.md's random figures use), and the share
within ±5 % and ±10 % (docs/magnetics.md, "Per material").

    python benchmarks/measure_materials.py [--designs 50] [--json]

Each FEM solve costs 0.05–0.4 s (more on a loaded machine): 50 designs × 4 material sets
≈ 1–4 min; ``--only K`` runs the K-th set alone (to spread the sets over processes).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "fem_reference.json"
SETS = {
    "MRF-122EG / 1018": {"fluid": "mrf_122eg"},
    "MRF-132DG / 1018": {"fluid": "mrf_132dg"},
    "MRF-140CG / 1018": {"fluid": "mrf_140cg"},
    "MRF-132DG / Hiperco 50 core + shell": {"core": "hiperco_50", "shell": "hiperco_50"},
}
CURRENTS = (7.0,)


def main() -> None:
    from geometry.materials import MaterialChoice
    from geometry.params import DrumClutch
    from geometry.section import build_section
    from magnetics.torque import torque_curve
    from mrclutch.design import design_preset

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=50)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--only", type=int, default=None, help="run only the K-th material set")
    args = ap.parse_args()
    data = json.loads(DATA.read_text())
    base = vars(design_preset(data["base_preset"]).clutch)
    ints = {"n_drums", "coil_turns", "hub_holes"}
    designs = [DrumClutch(**{k: (int if k in ints else float)(r["design"].get(k, v))
                             for k, v in base.items()})
               for r in data["random"][: args.designs] if r["torque"] is not None]  # fmt: skip
    out: dict[str, dict[str, float]] = {}
    for k, (label, choice) in enumerate(SETS.items()):
        if args.only is not None and k != args.only:
            continue
        mats = MaterialChoice(**choice)
        err = []
        t0 = time.perf_counter()
        for c in designs:
            s = build_section(c, mats)
            net = torque_curve(s, CURRENTS, "network").yield_torque
            fem = torque_curve(s, CURRENTS, "fem").yield_torque
            err.append(net / fem - 1)
        e = np.array(err)
        a = np.abs(e)
        out[label] = {
            "designs": len(designs),
            "within_5pct": float(np.mean(a <= 0.05)),
            "within_10pct": float(np.mean(a <= 0.10)),
            "median_abs": float(np.median(a)),
            "worst": float(e.flat[np.argmax(a)]),
            "seconds": time.perf_counter() - t0,
        }
    if args.json:
        print(json.dumps(out, indent=1))
        return
    print(f"{'material set':38s} designs  ±5 %   ±10 %  median|e|  worst")
    for label, r in out.items():
        print(f"{label:38s} {r['designs']:5d}  {r['within_5pct']:5.1%}  {r['within_10pct']:5.1%}"
              f"  {r['median_abs']:7.2%}  {r['worst']:+.1%}   ({r['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
