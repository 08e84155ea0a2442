"""The reluctance network and the single-loop circuit against the stored FEM reference
(`benchmarks/data/fem_reference.json`, written by measure_fem_reference.py): the signed
error model/FEM − 1 of the yield torque at 2, 4 and 7 A on the 648-design grid and on the
200 random designs, per drum count; the share within ±5 % and ±10 %; the paper preset; and,
with ``--plot PATH``, a histogram of the errors.

    python benchmarks/measure_network.py [--convention mid-line] [--plot docs/network.png]
        [--outer-air-scale 1.4]

``--outer-air-scale`` multiplies the network's permeance of the air outside the shell (the
solved one, magnetics.outer_air; docs/magnetics.md's ×1.4 figures scaled the flux tubes
it replaced, at revision 06bf0ce): a
diagnostic of how much of the error that element holds (docs/magnetics.md, "The shell,
traced"), not a model; the preset's FEM check is skipped with it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "fem_reference.json"


def load(convention: str = "mid-line") -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """(fields of every design, FEM torque (S, 3), is-random (S,)) of the stored data."""
    from mrclutch.design import design_preset

    data = json.loads(DATA.read_text())
    base = vars(design_preset(data["base_preset"]).clutch)
    rows = [(r, False) for r in data["grid"]] + [(r, True) for r in data["random"]]
    rows = [(r, rnd) for r, rnd in rows if r["torque"] is not None]
    fields = {k: np.array([r["design"].get(k, v) for r, _ in rows], dtype=float)
              for k, v in base.items()}  # fmt: skip
    fem = np.array([r["torque"][convention] for r, _ in rows])
    return fields, fem, np.array([rnd for _, rnd in rows])


def errors(method: str, convention: str = "mid-line") -> tuple[np.ndarray, np.ndarray, dict]:
    """(error (S, 3), is-random (S,), fields) of ``method`` ("network" | "circuit")."""
    from magnetics.torque import network_torque_batch, torque_grid_batch

    fields, fem, rnd = load(convention)
    currents = json.loads(DATA.read_text())["currents_A"]
    if method == "network":
        t = network_torque_batch(fields, currents, convention=convention)
    else:
        t = torque_grid_batch(fields, currents, convention=convention)
    return t / fem - 1.0, rnd, fields


def table(err: np.ndarray, n: np.ndarray) -> list[tuple[str, int, float, float, float, float]]:
    """Per drum count and in all: (label, designs, within 5 %, within 10 %, min, max) over
    every design and current."""
    out = []
    for lab, sel in [*((str(int(v)), n == v) for v in np.unique(n)), ("all", n > 0)]:
        e = err[sel].ravel()
        out.append((lab, int(sel.sum()), float(np.mean(np.abs(e) <= 0.05)),
                    float(np.mean(np.abs(e) <= 0.10)), float(e.min()), float(e.max())))  # fmt: skip
    return out


def _scale_outer_air(scale: float) -> None:
    """Every network built from here on has its outside air's permeance × ``scale``."""
    from dataclasses import replace

    import magnetics.torque as torque

    build = torque.network_from_regions

    def scaled(*args, **kwargs):  # type: ignore[no-untyped-def]
        net = build(*args, **kwargs)
        return replace(net, outer_air=net.outer_air / scale)

    torque.network_from_regions = scaled


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--convention", default="mid-line")
    ap.add_argument("--plot", type=Path)
    ap.add_argument("--outer-air-scale", type=float, default=None)
    a = ap.parse_args()
    if a.outer_air_scale is not None:
        _scale_outer_air(a.outer_air_scale)
    res = {m: errors(m, a.convention) for m in ("network", "circuit")}
    for m, (err, rnd, f) in res.items():
        for part, sel in (("grid (648)", ~rnd), ("random (200)", rnd)):
            print(f"\n{m}, {part}, 2/4/7 A, {a.convention}")
            print("| drums | designs | within ±5 % | within ±10 % | min | max |")
            print("|---|---|---|---|---|---|")
            for lab, cnt, w5, w10, lo, hi in table(err[sel], f["n_drums"][sel]):
                print(f"| {lab} | {cnt} | {w5:.0%} | {w10:.0%} | {lo:+.1%} | {hi:+.1%} |")
    if a.outer_air_scale is not None:
        return
    from magnetics.torque import torque_curve
    from mrclutch.design import design_preset

    c = design_preset("paper").clutch
    fem = torque_curve(c, [2.0, 4.0, 7.0], method="fem", convention=a.convention).yield_torque
    for m in ("network", "circuit"):
        t = torque_curve(c, [2.0, 4.0, 7.0], method=m, convention=a.convention).yield_torque
        print(f"paper preset, {m}: {np.round(t / fem - 1, 4)} at 2/4/7 A")
    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 3.5))
        bins = np.linspace(-0.9, 0.9, 73)
        for m, (err, _, _) in res.items():
            ax.hist(np.clip(err.ravel(), -0.9, 0.9), bins, alpha=0.6, label=m)
        ax.axvspan(-0.05, 0.05, color="0.85", zorder=0)
        ax.set_xlabel("yield torque, model/FEM − 1 (848 designs × 2, 4, 7 A)")
        ax.set_ylabel("count")
        ax.legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=110)
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
