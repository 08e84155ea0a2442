"""``mrclutch torque`` and ``mrclutch field``: torque against current, B map of the section.

Nothing heavy at module level (magnetics, scikit-fem and matplotlib load inside handlers).
"""

from __future__ import annotations

import argparse

from mrclutch.commands._common import add_design_args, atomic_path, load_clutch, print_json


def _parse_currents(text: str):  # type: ignore[no-untyped-def]
    """``A``, ``START:STOP:STEP`` (inclusive of STOP) or ``A,B,C`` in amperes."""
    import numpy as np

    from mrclutch.cli import CLIError

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
    p = sub.add_parser("torque", help="torque against coil current (circuit or FEM)")
    add_design_args(p)
    p.add_argument("--current", default="0:7:0.5", help="A, A,B,C or START:STOP:STEP (A)")
    p.add_argument("--method", default="circuit", help="circuit (default) or fem")
    p.add_argument("--speed-rpm", type=float, default=530.0, help="slip speed (rpm)")
    p.add_argument("--json", action="store_true", help="JSON on stdout")
    p.add_argument("--plot", metavar="FILE.png", help="write a torque-current chart")
    p.set_defaults(func=_torque)

    f = sub.add_parser("field", help="FEM flux-density map over the section at one current")
    add_design_args(f)
    f.add_argument("--current", type=float, default=4.0, help="coil current (A)")
    f.add_argument("--size-mm", type=float, default=None, help="FEM element size (mm)")
    f.add_argument("--plot", metavar="FILE.png", required=True, help="output PNG")
    f.set_defaults(func=_field)


def _torque(args: argparse.Namespace) -> int:
    from geometry.validation import ParameterError, check_choice, check_range
    from magnetics.fem import FEMConvergenceError
    from magnetics.torque import torque_curve
    from mrclutch.cli import CLIError

    check_choice("--method", args.method, ("circuit", "fem"))
    check_range("--speed-rpm", args.speed_rpm, 0.0, 1e5, " rpm")
    currents = _parse_currents(args.current)
    clutch = load_clutch(args)
    try:
        tc = torque_curve(clutch, currents, method=args.method, speed_rpm=args.speed_rpm)
    except FEMConvergenceError as exc:
        raise CLIError(str(exc)) from None
    except FloatingPointError as exc:  # pragma: no cover - defensive
        raise ParameterError(str(exc)) from None
    if args.plot:
        from mrclutch.plots.magnetics import plot_torque

        with atomic_path(args.plot) as tmp:
            plot_torque([tc], tmp)
    if args.json:
        print_json(
            {
                "method": tc.method,
                "speed_rpm": tc.speed_rpm,
                "points": [
                    {"current_A": float(i), "torque_N_m": float(t)}
                    for i, t in zip(tc.currents, tc.torque, strict=True)
                ],
                "viscous_torque_N_m": tc.viscous_torque,
                "damping_N_m_s": tc.damping,
            }
        )
    else:
        print(f"method {tc.method}, {tc.speed_rpm:g} rpm: viscous {tc.viscous_torque:.4g} N·m, "
              f"damping {tc.damping:.4g} N·m·s")  # fmt: skip
        print("current_A  torque_N_m")
        for i, t in zip(tc.currents, tc.torque, strict=True):
            print(f"{i:9.4g}  {t:.5g}")
    return 0


def _field(args: argparse.Namespace) -> int:
    from geometry.section import build_section
    from geometry.validation import check_range
    from magnetics.fem import FEMConvergenceError, solve_fem
    from mrclutch.cli import CLIError
    from mrclutch.plots.magnetics import plot_field

    check_range("--current", args.current, -1e4, 1e4, " A")
    size = None
    if args.size_mm is not None:
        size = check_range("--size-mm", args.size_mm, 0.02, 5.0, " mm") * 1e-3
    section = build_section(load_clutch(args))
    try:
        sol = solve_fem(section, args.current, size=size)
    except FEMConvergenceError as exc:
        raise CLIError(str(exc)) from None
    with atomic_path(args.plot) as tmp:
        plot_field(section, sol, tmp)
    print(f"wrote {args.plot}: |B| max {sol.b.max():.3g} T, {sol.iterations} Newton iterations")
    return 0
