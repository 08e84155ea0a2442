"""Optimise the clutch for rendering bandwidth under a torque floor and a mass limit,
then check the winner at reference fidelity (exact B-rep inertia, FEM torque).

    python examples/optimize_bandwidth.py [--tiny]
"""

from __future__ import annotations

import sys

from mrclutch.design import design_preset
from mrclutch.optimize import Constraints, optimize
from mrclutch.pipeline import evaluate


def main(tiny: bool = False, verify: bool = True) -> dict:
    opt = optimize(
        design_preset("paper"),
        constraints=Constraints(min_torque=0.4, max_mass=0.100),
        drum_counts=(2,) if tiny else (1, 2, 3, 4),
        maxiter=8 if tiny else 60,
        popsize=8 if tiny else 24,
    )
    c = opt.design.clutch
    print(f"best: {c.n_drums} drums, gap {c.gap * 1e3:.3g} mm, drum {c.drum_thickness * 1e3:.3g}"
          f" mm → {opt.value:.1f} Hz ({opt.evaluations} designs evaluated)")  # fmt: skip
    result = {"fast": evaluate(opt.design, "fast").as_json()}
    if verify:
        result["reference"] = evaluate(opt.design, "reference").as_json()
        f, r = (
            result["fast"]["haptic"]["bandwidth_hz"],
            result["reference"]["haptic"]["bandwidth_hz"],
        )
        print(f"reference fidelity: {r:.1f} Hz ({(r / f - 1) * 100:+.2f} % vs fast)")
    return result


if __name__ == "__main__":
    main(tiny="--tiny" in sys.argv)
