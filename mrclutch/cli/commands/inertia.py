"""``mrclutch inertia``: a design's rotor inertia and masses (analytic, mesh, B-rep), or a
STEP/STL file weighed. Its own module so that ``inertia --method analytic`` imports none of
``export``'s hand-offs and ``view``'s renderer (issue 40: interactive commands answer fast).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from geometry.params import DrumClutch
from geometry.validation import ParameterError, check_range
from mrclutch.cli.commands._common import add_design_args, load_design_args, print_json
from mrclutch.cli.errors import CLIError
from mrclutch.cli.progress import bar
from mrclutch.inertia import design_inertia

CAD_SUFFIXES = (".step", ".stp", ".stl")
DEFAULT_TOLERANCE_MM = 0.01
INERTIA_METHODS = ("all", "analytic", "mesh", "brep")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "inertia",
        help="rotor inertia and masses (analytic, mesh, brep), or weigh a STEP/STL file",
        description="With a design (DESIGN.toml or --preset): the three methods compared. "
        "With FILE.step|FILE.stl (mm): mass and inertia about an axis through the origin.",
    )
    add_design_args(p)
    p.add_argument("--json", action="store_true", help="print JSON")
    add_tolerance(p)
    p.add_argument(
        "--method",
        choices=INERTIA_METHODS,
        default="all",
        help="a design: one method (analytic answers at once; mesh and brep build the CAD "
        "solids) or all three compared (default)",
    )
    p.add_argument("--axis", choices=("x", "y", "z"), default="z", help="CAD file: axis")
    p.add_argument("--density", type=float, metavar="KG_M3", help="CAD file: one density")
    p.add_argument(
        "--part-density",
        action="append",
        default=[],
        metavar="NAME=KG_M3",
        help="CAD file: density of a named part (STEP labels; repeatable)",
    )
    p.set_defaults(func=cmd_inertia)


def add_tolerance(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--tolerance-mm",
        type=float,
        default=DEFAULT_TOLERANCE_MM,
        help=f"mesh chord height, mm (default {DEFAULT_TOLERANCE_MM})",
    )


def tolerance(args: argparse.Namespace, clutch: DrumClutch) -> float:
    """``--tolerance-mm`` in metres, bounded below relative to the clutch (memory)."""
    from mrclutch.solids import chord_height_mm  # the CAD export's module: a mesh's alone

    return chord_height_mm("--tolerance-mm", args.tolerance_mm, clutch)


def _method(rep: Any) -> dict[str, Any]:
    return {
        "rotor_inertia_kg_m2": rep.rotor_inertia,
        "rotor_mass_kg": rep.rotor_mass,
        "clutch_mass_kg": rep.clutch_mass,
        "parts": {
            n: {"mass_kg": pm.mass, "inertia_kg_m2": pm.inertia} for n, pm in rep.parts.items()
        },
        "notes": list(rep.notes),
    }


def cmd_inertia(args: argparse.Namespace) -> int:
    if args.design is not None and Path(args.design).suffix.lower() in CAD_SUFFIXES:
        if args.method != "all":
            raise CLIError(f"--method {args.method}: applies to a design, not a CAD file")
        return _weigh_file(args)
    if args.density is not None or args.part_density:
        raise CLIError("--density/--part-density apply to a STEP/STL file only")
    design = load_design_args(args)
    clutch = design.clutch
    wanted = INERTIA_METHODS[1:] if args.method == "all" else (args.method,)
    # the chord height bounds the mesh only: --method analytic|brep never reads it
    tol = tolerance(args, clutch) if "mesh" in wanted else None
    cad = bool(set(wanted) - {"analytic"})
    # the CAD solids (build123d, seconds) only for the methods that weigh them, under a bar
    # of the steps with its estimate (issue 40: a wait over ~2 s says how long)
    with bar(1 + len(wanted), "inertia", "step", enabled=cad) as done:
        reps, envelope = design_inertia(design, wanted, tol, done)
    out: dict[str, Any] = {k: _method(r) for k, r in reps.items()}
    # the clutch's mass by the most exact method run (the B-rep, else the first)
    out["clutch_mass_kg"] = reps.get("brep", reps[wanted[0]]).clutch_mass
    out["envelope_m"] = list(envelope)
    out["tolerance_mm"] = args.tolerance_mm
    if args.json:
        print_json(out)
        return 0
    print(f"{'method':<9} {'rotor inertia':>16} {'rotor mass':>11} {'clutch mass':>12}")
    for k, r in reps.items():
        print(
            f"{k:<9} {r.rotor_inertia * 1e7:>11.5f} g·cm² {r.rotor_mass * 1e3:>8.3f} g "
            f"{r.clutch_mass * 1e3:>9.3f} g"
        )
        for note in r.notes:
            print(f"          note: {note}")
    d, length = envelope
    print(f"envelope: Ø {d * 1e3:.2f} mm × {length * 1e3:.2f} mm (rotor = output drums + shaft)")
    return 0


def _densities(
    args: argparse.Namespace, names: list[str], optional: bool = False, hint: str = ""
) -> dict[str, float]:
    """Density of each part named on the command line (``--part-density``, else
    ``--density``); with ``optional`` (a sidecar has the rest) a part without one is left
    out instead of refused."""
    from mrclutch.weigh import DENSITY_RANGE  # a CAD file's, as _weigh_file's

    per: dict[str, float] = {}
    for item in args.part_density:
        name, sep, val = item.partition("=")
        try:
            rho = float(val)
        except ValueError:
            rho = math.nan
        if not sep or not name:
            raise ParameterError(f"--part-density {item!r}: expected NAME=KG_M3")
        per[name] = check_range(f"--part-density {name}", rho, *DENSITY_RANGE, " kg/m³")
    unknown = sorted(set(per) - set(names))
    if unknown:
        raise ParameterError(
            f"--part-density {unknown[0]}: no such part; the file has {', '.join(names)}"
        )
    out: dict[str, float] = {}
    for n in names:
        if n in per:
            out[n] = per[n]
        elif args.density is not None:
            out[n] = check_range("--density", args.density, *DENSITY_RANGE, " kg/m³")
        elif optional:
            continue
        else:
            raise ParameterError(
                f"part {n}: no density; give --density or --part-density {n}=… "
                + (hint or "(or keep the export's <stem>.materials.json beside the STEP)")
            )
    return out


def _weigh_file(args: argparse.Namespace) -> int:
    # a CAD file's weighing (the STEP reader, the sidecar): not a design's imports
    from mrclutch.weigh import load_stl, output_rotor, read_step, stl_hint, weigh_step, weigh_stl

    path = Path(args.design)
    if args.preset is not None:
        raise CLIError("give either a CAD file or --preset, not both")
    results: dict[str, dict[str, Any]] = {}
    if path.suffix.lower() == ".stl":
        mesh = load_stl(path)
        name = path.stem
        rho = _densities(args, [name], hint=stl_hint(path))[name]
        results[name] = weigh_stl(mesh, name, rho, args.axis)
        method = "mesh"
    else:
        shapes, side = read_step(path)
        dens = _densities(args, list(shapes), optional=side is not None)
        results = weigh_step(path, shapes, side, dens, args.axis)
        method = "brep"
    total = {
        "mass_kg": sum(r["mass_kg"] for r in results.values()),
        "inertia_kg_m2": sum(r["inertia_kg_m2"] for r in results.values()),
    }
    out = {"file": str(path), "method": method, "axis": args.axis, "parts": results, "total": total}
    rows = [*results.items(), ("total", total)]
    label, rotor = output_rotor(results, list(total))
    if rotor:  # the tool's own part names: the output rotor too
        out["output_rotor"] = rotor
        rows.append((label, rotor))
    if args.json:
        print_json(out)
        return 0
    print(f"{path} ({method}, axis {args.axis} through the origin, lengths in mm)")
    for name, r in rows:
        print(f"  {name:<12} {r['mass_kg'] * 1e3:10.4f} g  {r['inertia_kg_m2'] * 1e7:12.5f} g·cm²")
    return 0
