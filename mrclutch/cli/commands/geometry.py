"""``export``, ``inertia`` and ``view``: the clutch as CAD, its mass and inertia, a 3-D view.

Nothing heavy at module level (``mrclutch --help`` imports this): build123d, trimesh and
pyvista are imported by the handlers.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from geometry.cad import brep_volume_mm3, check_tolerance, material_solids
from geometry.export import (
    export_clutch,
    read_materials,
    read_step_parts,
    sidecar_path,
    step_solids,
)
from geometry.mass import (
    analytic_mass,
    brep_mass,
    check_mesh,
    check_shells,
    mesh_mass,
    weigh_mesh,
    weigh_shape,
)
from geometry.materials import DENSITY_RANGE
from geometry.params import DrumClutch
from geometry.reading import check_regular
from geometry.section import OUTPUT_PARTS, build_section
from geometry.validation import ParameterError, check_choice, check_positive, check_range
from mrclutch.cli.commands._common import add_design_args, load_clutch, load_design_args, print_json
from mrclutch.cli.commands.handoff import export_handoff
from mrclutch.cli.errors import CLIError
from mrclutch.cli.progress import bar
from mrclutch.cli.view import screenshot, show

CAD_SUFFIXES = (".step", ".stp", ".stl")
DEFAULT_TOLERANCE_MM = 0.01


def register(sub: Any) -> None:
    p = sub.add_parser(
        "export",
        help="write clutch.step and one STL per part",
        description="Write DIR/clutch.step (the assembly, one solid per material), "
        "DIR/clutch.materials.json (each solid's material and density: `mrclutch inertia "
        "DIR/clutch.step` weighs it) and DIR/<part>.stl (one mesh per part, mm).",
    )
    add_design_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    _tol(p)
    p.add_argument(
        "--format",
        default="step",
        help="step (default: the CAD above), femm (DIR/NAME.fem + NAME.lua: FEMM 4.2), onelab "
        "(DIR/NAME.geo + NAME.pro: Gmsh + GetDP), dxf (DIR/NAME.dxf: the r-z section, a layer "
        "per part and material) or drawing (DIR/NAME.svg: dimensioned, with the [process] "
        "tolerances); NAME is the design's name (docs/handoff.md)",
    )
    p.add_argument(
        "--current",
        type=float,
        default=None,
        metavar="A",
        help="femm, onelab: the coil current (default: the design's current limit)",
    )
    p.set_defaults(func=cmd_export)

    p = sub.add_parser(
        "inertia",
        help="rotor inertia and masses (analytic, mesh, brep), or weigh a STEP/STL file",
        description="With a design (DESIGN.toml or --preset): the three methods compared. "
        "With FILE.step|FILE.stl (mm): mass and inertia about an axis through the origin.",
    )
    add_design_args(p)
    p.add_argument("--json", action="store_true", help="print JSON")
    _tol(p)
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

    p = sub.add_parser("view", help="3-D view cut in half; --screenshot works headless")
    add_design_args(p)
    p.add_argument("--screenshot", metavar="FILE.png", help="render off screen into a PNG")
    p.add_argument(
        "--tolerance-mm",
        type=float,
        default=None,
        help="chord height of the view, mm (default: one screen pixel of the clutch)",
    )
    p.set_defaults(func=cmd_view)


def _tol(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--tolerance-mm",
        type=float,
        default=DEFAULT_TOLERANCE_MM,
        help=f"mesh chord height, mm (default {DEFAULT_TOLERANCE_MM})",
    )


def _tolerance(args: argparse.Namespace, clutch: DrumClutch) -> float:
    """``--tolerance-mm`` in metres, bounded below relative to the clutch (memory)."""
    tol = check_positive("--tolerance-mm", args.tolerance_mm, " mm") * 1e-3
    return check_tolerance("--tolerance-mm", tol, clutch, scale=1e3)


EXPORT_FORMATS = ("step", "femm", "onelab", "dxf", "drawing")
INERTIA_METHODS = ("all", "analytic", "mesh", "brep")


def cmd_export(args: argparse.Namespace) -> int:
    check_choice("--format", args.format, EXPORT_FORMATS)
    if args.format != "step":
        return export_handoff(args)
    design = load_design_args(args)
    clutch = design.clutch
    res = export_clutch(clutch, args.out, _tolerance(args, clutch), materials=design.materials)
    print(f"{res.step}")
    print(f"{res.materials}  (material and density of every solid: mrclutch inertia reads it)")
    for name, path in res.stl.items():
        print(f"{path}  ({res.stl_triangles[name]} triangles)")
    for note in res.notes:
        print(f"note: {note}")
    return 0


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
    tol = _tolerance(args, clutch) if "mesh" in wanted else None
    s = build_section(clutch, design.materials)
    cad = bool(set(wanted) - {"analytic"})
    reps = {}
    # the CAD solids (build123d, seconds) only for the methods that weigh them, under a bar
    # of the steps with its estimate (issue 40: a wait over ~2 s says how long)
    with bar(1 + len(wanted), "inertia", "step", enabled=cad) as done:
        solids = material_solids(clutch, s) if cad else None
        done(1, "inertia: CAD solids built" if cad else None)
        for k, m in enumerate(wanted, 2):
            if m == "analytic":
                reps[m] = analytic_mass(s)
            elif m == "mesh":
                reps[m] = mesh_mass(clutch, tol, solids=solids, materials=design.materials)
            else:
                reps[m] = brep_mass(clutch, solids, materials=design.materials)
            done(k)
    out: dict[str, Any] = {k: _method(r) for k, r in reps.items()}
    # the clutch's mass by the most exact method run (the B-rep, else the first)
    out["clutch_mass_kg"] = reps.get("brep", reps[wanted[0]]).clutch_mass
    out["envelope_m"] = list(s.envelope)
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
    d, length = s.envelope
    print(f"envelope: Ø {d * 1e3:.2f} mm × {length * 1e3:.2f} mm (rotor = output drums + shaft)")
    return 0


def _densities(
    args: argparse.Namespace, names: list[str], optional: bool = False, hint: str = ""
) -> dict[str, float]:
    """Density of each part named on the command line (``--part-density``, else
    ``--density``); with ``optional`` (a sidecar has the rest) a part without one is left
    out instead of refused."""
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


def _weigh_step(args: argparse.Namespace, path: Path) -> dict[str, dict[str, Any]]:
    """Every part of a STEP weighed: densities given on the command line win; the others
    come from the sidecar (``geometry.export.read_materials``) solid by solid."""
    shapes = read_step_parts(path)
    side = read_materials(path)
    dens = _densities(args, list(shapes), optional=side is not None)
    results: dict[str, dict[str, Any]] = {}
    for part, shape in shapes.items():
        if part in dens:
            pm = weigh_shape(shape, dens[part], args.axis)
            results[part] = {"mass_kg": pm.mass, "inertia_kg_m2": pm.inertia,
                             "density_kg_m3": dens[part], "density_from": "option"}  # fmt: skip
            continue
        mass = inertia = 0.0
        materials = []
        for _, name, solid in step_solids({part: shape}):
            entry = (side or {}).get(name)
            if entry is None:
                raise ParameterError(
                    f"{sidecar_path(path)}: no entry for solid {name!r} of {path.name}; "
                    "give --density or --part-density"
                )
            vol = brep_volume_mm3(solid)
            if abs(vol / entry["volume_mm3"] - 1) > 1e-5:
                raise ParameterError(
                    f"{sidecar_path(path)}: solid {name} is {vol:.6g} mm³ in {path.name}, "
                    f"{entry['volume_mm3']:.6g} mm³ in the sidecar (written for another file?)"
                )
            pm = weigh_shape(solid, entry["density_kg_m3"], args.axis)
            mass, inertia = mass + pm.mass, inertia + pm.inertia
            materials.append(str(entry.get("material", name)))
        vol_m3 = brep_volume_mm3(shape) * 1e-9
        results[part] = {"mass_kg": mass, "inertia_kg_m2": inertia,
                         "density_kg_m3": mass / vol_m3, "density_from": "sidecar",
                         "materials": materials}  # fmt: skip
    return results


def _stl_hint(stl: Path) -> str:
    """What the export's materials file beside an STL says about its part (an STL has no
    material): the densities to give, or the STEP that weighs the exact mix."""
    suffix = ".materials.json"
    for side in sorted(stl.parent.glob(f"*{suffix}")):
        step = side.name[: -len(suffix)] + ".step"
        try:
            info = read_materials(side.with_name(step)) or {}
        except ParameterError:
            continue
        mats = sorted({(v["material"], v["density_kg_m3"]) for v in info.values()
                       if v.get("part") == stl.stem})  # fmt: skip
        if mats:
            listed = ", ".join(f"{m} {rho:g} kg/m³" for m, rho in mats)
            mixed = (f"; it mixes materials, so one density is approximate: "
                     f"`mrclutch inertia {step}` weighs each" if len(mats) > 1 else "")  # fmt: skip
            return f"({side.name} beside it lists {stl.stem}: {listed}{mixed})"
    return "(an STL carries no material; the export's <stem>.materials.json lists each part's)"


def _weigh_file(args: argparse.Namespace) -> int:
    path = Path(args.design)
    if args.preset is not None:
        raise CLIError("give either a CAD file or --preset, not both")
    check_regular(path, "CAD file")  # a FIFO, device or directory refused by name; size cap
    results: dict[str, dict[str, Any]] = {}
    if path.suffix.lower() == ".stl":
        import trimesh

        try:
            mesh = trimesh.load_mesh(path, file_type="stl")
        except Exception as exc:  # trimesh raises assorted errors on bad files
            raise ParameterError(f"{path}: not a readable STL ({exc})") from None
        name = path.stem
        rho = _densities(args, [name], hint=_stl_hint(path))[name]
        check_mesh(mesh, name)
        check_shells(mesh, name)
        pm = weigh_mesh(mesh, rho, args.axis)
        results[name] = {"mass_kg": pm.mass, "inertia_kg_m2": pm.inertia, "density_kg_m3": rho}
        method = "mesh"
    else:
        results = _weigh_step(args, path)
        method = "brep"
    total = {
        "mass_kg": sum(r["mass_kg"] for r in results.values()),
        "inertia_kg_m2": sum(r["inertia_kg_m2"] for r in results.values()),
    }
    out = {"file": str(path), "method": method, "axis": args.axis, "parts": results, "total": total}
    rows = [*results.items(), ("total", total)]
    if set(OUTPUT_PARTS) <= set(results):  # the tool's own part names: the output rotor too
        out["output_rotor"] = {k: sum(results[p][k] for p in OUTPUT_PARTS) for k in total}
        rows.append(("+".join(OUTPUT_PARTS), out["output_rotor"]))
    if args.json:
        print_json(out)
        return 0
    print(f"{path} ({method}, axis {args.axis} through the origin, lengths in mm)")
    for name, r in rows:
        print(f"  {name:<12} {r['mass_kg'] * 1e3:10.4f} g  {r['inertia_kg_m2'] * 1e7:12.5f} g·cm²")
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    clutch = load_clutch(args)
    tol = None if args.tolerance_mm is None else _tolerance(args, clutch)
    if args.screenshot:
        print(screenshot(clutch, args.screenshot, tolerance=tol))
    else:
        show(clutch, tolerance=tol)
    return 0
