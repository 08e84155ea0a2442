"""Thin command line over the library. ``mrclutch COMMAND --help`` for each command.

The arguments are parsed before anything heavy is imported: COMMANDS names each command's
module and its one-line summary, ``mrclutch --help`` is built from the table alone (no
numpy, no physics), and a command's module (``mrclutch.cli.commands.*``, exposing
``register(subparsers)``) is imported only when that command runs. Bad input ends in one
line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Collection, Sequence

from mrclutch.cli.errors import CLIError
from mrclutch.cli.paths import OUTPUT_OPTIONS, check_writable

_HAPTIC = "mrclutch.cli.commands.haptic"
_GEOMETRY = "mrclutch.cli.commands.geometry"
_MAGNETICS = "mrclutch.cli.commands.magnetics"
_DESIGN = "mrclutch.cli.commands.design"
#: The command table, in the order of ``--help``: name → (the module that registers and runs
#: it, its one-line summary). The summary is the one ``--help`` lists; the module's own
#: ``add_parser(help=...)`` must say the same (tests/mrclutch/test_cli_lazy.py).
COMMANDS: dict[str, tuple[str, str]] = {
    "haptic": (_HAPTIC, "one actuator + transmission + virtual spring K → haptic metrics"),
    "compare": (_HAPTIC, "the paper's equal-force comparison: MR pair vs Maxon 136206 "
                "(Fig. 7c)"),
    "export": (_GEOMETRY, "write clutch.step and one STL per part"),
    "inertia": (_GEOMETRY, "rotor inertia and masses (analytic, mesh, brep), or weigh a "
                "STEP/STL file"),
    "view": (_GEOMETRY, "3-D view cut in half; --screenshot works headless"),
    "torque": (_MAGNETICS, "torque against coil current (network, circuit or FEM)"),
    "field": (_MAGNETICS, "FEM flux-density map over the section at one current"),
    "evaluate": (_DESIGN, "a clutch design and its haptic consequences, beside the "
                 "equal-force motor"),
    "report": (_DESIGN, "the full report of one design: CAD, views, torque curve, haptic "
               "plots, HTML"),
    "sweep": (_DESIGN, "evaluate a grid or random sample of designs on the fast path (CSV or "
              "Parquet)"),
    "optimize": (_DESIGN, "maximise rendering bandwidth (area, Z-width or transparency) "
                 "under torque, mass, envelope and stability/passivity limits"),
    "scale": ("mrclutch.cli.commands.scaling", "reach k× torque by more drums, longer drums "
              "or a larger diameter (Fig. 7b)"),
    "fidelity": ("mrclutch.cli.commands.fidelity", "speed against accuracy: time and error of "
                 "every method (chart + table)"),
}  # fmt: skip


class _Version(argparse.Action):
    """``--version``: reads the installed version only when asked (mrclutch.__version__)."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str | None = None) -> None:  # fmt: skip
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        print(f"mrclutch {importlib.import_module('mrclutch').__version__}")
        parser.exit()


def build_parser(commands: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The parser. The modules of ``commands`` (None: every command) register their full
    subparsers; every other command is a stub that only carries its summary for ``--help``
    (its module is not imported)."""
    parser = argparse.ArgumentParser(
        prog="mrclutch",
        description="Design MR drum clutches for haptic devices: CAD, inertia, torque, "
        "drag and the haptic consequences (SI units; lengths in mm where marked _mm).",
    )
    parser.add_argument("--version", action=_Version, help="show the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    wanted = {COMMANDS[c][0] for c in (COMMANDS if commands is None else commands)
              if c in COMMANDS}  # fmt: skip
    for name, (module, summary) in COMMANDS.items():
        if name in sub.choices:  # registered with an earlier command of its module
            continue
        if module in wanted:
            importlib.import_module(module).register(sub)
        else:
            sub.add_parser(name, help=summary, add_help=False)
    for command in sub.choices.values():  # which outputs each command writes, and their kind
        outs = {a.dest: a.metavar == "DIR" for a in command._actions if a.dest in OUTPUT_OPTIONS}
        command.set_defaults(output_options=outs)
    return parser


def command_of(argv: Sequence[str]) -> str | None:
    """The command named in ``argv``: its first word not an option (the top-level parser
    has only flags), or None."""
    return next((a for a in argv if not a.startswith("-")), None)


def check_outputs(args: argparse.Namespace) -> None:
    """Every output option given can be written: checked before any work starts."""
    for dest, folder in getattr(args, "output_options", {}).items():
        value = getattr(args, dest, None)
        if value is not None:
            check_writable(f"--{dest}", value, folder)


def main(argv: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = command_of(argv)
    parser = build_parser(() if command is None else (command,))
    args = parser.parse_args(argv)
    # the command's module has imported the physics by now; its input errors are
    # ParameterErrors (geometry.validation), caught here without importing it up front
    user_errors = (CLIError, importlib.import_module("geometry.validation").ParameterError)
    try:
        check_outputs(args)
        return int(args.func(args) or 0)
    except user_errors as exc:
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
