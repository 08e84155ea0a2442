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
import os
import sys
import warnings
from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Any, NoReturn, TextIO

from mrclutch.cli.errors import CLIError
from mrclutch.cli.paths import OUTPUT_OPTIONS, check_writable

_HAPTIC = "mrclutch.cli.commands.haptic"
_GEOMETRY = "mrclutch.cli.commands.geometry"
_MAGNETICS = "mrclutch.cli.commands.magnetics"
#: The command table, in the order of ``--help``: name → (the module that registers and runs
#: it, its one-line summary). The summary is the one ``--help`` lists; the module's own
#: ``add_parser(help=...)`` must say the same (tests/mrclutch/test_cli_lazy.py).
COMMANDS: dict[str, tuple[str, str]] = {
    "haptic": (_HAPTIC, "one actuator + transmission + virtual spring K → haptic metrics"),
    "compare": (_HAPTIC, "the paper's equal-force comparison: MR pair vs Maxon 136206 "
                "(Fig. 7c)"),
    "export": (_GEOMETRY, "write clutch.step and one STL per part"),
    "inertia": ("mrclutch.cli.commands.inertia", "rotor inertia and masses (analytic, mesh, "
                "brep), or weigh a STEP/STL file"),
    "view": (_GEOMETRY, "3-D view cut in half; --screenshot works headless"),
    "torque": (_MAGNETICS, "torque against coil current (network, circuit or FEM)"),
    "field": (_MAGNETICS, "FEM flux-density map over the section at one current"),
    "evaluate": ("mrclutch.cli.commands.evaluate", "a clutch design and its haptic "
                 "consequences, beside the equal-force motor"),
    "report": ("mrclutch.cli.commands.report_command", "the full report of one design: CAD, "
               "views, torque curve, haptic plots, HTML"),
    "sweep": ("mrclutch.cli.commands.sweep", "evaluate a grid or random sample of designs on "
              "the fast path (CSV or Parquet)"),
    "optimize": ("mrclutch.cli.commands.optimize", "the trade-offs (a Pareto set: rendering "
                 "bandwidth, transparency, continuous torque, mass) or one objective, under "
                 "the builder's limits"),
    "scale": ("mrclutch.cli.commands.scaling", "reach k× torque by more drums, longer drums "
              "or a larger diameter (Fig. 7b)"),
    "fidelity": ("mrclutch.cli.commands.fidelity", "speed against accuracy: time and error of "
                 "every method (chart + table)"),
    "tables": ("mrclutch.cli.commands.handoff", "the material library as CSV tables (B-H, "
               "yield stress, viscosity, hysteresis, fluid life)"),
    "device": ("mrclutch.cli.commands.handoff", "the device description a haptic rendering "
               "framework clamps its commands to"),
}  # fmt: skip


class _Version(argparse.Action):
    """``--version``: reads the installed version only when asked (mrclutch.__version__)."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str | None = None) -> None:  # fmt: skip
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        print(f"mrclutch {importlib.import_module('mrclutch').__version__}")
        parser.exit()


class OneLineParser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line on stderr, exit 2, as every other
    bad input of the CLI (argparse prints its usage block first; the line names where the
    options are listed instead)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (options: {self.prog} --help)\n")


def build_parser(commands: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The parser. The modules of ``commands`` (None: every command) register their full
    subparsers; every other command is a stub that only carries its summary for ``--help``
    (its module is not imported)."""
    parser = OneLineParser(
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


#: Exit status when standard output is closed early (``mrclutch evaluate --json | head -1``):
#: what a process killed by SIGPIPE reports to the shell (128 + 13).
EXIT_CLOSED_PIPE = 141


class StdoutError(Exception):
    """Standard output could not be written (not a closed pipe: that one is quiet)."""


class GuardedStream:
    """Standard output under the output layer's rule (geometry.atomic): an OSError writing
    it (a full disk behind ``> file``) is one ``StdoutError`` line naming it and the
    reason; a closed pipe stays a BrokenPipeError, which ``main`` ends quietly."""

    def __init__(self, stream: TextIO, name: str = "standard output") -> None:
        self._stream, self._name = stream, name

    def _guard(self, fn: Any, *a: Any) -> Any:
        try:
            return fn(*a)
        except BrokenPipeError:
            raise
        except OSError as exc:
            reason = exc.strerror or type(exc).__name__
            raise StdoutError(f"{self._name}: cannot write ({reason})") from None

    def write(self, s: str) -> int:
        return self._guard(self._stream.write, s)

    def flush(self) -> None:
        self._guard(self._stream.flush)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _silence_stdout(stream: TextIO) -> None:
    """Point file descriptor 1 at /dev/null after a write to it failed, so the
    interpreter's own flush at exit has nowhere to fail again (no "Exception ignored")."""
    try:
        fd = stream.fileno()
    except (OSError, ValueError, AttributeError):  # not a real file (pytest's capture)
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _report_warnings(command: str, caught: list[warnings.WarningMessage]) -> None:
    """Numerical libraries' RuntimeWarnings (overflow in an intermediate step) never reach
    the terminal raw: one line says how many and the first; other warnings are shown as
    usual. (A command that ends in an error drops them: its one line says why.)"""
    numeric = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    for w in caught:
        if not issubclass(w.category, RuntimeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    if numeric:
        first = numeric[0]
        where = f"{Path(first.filename).parent.name}/{Path(first.filename).name}:{first.lineno}"
        print(f"mrclutch {command}: note: {len(numeric)} numerical warning(s) in intermediate "
              f"steps (first: {str(first.message).splitlines()[0]}, {where}); the figures "
              "printed are finite or say why not", file=sys.stderr)  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; its exit status (0, 2 for bad input or an output that cannot be
    written, 130 interrupted, 141 standard output closed early)."""
    real_stdout = sys.stdout
    sys.stdout = GuardedStream(real_stdout)  # type: ignore[assignment]
    try:
        try:
            code = _run(argv)
        except SystemExit:  # argparse's --help, --version and usage errors
            sys.stdout.flush()
            raise
        sys.stdout.flush()
        return code
    except BrokenPipeError:  # the reader went away (| head): the Unix convention is quiet
        _silence_stdout(real_stdout)
        return EXIT_CLOSED_PIPE
    except StdoutError as exc:
        _silence_stdout(real_stdout)
        print(f"mrclutch: error: {exc}", file=sys.stderr)
        return 2
    finally:
        sys.stdout = real_stdout


def _run(argv: Sequence[str] | None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = command_of(argv)
    parser = build_parser(() if command is None else (command,))
    args = parser.parse_args(argv)
    # the command's module has imported the physics by now; its input errors are
    # ParameterErrors (geometry.validation), and a file that cannot be written an
    # OutputError (geometry.atomic, the output layer), caught here without importing them
    # up front
    user_errors = (CLIError, importlib.import_module("geometry.validation").ParameterError,
                   importlib.import_module("geometry.atomic").OutputError)  # fmt: skip
    try:
        check_outputs(args)
        with warnings.catch_warnings(record=True) as caught:
            code = int(args.func(args) or 0)
        _report_warnings(args.command, caught)
        sys.stdout.flush()
        return code
    except StdoutError:
        raise
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
