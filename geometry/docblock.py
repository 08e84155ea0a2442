"""Generated blocks in the docs: Markdown between two markers that a command rewrites
(``--write``) and a test compares with what the command prints, so the doc cannot drift.

Used by ``python -m magnetics.materials_table`` (docs/materials.md) and
``python -m mrclutch.docs_architecture`` (docs/architecture.md).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

from geometry.atomic import write_text


def block(begin: str, end: str, command: str, body: str) -> str:
    """The block the doc holds: its markers, the command that writes it, then ``body``."""
    return f"{begin}\n`{command}`:\n\n{body}\n{end}"


def replaced(text: str, begin: str, end: str, new: str) -> str:
    """``text`` with its marked block replaced by ``new``; ValueError without markers."""
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        raise ValueError(f"no {begin} … {end} block")
    return text[:i] + new + text[j + len(end) :]


def main(argv: list[str] | None, prog: str, doc: Path, body: Callable[[], str],
         rewrite: Callable[[str], str]) -> int:  # fmt: skip
    """Print ``body()``, or rewrite the block in ``doc`` (``--write``): exit 2 with one line
    when the doc cannot be read, written or has no markers."""
    ap = argparse.ArgumentParser(prog=prog)
    ap.add_argument("--write", action="store_true", help=f"rewrite the block in {doc.name}")
    args = ap.parse_args(argv)
    if not args.write:
        sys.stdout.write(body() + "\n")
        return 0
    try:
        write_text(doc, rewrite(doc.read_text(encoding="utf-8")))
    except (OSError, ValueError) as e:
        print(f"{prog}: {doc.name}: {e}", file=sys.stderr)
        return 2
    print(doc)
    return 0
