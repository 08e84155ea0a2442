"""``mrclutch torque`` and ``mrclutch field``: torque against current, B map of the section.

Nothing heavy at module level (magnetics, scikit-fem and matplotlib load inside handlers).
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from geometry.section import build_section
from geometry.validation import ParameterError, check_choice, check_range
from magnetics.circuit import path_from_section
from magnetics.drag import ROOM_TEMPERATURE
from magnetics.dynamics import flux_linkage
from magnetics.fem import DEFAULT_SIZE, FEMConvergenceError, solve_fem
from magnetics.fem.grid import check_memory, time_estimate
from magnetics.network import flux_linkage as network_flux_linkage
from magnetics.network import network_from_regions
from magnetics.torque import torque_curve
from mrclutch.cli.commands._common import (
    add_design_args,
    load_design_args,
    print_json,
)
from mrclutch.cli.commands.handoff import add_map_args, write_torque_map
from mrclutch.cli.errors import CLIError
from mrclutch.cli.longjobs import announce
from mrclutch.cli.plots.magnetics import plot_field, plot_torque
from mrclutch.pipeline import current_notes
from mrclutch.torque_for import current_for


def _parse_currents(text: str):  # type: ignore[no-untyped-def]
    """``A``, ``START:STOP:STEP`` (inclusive of STOP) or ``A,B,C`` in amperes."""
    try:
        if ":" in text:
            a, b, s = (float(x) for x in text.split(":"))
            if not (s > 0 and b >= a) or not all(np.isfinite([a, b, s])):
                raise ValueError
            if (b - a) / s > 10_000:
                raise CLIError(f"--current {text}: more than 10000 points")
            vals = np.arange(a, b + s * 1e-9, s)
        else:
            vals = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise CLIError(
            f"--current {text!r}: give A, A,B,C or START:STOP:STEP with STEP > 0, STOP ≥ START"
        ) from None
    if not np.all(np.isfinite(vals)) or vals.size == 0:
        raise CLIError(f"--current {text!r}: currents must be finite numbers (A)")
    return vals


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("torque", help="torque against coil current (network, circuit or FEM)")
    add_design_args(p)
    p.add_argument("--current", default=None,
                   help="A, A,B,C or START:STOP:STEP (A); default 0 to the design's current "
                   "limit in 0.5 A steps")  # fmt: skip
    p.add_argument("--ignore-limit", action="store_true",
                   help="allow currents below 0 A or above the design's current limit (its "
                   "max_current_A capped by the current density and the supply)")  # fmt: skip
    p.add_argument("--for", dest="for_torque", type=float, default=None, metavar="NM",
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
    p.add_argument("--speed-rpm", type=float, default=530.0, help="slip speed (rpm)")
    p.add_argument("--yes", action="store_true",
                   help="run FEM solves estimated above 10 min (refused without it; above "
                   "30 s the estimate is said first: mrclutch/cli/longjobs.py)")  # fmt: skip
    p.add_argument(
        "--fluid-temperature-C",
        type=float,
        default=ROOM_TEMPERATURE,
        help="fluid temperature for its viscosity (°C, default room)",
    )
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


def _currents(args: argparse.Namespace, design: Any) -> Any:
    """The currents asked for (default 0 to the current limit), each within
    [0, the design's current limit] unless ``--ignore-limit``."""
    limit = design.current_limit
    if args.current is None:
        steps = np.arange(0.0, limit, 0.5)
        return np.append(steps, limit) if limit - steps[-1] > 1e-9 else steps
    currents = _parse_currents(args.current)
    if args.ignore_limit:
        return currents
    if np.any(currents < 0):
        raise CLIError(f"--current {args.current}: {currents.min():g} A is negative; the "
                       "yield torque does not depend on the current's sign (give "
                       "--ignore-limit to compute it anyway)")  # fmt: skip
    if np.any(currents > limit * (1 + 1e-9)):
        why = "; ".join(current_notes(design)) or f"max_current_A = {limit:g}"
        raise CLIError(f"--current {args.current}: {currents.max():g} A is above the design's "
                       f"current limit {limit:.4g} A ({why}); give --ignore-limit to compute "
                       "it anyway")  # fmt: skip
    return currents


def _torque(args: argparse.Namespace) -> int:
    check_choice("--method", args.method, ("circuit", "network", "fem", "both"))
    check_range("--speed-rpm", args.speed_rpm, 0.0, 1e5, " rpm")
    design = load_design_args(args)
    if args.for_torque is not None:
        return _torque_for(args, design)
    currents = _currents(args, design)
    if args.map is not None:
        return write_torque_map(args, currents)
    clutch = build_section(design.clutch, design.materials)
    methods = ("network", "fem") if args.method == "both" else (args.method,)
    if "fem" in methods and currents.size > 1:  # long FEM work says how long first
        section = clutch  # already the section, with the design's materials
        check_memory(section, DEFAULT_SIZE)
        seconds = time_estimate(section, DEFAULT_SIZE, int(currents.size))
        announce("torque", f"{currents.size} FEM solves at {DEFAULT_SIZE * 1e3:g} mm", seconds,
                 "the FEM's measured rate per grid node, magnetics.fem.grid.SECONDS_PER_NODE",
                 args.yes)  # fmt: skip
    try:
        curves = [torque_curve(clutch, currents, method=m, speed_rpm=args.speed_rpm,
                               temperature=args.fluid_temperature_C) for m in methods]  # fmt: skip
    except FEMConvergenceError as exc:
        raise CLIError(str(exc)) from None
    except FloatingPointError as exc:  # pragma: no cover - defensive
        raise ParameterError(str(exc)) from None
    if args.plot:
        plot_torque(curves, args.plot)  # through the output layer
    # largest relative network-vs-FEM difference where the FEM torque is not ~0 (0 A)
    err = None
    if len(curves) == 2:
        c, f = curves[0].torque, curves[1].torque
        keep = f > 10 * curves[1].off_state_torque
        err = float(np.max(np.abs(c[keep] / f[keep] - 1))) if keep.any() else 0.0
    model = "circuit" if args.method == "circuit" else "network"
    lam, ind = _inductance(clutch, curves[0].currents, model)
    notes = [*current_notes(design)] if not args.ignore_limit else []
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


def _torque_for(args: argparse.Namespace, design: Any) -> int:
    """``torque --for NM``: the current each method needs for NM N·m, or the most it gives
    at the design's current limit (``--ignore-limit``: up to 10× that limit)."""
    target = check_range("--for", args.for_torque, 0.0, 1e6, " N·m", lo_open=True)
    if args.current is not None or args.map is not None or args.plot:
        raise CLIError("--for: not with --current, --map or --plot (it finds the current)")
    methods = ("network", "fem") if args.method == "both" else (args.method,)
    limit = design.current_limit * (10.0 if args.ignore_limit else 1.0)
    try:
        rows = [current_for(design, target, m, limit, speed_rpm=args.speed_rpm,
                            temperature=args.fluid_temperature_C) for m in methods]  # fmt: skip
    except FEMConvergenceError as exc:
        raise CLIError(str(exc)) from None
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


def _inductance(clutch: Any, currents: Any, model: str = "circuit") -> tuple[Any, Any]:
    """Flux linkage λ (Wb) and incremental inductance dλ/dI (H) at the currents, by the
    saturating circuit (magnetics.dynamics.flux_linkage) or the reluctance network
    (magnetics.network.flux_linkage: within 1 % of the FEM's λ on the paper preset)."""
    section = clutch if hasattr(clutch, "regions") else build_section(clutch)
    cur = np.asarray(currents, dtype=float)[None, :]
    if model == "network":
        net = network_from_regions(section.table)
        lam, ind = network_flux_linkage(net, net.turns[:, None] * cur)
    else:
        lam, ind = flux_linkage(path_from_section(section), cur)
    return lam[0], ind[0]


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
    section = build_section(design.clutch, design.materials)
    try:
        sol = solve_fem(section, args.current, size=size)
    except FEMConvergenceError as exc:
        raise CLIError(str(exc)) from None
    plot_field(section, sol, args.plot)  # through the output layer
    print(f"wrote {args.plot}: |B| max {sol.b.max():.3g} T, {sol.iterations} Newton iterations")
    limit = design.current_limit
    if abs(args.current) > limit:  # a field the clutch cannot carry: say why it is so high
        c = design.clutch
        j = abs(args.current) / (math.pi * c.wire_diameter**2 / 4) * 1e-6
        amps = abs(args.current)
        print(f"note: {amps:g} A is {amps / limit:.3g}× the design's current limit "
              f"({limit:.3g} A): {j:.3g} A/mm² in the copper, which the wire does not "
              "survive; past the steel's saturation (about 2 T) the rest of |B| is the "
              f"air-core field of {c.coil_turns * amps:.3g} ampere-turns")  # fmt: skip
    return 0
