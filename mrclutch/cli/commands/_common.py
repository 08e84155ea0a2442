"""Helpers shared by the command modules: design selection, JSON output, atomic files."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from geometry.atomic import atomic_path
from geometry.params import DrumClutch
from mrclutch.cli.errors import CLIError
from mrclutch.cli.jsonio import to_jsonable
from mrclutch.cli.paths import OUTPUT_OPTIONS, check_writable
from mrclutch.design import ClutchDesign, design_preset, load_design

__all__ = [
    "OUTPUT_OPTIONS",
    "add_design_args",
    "atomic_path",
    "check_writable",
    "load_clutch",
    "load_design_args",
    "print_json",
    "to_jsonable",
]


def add_design_args(p: argparse.ArgumentParser) -> None:
    """``[DESIGN.toml] [--preset NAME]``: a design file or a named preset (default paper)."""
    p.add_argument(
        "design", nargs="?", metavar="DESIGN.toml", help="design file (lengths in mm, *_mm keys)"
    )
    p.add_argument("--preset", default=None, metavar="NAME", help="named preset (default: paper)")


def load_design_args(args: argparse.Namespace) -> ClutchDesign:
    """The ClutchDesign named by ``add_design_args`` options (default: the paper preset)."""
    if args.design is not None and args.preset is not None:
        raise CLIError("give either a design file or --preset, not both")
    if args.design is not None:
        return load_design(args.design)
    return design_preset(args.preset or "paper")


def load_clutch(args: argparse.Namespace) -> DrumClutch:
    """The DrumClutch named by ``add_design_args`` options."""
    return load_design_args(args).clutch


def print_json(obj: Any) -> None:
    """``obj`` as JSON on standard output, flushed at once: a full disk behind ``> file``
    is one line (``mrclutch.cli.main.GuardedStream``), a closed pipe ends quietly."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")
    sys.stdout.flush()
