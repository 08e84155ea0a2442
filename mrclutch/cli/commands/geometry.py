"""``export``, ``inertia`` and ``view``: the clutch as CAD, its mass and inertia, a 3-D view.

Nothing heavy at module level (``mrclutch --help`` imports this): build123d, trimesh and
pyvista are imported by the handlers. ``inertia`` lives in ``mrclutch.cli.commands.inertia``
(registered here too, so ``--help`` keeps its order), which ``mrclutch inertia`` imports
alone.
"""

from __future__ import annotations

import argparse
from typing import Any

from geometry.validation import check_choice
from mrclutch.cli.commands._common import add_design_args, load_clutch, load_design_args
from mrclutch.cli.commands.handoff import export_handoff
from mrclutch.cli.commands.inertia import DEFAULT_TOLERANCE_MM, add_tolerance, tolerance
from mrclutch.cli.commands.inertia import register as register_inertia
from mrclutch.cli.errors import CLIError
from mrclutch.cli.progress import bar
from mrclutch.cli.view import screenshot, show
from mrclutch.solids import export_cad


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
    add_tolerance(p)
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
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(func=cmd_export)

    register_inertia(sub)  # between export and view, the order of --help

    p = sub.add_parser("view", help="3-D view cut in half; --screenshot works headless")
    add_design_args(p)
    p.add_argument("--screenshot", metavar="FILE.png", help="render off screen into a PNG")
    p.add_argument(
        "--tolerance-mm",
        type=float,
        default=None,
        help="chord height of the view, mm (default: one screen pixel of the clutch)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(func=cmd_view)


EXPORT_FORMATS = ("step", "femm", "onelab", "dxf", "drawing")


def cmd_export(args: argparse.Namespace) -> int:
    check_choice("--format", args.format, EXPORT_FORMATS)
    if args.format != "step":  # each option applies to its formats only, never ignored
        if args.tolerance_mm != DEFAULT_TOLERANCE_MM:
            raise CLIError("--tolerance-mm: applies to --format step only (the STL chord)")
        return export_handoff(args)
    if args.current is not None:
        raise CLIError("--current: applies to --format femm or onelab only")
    design = load_design_args(args)
    tol = tolerance(args, design.clutch)
    # a bar of its two steps with its estimate (issue 40: ~8 s idle, silent before): the
    # CAD kernel's import (≈ 6 s of CPU), then the solids, the files and the read-back
    with bar(2, "export", "step", not args.no_progress) as done:
        done(0, "export: loading the CAD kernel (build123d)")
        _load_cad()
        done(1, "export: the solids, clutch.step, the STL files, clutch.step read back")
        res = export_cad(design, args.out, tol)
        done(2)
    print(f"{res.step}")
    print(f"{res.materials}  (material and density of every solid: mrclutch inertia reads it)")
    for name, path in res.stl.items():
        print(f"{path}  ({res.stl_triangles[name]} triangles)")
    for note in res.notes:
        print(f"note: {note}")
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    clutch = load_clutch(args)
    tol = None if args.tolerance_mm is None else tolerance(args, clutch)
    # a bar with its estimate (issue 40: ~11 s idle, silent before): the CAD kernel imported,
    # then the solids tessellated and rendered (a window: it opens after the bar)
    with bar(2 if args.screenshot else 1, "view", "step", not args.no_progress) as done:
        done(0, "view: loading the CAD kernel (build123d)")
        _load_cad()
        if args.screenshot:
            done(1, f"view: the solids tessellated and rendered into {args.screenshot}")
            shot = screenshot(clutch, args.screenshot, tolerance=tol)
        done(2 if args.screenshot else 1)
    if args.screenshot:
        print(shot)
    else:
        show(clutch, tolerance=tol)
    return 0


def _load_cad() -> None:
    """Import the CAD kernel (build123d: ≈ 6 s of CPU) as the first step of a bar; the
    steps after find it loaded."""
    import build123d  # noqa: F401
