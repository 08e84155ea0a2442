"""Helpers shared by the command modules: design selection, JSON output, atomic files
(the options and the JSON output from ``mrclutch.cli.options``, which loads no design)."""

from __future__ import annotations

import argparse

from geometry.atomic import atomic_path
from geometry.params import DrumClutch
from mrclutch.cli.errors import CLIError
from mrclutch.cli.jsonio import to_jsonable
from mrclutch.cli.options import add_design_args, print_json
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
