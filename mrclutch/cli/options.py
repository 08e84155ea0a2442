"""The options and output every command shares that need no design loaded: a design's
``[DESIGN.toml] [--preset NAME]`` arguments and JSON on standard output
(``mrclutch.cli.commands._common`` re-exports them beside the design's loading; the
catalogue's ``haptic`` and ``compare`` import this alone, issue 40)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from mrclutch.cli.jsonio import to_jsonable


def add_design_args(p: argparse.ArgumentParser) -> None:
    """``[DESIGN.toml] [--preset NAME]``: a design file or a named preset (default paper)."""
    p.add_argument(
        "design", nargs="?", metavar="DESIGN.toml", help="design file (lengths in mm, *_mm keys)"
    )
    p.add_argument("--preset", default=None, metavar="NAME", help="named preset (default: paper)")


def print_json(obj: Any) -> None:
    """``obj`` as JSON on standard output, flushed at once: a full disk behind ``> file``
    is one line (``mrclutch.cli.main.GuardedStream``), a closed pipe ends quietly."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")
    sys.stdout.flush()
