"""Hand-offs to the next tool in the chain: ``export --format femm|onelab|dxf|drawing``
(called by ``mrclutch export``), ``mrclutch tables --export DIR`` (the material
library as CSV) and ``mrclutch device DESIGN --out FILE.json`` (what a haptic rendering
framework clamps its commands to). docs/handoff.md.

Every file goes through the output layer (geometry.atomic). ezdxf and matplotlib load
only when a DXF or a drawing is written; the drawing (~2 s, most of it matplotlib's import)
under a bar of its two steps on stderr.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from geometry.atomic import atomic_path, write_text
from geometry.validation import check_range
from mrclutch.cli.commands._common import add_design_args, load_design_args
from mrclutch.cli.errors import CLIError
from mrclutch.cli.jsonio import to_jsonable
from mrclutch.cli.longjobs import announce
from mrclutch.cli.progress import bar
from mrclutch.handoff import (
    MAP_COLUMNS,
    device_description,
    draw_section,
    dxf_text,
    material_tables,
    solver_files,
    torque_map,
)
from mrclutch.torque_curves import FEM_SIZE, fem_seconds


def register(sub: Any) -> None:
    p = sub.add_parser(
        "tables",
        help="the material library as CSV tables (B-H, yield stress, viscosity, "
        "hysteresis, fluid life)",
        description="Write DIR/<material>_bh.csv (B-H of every magnetic material), "
        "DIR/<fluid>_tau_y.csv (Carlson's yield stress against H), DIR/<fluid>_viscosity.csv "
        "(off-state viscosity against temperature), DIR/<fluid>_tau_y_temperature.csv "
        "(yield stress against temperature), DIR/hysteresis.csv (each steel's coercivity and "
        "remanence), DIR/fluids.csv (each fluid's tau_y(T) coefficient and lifetime "
        "dissipated energy) and DIR/materials.csv (the index: kind, density, the tables of "
        "each). Units are in the column names; each file starts with '# ' lines naming its "
        "source, and an 'unverified' column names the values not read in a source "
        "(docs/handoff.md).",
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
    out = Path(args.out)
    name = design.name or "clutch"
    written: list[Path] = []
    if args.format in ("femm", "onelab"):
        current = design.current_limit if args.current is None else args.current
        current = check_range("--current", current, -1e4, 1e4, " A")
        for fname, text in solver_files(design, args.format, current, name).items():
            written.append(write_text(out / fname, text))
        print(f"coil: {design.clutch.coil_turns} turns at {current:g} A")
    elif args.current is not None:
        raise CLIError("--current: applies to --format femm or onelab only")
    elif args.format == "dxf":
        written.append(write_text(out / f"{name}.dxf", dxf_text(design)))
    else:  # ~2 s, most of it matplotlib's import: a bar of the two (issue 40)
        path = out / f"{name}.svg"
        with bar(2, "export", "step", not args.no_progress) as done, atomic_path(path) as tmp:
            done(0, "export: loading matplotlib")
            _load_matplotlib()
            done(1, f"export: drawing {path}")
            draw_section(design, str(tmp))
            done(2)
        written.append(path)
    for w in written:
        print(w)
    return 0


def _load_matplotlib() -> None:
    """Import matplotlib's drawing machinery (pyplot: ≈ 1 s of CPU) as a bar's first step."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot


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


def _floats(option: str, text: str) -> list[float]:
    try:
        vals = [float(x) for x in text.split(",")]
    except ValueError:
        raise CLIError(f"{option} {text!r}: give numbers separated by commas") from None
    if not vals or not all(math.isfinite(v) for v in vals):
        raise CLIError(f"{option} {text!r}: give finite numbers separated by commas")
    return vals


def write_torque_map(args: argparse.Namespace, currents: Any) -> int:
    """``mrclutch torque --map FILE``: the map (mrclutch.handoff.torque_map) as CSV or
    Parquet, by the file's suffix, through the output layer (its options: the torque
    command's ``add_map_args``, mrclutch.cli.commands.magnetics)."""
    path = Path(args.map)
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".parquet"):
        raise CLIError(f"--map {args.map}: the file must end in .csv or .parquet")
    if args.method not in ("network", "circuit", "fem"):
        raise CLIError(f"--map: --method {args.method!r}: give network, circuit or fem")
    if args.json or args.plot:
        raise CLIError("--map: not with --json or --plot (the map is the output)")
    speeds = _floats("--map-speeds-rpm", args.map_speeds_rpm)
    temps = _floats("--map-temperatures-C", args.map_temperatures_C)
    design = load_design_args(args)
    if args.method == "fem" and len(currents) > 1:  # the yield is solved once per current
        announce("torque", f"{len(currents)} FEM solves at {FEM_SIZE * 1e3:g} mm",
                 fem_seconds(design.section(), len(currents)),
                 "the FEM's measured rate per grid node, magnetics.fem.grid.SECONDS_PER_NODE",
                 args.yes)  # fmt: skip
    cols = torque_map(design, currents, speeds, temps, method=args.method)
    if suffix == ".csv":
        rows = zip(*(cols[c] for c in MAP_COLUMNS), strict=True)
        body = ",".join(MAP_COLUMNS) + "\n"
        body += "".join(",".join(f"{x:.10g}" for x in r) + "\n" for r in rows)
        write_text(path, body)
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.table({c: cols[c] for c in MAP_COLUMNS})
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)
    print(f"{path}  ({len(cols['current_A'])} rows: {', '.join(MAP_COLUMNS)})")
    return 0
