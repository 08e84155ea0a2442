"""``mrclutch scale``: the paper's scaling study (Fig. 7b) with real geometry; a bar of its
steps with its estimate on stderr (issue 40: a job over ~2 s says how long)."""

from __future__ import annotations

import argparse

from mrclutch.cli.commands._common import add_design_args, load_design_args, print_json
from mrclutch.cli.progress import bar
from mrclutch.pipeline import source_label
from mrclutch.scaling import PAPER_TOTAL_INERTIA_INCREASE_2X, STEPS, as_json, scaling_study


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "scale",
        help="reach k× torque by more drums, longer drums or a larger diameter (Fig. 7b)",
        description="For each route to --factor × the design's torque: the change in rotor "
        "inertia, total moving mass at the hand, damping b1 and clutch mass, beside the "
        "paper's +14 % total reflected inertia for 2× scaling.",
    )
    add_design_args(p)
    p.add_argument("--factor", type=float, default=2.0, help="torque factor (default 2)")
    p.add_argument("--json", action="store_true")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(func=_scale)


def _scale(args: argparse.Namespace) -> int:
    design = load_design_args(args)
    with bar(len(STEPS), "scale", "step", not args.no_progress) as done:
        done(0, f"scale: {STEPS[0]}")
        base, routes, notes = scaling_study(
            design, args.factor, lambda n, what: done(n, f"scale: {what}" if what else None)
        )
    if args.json:
        print_json(as_json(base, routes, notes, design))
        return 0
    print(f"{design.name}: {base['max_torque_N_m']:.3g} N·m → target "
          f"{args.factor:g}× = {args.factor * base['max_torque_N_m']:.3g} N·m  "
          f"[MR pair, {source_label('fast')}: changes against its m1, b1, K_max]")  # fmt: skip
    print(f"{'route':<17}{'value':>12}{'torque':>9}{'inertia':>10}{'m1+m2':>9}{'b1':>9}"
          f"{'mass':>9}")  # fmt: skip
    for r in routes:
        v = f"{r.value:g}" if r.parameter == "n_drums" else f"{r.value * 1e3:.3g} mm"
        keys = ("rotor_inertia", "total_moving_mass", "damping_b1", "clutch_mass")
        cells = "".join(f"{r.changes[k] * 100:>+8.0f}%" for k in keys)
        print(f"{r.name:<17}{v:>12}{r.torque_ratio:>8.2f}×{cells}")
    print(f"lumped bandwidth √(K/(m1+m2)) (Eq. 1), base {base['bandwidth_lumped_hz']:.3g} Hz: "
          f"the base K_max ({base['K_N_per_m']:.4g} N/m) on the added mass lowers it; "
          "a route's own K_max (∝ torque) raises it")  # fmt: skip
    for r in routes:
        same, own = (r.changes[k] * 100 for k in ("bandwidth_lumped_same_K",
                                                 "bandwidth_lumped_own_K"))  # fmt: skip
        print(f"  {r.name:<17}{same:>+7.0f}% at the base K_max{own:>+8.0f}% at its own K_max")
    print(f"paper (abstract 2× scaling): total reflected inertia "
          f"+{PAPER_TOTAL_INERTIA_INCREASE_2X * 100:.0f} %")  # fmt: skip
    for n in notes:
        print(f"note: {n}")
    return 0
