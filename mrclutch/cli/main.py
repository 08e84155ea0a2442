"""Thin command line over the library. ``mrclutch COMMAND --help`` for each command.

Each command lives in a module of ``mrclutch.cli.commands`` that exposes
``register(subparsers)``; those modules import nothing heavy at module level, so
``mrclutch --help`` and the analytic commands start fast. Bad input ends in one line on
stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from geometry.validation import ParameterError
from mrclutch import __version__
from mrclutch.cli.commands._common import OUTPUT_OPTIONS, check_writable
from mrclutch.cli.errors import CLIError

#: Command modules, in the order their commands appear in ``--help``.
COMMAND_MODULES: tuple[str, ...] = (
    "mrclutch.cli.commands.haptic",
    "mrclutch.cli.commands.geometry",
    "mrclutch.cli.commands.magnetics",
    "mrclutch.cli.commands.design",
    "mrclutch.cli.commands.scaling",
    "mrclutch.cli.commands.fidelity",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mrclutch",
        description="Design MR drum clutches for haptic devices: CAD, inertia, torque, "
        "drag and the haptic consequences (SI units; lengths in mm where marked _mm).",
    )
    parser.add_argument("--version", action="version", version=f"mrclutch {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # a command module not written yet
                continue
            raise
        module.register(sub)
    for command in sub.choices.values():  # which outputs each command writes, and their kind
        outs = {a.dest: a.metavar == "DIR" for a in command._actions if a.dest in OUTPUT_OPTIONS}
        command.set_defaults(output_options=outs)
    return parser


def check_outputs(args: argparse.Namespace) -> None:
    """Every output option given can be written: checked before any work starts."""
    for dest, folder in getattr(args, "output_options", {}).items():
        value = getattr(args, dest, None)
        if value is not None:
            check_writable(f"--{dest}", value, folder)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        check_outputs(args)
        return int(args.func(args) or 0)
    except (ParameterError, CLIError) as exc:
        print(f"mrclutch {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"mrclutch {args.command}: interrupted", file=sys.stderr)
        return 130
    except ImportError as exc:
        # Ctrl-C or SIGTERM while a C extension initialises (OpenCascade, VTK) surfaces as
        # "ImportError: initialization failed" caused by the KeyboardInterrupt
        if isinstance(exc.__cause__ or exc.__context__, KeyboardInterrupt):
            print(f"mrclutch {args.command}: interrupted", file=sys.stderr)
            return 130
        raise
