"""``mrclutch torque`` and ``mrclutch field``: torque against current, B map of the section.

Parses, calls the application layer (mrclutch.torque_curves: the currents, curves,
inductance and field map) and formats (issue 43: no computation under ``mrclutch/cli/``).
"""

from __future__ import annotations

import argparse
from typing import Any

from geometry.validation import check_choice, check_range
from mrclutch.cli.commands._common import (
    add_design_args,
    load_design_args,
    print_json,
)
from mrclutch.cli.errors import CLIError
from mrclutch.design import current_notes
from mrclutch.torque_curves import (
    FEM_SIZE,
    b_max,
    currents_asked,
    currents_for,
    fem_seconds,
    field_map,
    inductance,
    largest_difference,
    overload_note,
    torque_curves,
)


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("torque", help="torque against coil current (network, circuit or FEM)")
    add_design_args(p)
    p.add_argument("--current", default=None,
                   help="A, A,B,C or START:STOP:STEP (A); default 0 to the design's current "
                   "limit in 0.5 A steps")  # fmt: skip
    p.add_argument("--ignore-limit", action="store_true",
                   help="allow currents below 0 A or above the design's current limit (its "
                   "max_current_A capped by the current density and the supply)")  # fmt: skip
    p.add_argument("--for", dest="for_torque", default=None, metavar="NM",
                   help="the current that gives NM N·m (yield + drag at the slip speed), by "
                   "each --method (both: network and FEM); or what the most is, if out of "
                   "reach")  # fmt: skip
    p.add_argument(
        "--method",
        default="network",
        help="network (default: the reluctance network built from the section, within 1.6 %% "
        "of the FEM on the paper preset and 10 %% on all 848 reference designs and on 200 "
        "random designs varying every dimension, whose FEM error its 95 %% bound covers on "
        "96.5 %%, docs/magnetics.md), circuit (the single loop, tuned at the paper preset), "
        "fem, or both (the network checked against the FEM: both curves, and the largest relative "
        "difference)",
    )
    p.add_argument("--speed-rpm", type=float, default=None,
                   help="slip speed (rpm; default: the design's [operating] input_speed_rpm, "
                   "as evaluate)")  # fmt: skip
    p.add_argument("--yes", action="store_true",
                   help="run FEM solves estimated above 10 min (refused without it; above "
                   "30 s the estimate is said first: mrclutch/cli/longjobs.py)")  # fmt: skip
    p.add_argument("--fluid-temperature-C", type=float, default=None,
                   help="fluid temperature for its viscosity (°C; default: the design's "
                   "[operating] fluid_temperature_C, as evaluate)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="JSON on stdout")
    p.add_argument("--plot", metavar="FILE.png", help="write a torque-current chart")
    add_map_args(p)
    p.set_defaults(func=_torque)

    f = sub.add_parser("field", help="FEM flux-density map over the section at one current")
    add_design_args(f)
    f.add_argument("--current", type=float, default=4.0, help="coil current (A)")
    f.add_argument("--size-mm", type=float, default=None, help="FEM element size (mm)")
    f.add_argument("--plot", metavar="FILE.png", required=True, help="output PNG")
    f.set_defaults(func=_field)


def add_map_args(p: argparse.ArgumentParser) -> None:
    """``mrclutch torque``'s torque-map options (``write_torque_map`` of
    mrclutch.cli.commands.handoff, loaded only when ``--map`` is given: the hand-offs' module
    and mrclutch.handoff are not a plain torque curve's imports, issue 40)."""
    p.add_argument(
        "--map",
        metavar="FILE.csv|.parquet",
        help="write a torque map over current (--current) x slip speed (--map-speeds-rpm) x "
        "fluid temperature (--map-temperatures-C): the yield torque by --method (network, "
        "circuit or fem) with the fluid's tau_y(T), the off-state torque (the drag) and "
        "their sum; a controller's lookup table (docs/handoff.md)",
    )
    p.add_argument(
        "--map-speeds-rpm",
        default="0,100,265,530",
        metavar="S,S,...",
        help="--map: slip speeds, rpm (default 0,100,265,530)",
    )
    p.add_argument(
        "--map-temperatures-C",
        default="20,40,60",
        metavar="T,T,...",
        help="--map: fluid temperatures, °C (default 20,40,60)",
    )


def _operating_point(args: argparse.Namespace, design: Any) -> None:
    """The slip speed and fluid temperature not given take the design's own (``evaluate``'s
    max torque is at them, with the design's ``[support]`` drag): one design, one torque."""
    op = design.operating
    if args.speed_rpm is None:
        args.speed_rpm = op.input_speed_rpm
    if args.fluid_temperature_C is None:
        args.fluid_temperature_C = op.fluid_temperature


def _torque(args: argparse.Namespace) -> int:
    check_choice("--method", args.method, ("circuit", "network", "fem", "both"))
    if args.speed_rpm is not None:
        check_range("--speed-rpm", args.speed_rpm, 0.0, 1e5, " rpm")
    given = [o for o, v in (("--speed-rpm", args.speed_rpm),
                            ("--fluid-temperature-C", args.fluid_temperature_C))
             if v is not None]  # fmt: skip
    if args.map is not None and given:
        raise CLIError(f"--map: not with {given[0]} (give --map-speeds-rpm and "
                       "--map-temperatures-C)")  # fmt: skip
    design = load_design_args(args)
    _operating_point(args, design)
    if args.for_torque is not None:
        return _torque_for(args, design)
    currents = currents_asked(design, args.current, args.ignore_limit)
    if args.map is not None:
        from mrclutch.cli.commands.handoff import write_torque_map  # the map's alone

        return write_torque_map(args, currents)
    clutch = design.section()
    methods = ("network", "fem") if args.method == "both" else (args.method,)
    if "fem" in methods and currents.size > 1:  # long FEM work says how long first
        from mrclutch.cli.longjobs import announce  # the FEM's alone

        seconds = fem_seconds(clutch, int(currents.size))
        announce("torque", f"{currents.size} FEM solves at {FEM_SIZE * 1e3:g} mm", seconds,
                 "the FEM's measured rate per grid node, magnetics.fem.grid.SECONDS_PER_NODE",
                 args.yes)  # fmt: skip
    curves = torque_curves(clutch, currents, methods, speed_rpm=args.speed_rpm,
                           temperature=args.fluid_temperature_C,
                           support=design.support)  # fmt: skip
    if args.plot:
        from mrclutch.cli.plots.magnetics import plot_torque  # a plot's alone

        plot_torque(curves, args.plot)  # through the output layer
    err = largest_difference(*curves) if len(curves) == 2 else None
    model = "circuit" if args.method == "circuit" else "network"
    lam, ind = inductance(clutch, curves[0].currents, model)
    notes = [*current_notes(design)] if not args.ignore_limit else _past_limit(design, currents)
    if args.json:
        data = {**_curve_json(curves[0])}
        if err is not None:
            data = {"network": _curve_json(curves[0]), "fem": _curve_json(curves[1]),
                    "max_torque_error_rel": err}  # fmt: skip
        data["flux_linkage_Wb"], data["inductance_H"] = lam, ind
        data["flux_linkage_method"] = model
        data["current_limit_A"], data["notes"] = design.current_limit, notes
        print_json(data)
        return 0
    for note in notes:
        print(f"note: {note}")
    for tc in curves:
        print(
            f"method {tc.method}, {tc.speed_rpm:g} rpm, fluid at {tc.drag.temperature:g} °C: "
            f"off-state {tc.off_state_torque:.4g} N·m, damping {tc.damping:.4g} N·m·s"
        )
    print("current_A  " + "  ".join(f"{tc.method}_N_m" for tc in curves)
          + f"  flux_linkage_mWb  L_inc_mH ({model})")  # fmt: skip
    for k, i in enumerate(curves[0].currents):
        print(f"{i:9.4g}  " + "  ".join(f"{tc.torque[k]:.5g}" for tc in curves)
              + f"  {lam[k] * 1e3:.4g}  {ind[k] * 1e3:.4g}")  # fmt: skip
    if err is not None:
        print(f"largest network-vs-FEM difference: {err * 100:.2f} %")
    return 0


def _past_limit(design: Any, currents: Any) -> list[str]:
    """With ``--ignore-limit``: say which currents asked lie past the design's limit (the
    figures there are computed as asked, not what the design can carry)."""
    cap = design.current_limit
    past = [float(i) for i in currents if i < 0 or i > cap * (1 + 1e-9)]
    if not past:
        return []
    why = "; ".join(current_notes(design)) or f"max_current_A = {cap:g}"
    return [f"{', '.join(f'{i:g}' for i in past[:5])}{' …' if len(past) > 5 else ''} A outside "
            f"the design's current range [0, {cap:.4g}] A ({why}): computed as asked "
            "(--ignore-limit)"]  # fmt: skip


def _torque_for(args: argparse.Namespace, design: Any) -> int:
    """``torque --for NM``: the current each method needs for NM N·m, or the most it gives
    at the design's current limit (``--ignore-limit``: up to 10× that limit)."""
    try:  # parsed here, not by argparse: a word is one line too (its usage block is not)
        value = float(args.for_torque)
    except ValueError:
        raise CLIError(f"--for {args.for_torque!r}: give a torque in N·m, e.g. --for 0.3") from None
    target = check_range("--for", value, 0.0, 1e6, " N·m", lo_open=True)
    if args.current is not None or args.map is not None or args.plot:
        raise CLIError("--for: not with --current, --map or --plot (it finds the current)")
    methods = ("network", "fem") if args.method == "both" else (args.method,)
    limit = design.current_limit * (10.0 if args.ignore_limit else 1.0)
    rows = currents_for(design, target, methods, limit, speed_rpm=args.speed_rpm,
                        temperature=args.fluid_temperature_C)  # fmt: skip
    notes = [*current_notes(design)] if not args.ignore_limit else []
    if args.json:
        print_json({"torque_N_m": target, "current_limit_A": limit, "methods": rows,
                    "notes": notes})  # fmt: skip
        return 0
    for r in rows:
        print(r["text"])
    for note in notes:
        print(f"note: {note}")
    return 0


def _curve_json(tc) -> dict:  # type: ignore[no-untyped-def]
    return {
        "method": tc.method,
        "speed_rpm": tc.speed_rpm,
        "points": [
            {"current_A": float(i), "torque_N_m": float(t)}
            for i, t in zip(tc.currents, tc.torque, strict=True)
        ],
        "off_state_torque_N_m": tc.off_state_torque,
        "drag_damping_N_m_s": tc.damping,
        "drag": tc.drag.as_json(),
    }


def _field(args: argparse.Namespace) -> int:
    check_range("--current", args.current, -1e4, 1e4, " A")
    size = None
    if args.size_mm is not None:
        size = check_range("--size-mm", args.size_mm, 0.02, 5.0, " mm") * 1e-3
    design = load_design_args(args)
    section, sol = field_map(design, args.current, size)
    from mrclutch.cli.plots.magnetics import plot_field  # the torque curve's: not its plots

    plot_field(section, sol, args.plot)  # through the output layer
    print(f"wrote {args.plot}: |B| max {b_max(sol):.3g} T, {sol.iterations} Newton iterations")
    note = overload_note(design, args.current)
    if note is not None:  # a field the clutch cannot carry: say why it is so high
        print(f"note: {note}")
    return 0
