"""Output options checked before any work starts (no numpy, no physics: ``mrclutch.cli.main``
imports it before it knows which command runs)."""

from __future__ import annotations

import importlib
import tempfile
from pathlib import Path

from mrclutch.cli.errors import CLIError

#: Options that name a file or folder the command writes; ``main`` checks them before the
#: work starts (a folder when the option's metavar is DIR, a file otherwise).
OUTPUT_OPTIONS: tuple[str, ...] = ("out", "plot", "screenshot")


def check_writable(option: str, path: str, folder: bool) -> None:
    """Raise a one-line CLIError unless ``path`` can be written as a file (or a folder):
    its nearest existing ancestor is a folder we can create a file in."""
    p = Path(path)
    if p.exists() and not p.is_dir() and not p.is_file():  # a device node, a FIFO, a socket
        # the output layer's rule (imported here, after the command's module: no numpy before)
        layer = importlib.import_module("geometry.atomic")
        try:
            layer.check_target(p)
        except layer.OutputError as exc:
            raise CLIError(f"{option} {exc}") from None
    if p.exists() and p.is_dir() != folder:
        what = "is a directory; give a file name" if p.is_dir() else "is a file, not a folder"
        raise CLIError(f"{option} {path}: {what}")
    here = p if folder else p.parent
    while not here.exists() and here != here.parent:
        here = here.parent
    if not here.is_dir():
        raise CLIError(f"{option} {path}: cannot be created; {here} is not a directory")
    try:  # the only sure test: make a file there (root passes os.access everywhere)
        with tempfile.TemporaryFile(dir=here):
            pass
    except OSError as exc:
        raise CLIError(f"{option} {path}: cannot write in {here} ({exc.strerror})") from None
