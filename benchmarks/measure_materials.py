"""The reluctance network against the FEM for every fluid of the library (steel 1018 in
core, drums and shell, the representative steel), and for Hiperco 50 in the core and the
shell with MRF-132DG: the signed error network/FEM − 1 of the yield torque at 7 A (the
knee of Fig. 2b, where the materials differ most) on the first 50 random designs of the
stored FEM reference's sample (benchmarks/data/fem_reference.json, the designs of
docs/magnetics.md's random figures), and the share within ±5 % and ±10 % (docs/magnetics.md,
"Per material").

    python benchmarks/measure_materials.py [--json]          # network now, FEM as stored
    python benchmarks/measure_materials.py --fem [--only K]  # solve and store the FEM

The FEM torques are stored in benchmarks/data/fem_materials.json (``--fem``: each solve
0.05–0.4 s, ~5 min per material set on a loaded machine; ``--only K`` solves the K-th set
alone, to spread the sets over processes, and merges it into the file).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE / "data" / "fem_reference.json"
STORED = HERE / "data" / "fem_materials.json"
SETS = {
    "MRF-122EG / 1018": {"fluid": "mrf_122eg"},
    "MRF-132DG / 1018": {"fluid": "mrf_132dg"},
    "MRF-140CG / 1018": {"fluid": "mrf_140cg"},
    "MRF-132DG / Hiperco 50 core + shell": {"core": "hiperco_50", "shell": "hiperco_50"},
}
CURRENT = 7.0
DESIGNS = 50


def designs() -> list:
    from geometry.params import DrumClutch
    from mrclutch.design import design_preset

    data = json.loads(DATA.read_text())
    base = vars(design_preset(data["base_preset"]).clutch)
    ints = {"n_drums", "coil_turns", "hub_holes"}
    rows = [r for r in data["random"] if r["torque"] is not None][:DESIGNS]
    return [DrumClutch(**{k: (int if k in ints else float)(r["design"].get(k, v))
                          for k, v in base.items()}) for r in rows]  # fmt: skip


def torques(method: str, only: int | None = None) -> dict[str, list[float]]:
    from geometry.materials import MaterialChoice
    from geometry.section import build_section
    from magnetics.torque import torque_curve

    cs = designs()
    out = {}
    for k, (label, choice) in enumerate(SETS.items()):
        if only is not None and k != only:
            continue
        mats = MaterialChoice(**choice)
        out[label] = [float(torque_curve(build_section(c, mats), [CURRENT], method)
                            .yield_torque[0]) for c in cs]  # fmt: skip
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fem", action="store_true", help="solve the FEM and store its torques")
    ap.add_argument("--only", type=int, default=None, help="only the K-th material set")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    if args.fem:
        t0 = time.perf_counter()
        new = torques("fem", args.only)
        stored = json.loads(STORED.read_text()) if STORED.exists() else {}
        stored.update({"current_A": CURRENT, "designs": DESIGNS})
        stored.setdefault("torque_N_m", {}).update(new)
        STORED.write_text(json.dumps(stored, indent=1) + "\n")
        print(f"FEM stored for {', '.join(new)} in {time.perf_counter() - t0:.0f} s")
        return
    fem = json.loads(STORED.read_text())["torque_N_m"]
    net = torques("network")
    out = {}
    for label in SETS:
        e = np.array(net[label]) / np.array(fem[label]) - 1
        a = np.abs(e)
        out[label] = {
            "designs": int(e.size),
            "within_5pct": float(np.mean(a <= 0.05)),
            "within_10pct": float(np.mean(a <= 0.10)),
            "median_abs": float(np.median(a)),
            "worst": float(e[np.argmax(a)]),
        }
    if args.json:
        print(json.dumps(out, indent=1))
        return
    print(f"{'material set':38s} designs  ±5 %    ±10 %   median|e|  worst")
    for label, r in out.items():
        print(
            f"{label:38s} {r['designs']:5d}  {r['within_5pct']:6.1%}  {r['within_10pct']:6.1%}"
            f"  {r['median_abs']:7.2%}   {r['worst']:+.1%}"
        )


if __name__ == "__main__":
    main()
