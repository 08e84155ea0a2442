"""Hand-offs to the next tool in the chain: ``export --format femm|onelab|dxf|drawing``
(called by ``mrclutch export``), ``mrclutch materials --export DIR`` (the material
library as CSV) and ``mrclutch device DESIGN --out FILE.json`` (what a haptic rendering
framework clamps its commands to). docs/handoff.md.

Every file goes through the output layer (geometry.atomic). ezdxf and matplotlib load
only when a DXF or a drawing is written.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from geometry.atomic import atomic_path, write_text
from geometry.drawing import section_drawing, section_dxf
from geometry.section import build_section
from geometry.validation import check_range
from magnetics.export.femm import problem, write_fem, write_lua
from magnetics.export.onelab import write_geo, write_pro
from mrclutch.cli.commands._common import add_design_args, load_design_args
from mrclutch.cli.errors import CLIError
from mrclutch.cli.jsonio import to_jsonable
from mrclutch.handoff import device_description, material_tables


def register(sub: Any) -> None:
    p = sub.add_parser(
        "materials",
        help="the material library as CSV tables (B-H, yield stress, viscosity)",
        description="Write DIR/<material>_bh.csv (B-H of every magnetic material), "
        "DIR/<fluid>_tau_y.csv (Carlson's yield stress against H), DIR/<fluid>_viscosity.csv "
        "(off-state viscosity against temperature) and DIR/materials.csv (the index: kind, "
        "density, the source of each table). Units are in the column names; each file "
        "starts with '# ' lines naming its source (docs/handoff.md).",
    )
    p.add_argument("--export", required=True, metavar="DIR", help="output directory")
    p.set_defaults(func=cmd_materials)

    d = sub.add_parser(
        "device",
        help="the device description a haptic rendering framework clamps its commands to",
        description="Write the design's device description (JSON, schema in docs/handoff.md): "
        "the largest force at the hand, K_max, the stable and passive (K, B) region as a "
        "polygon, the damping range, the bandwidth at each K, and the update rate and "
        "delay assumed.",
    )
    add_design_args(d)
    d.add_argument("--out", required=True, metavar="FILE.json", help="output JSON file")
    d.set_defaults(func=cmd_device)


def export_handoff(args: argparse.Namespace) -> int:
    """``mrclutch export --format femm|onelab|dxf|drawing``: DIR/NAME.* (module docstring)."""
    design = load_design_args(args)
    section = build_section(design.clutch, design.materials)
    out = Path(args.out)
    name = design.name or "clutch"
    written: list[Path] = []
    if args.format in ("femm", "onelab"):
        current = design.current_limit if args.current is None else args.current
        current = check_range("--current", current, -1e4, 1e4, " A")
        p = problem(section, current, name)
        if args.format == "femm":
            written += [
                write_text(out / f"{name}.fem", write_fem(p)),
                write_text(out / f"{name}.lua", write_lua(p)),
            ]
        else:
            written += [
                write_text(out / f"{name}.geo", write_geo(p)),
                write_text(out / f"{name}.pro", write_pro(p)),
            ]
        print(f"coil: {section.clutch.coil_turns} turns at {current:g} A")
    elif args.current is not None:
        raise CLIError("--current: applies to --format femm or onelab only")
    elif args.format == "dxf":
        written.append(write_text(out / f"{name}.dxf", section_dxf(section)))
    else:
        path = out / f"{name}.svg"
        with atomic_path(path) as tmp:
            section_drawing(section, str(tmp), design.process.tolerance, design.process.runout)
        written.append(path)
    for w in written:
        print(w)
    return 0


def cmd_materials(args: argparse.Namespace) -> int:
    out = Path(args.export)
    for fname, text in material_tables().items():
        print(write_text(out / fname, text))
    return 0


def cmd_device(args: argparse.Namespace) -> int:
    design = load_design_args(args)
    desc = device_description(design)
    text = json.dumps(to_jsonable(desc), indent=2) + "\n"
    print(write_text(args.out, text))
    return 0
