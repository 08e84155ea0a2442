"""docs/architecture.md's module map, generated from the source so it cannot drift.

    python -m mrclutch.docs_architecture            # print the map (Markdown)
    python -m mrclutch.docs_architecture --write    # rewrite it in docs/architecture.md

The map sits between ``<!-- module-map -->`` and ``<!-- /module-map -->``: one row per
module of geometry/, magnetics/ and mrclutch/, in layer order (the layers of
tests/test_architecture.py), with the first sentence of its docstring — the one concept
the module holds. tests/test_docs_architecture.py checks the doc holds what this prints,
that every module's docstring says what it holds, and that every path and dotted name the
doc's hand-written tables ("where does a change go", the data flow of ``evaluate``) cite
exists.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from geometry import docblock

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "architecture.md"
BEGIN, END = "<!-- module-map -->", "<!-- /module-map -->"
PACKAGES = ("geometry", "magnetics", "mrclutch")
#: Layer of a module, lowest first (tests/test_architecture.py's LAYERS).
LAYER_NAMES = ("geometry", "magnetics", "mrclutch.haptics", "mrclutch (application)",
               "mrclutch.cli")  # fmt: skip
#: A sentence ends at a full stop before a capital, a backtick, a bracket or the end
#: ("Eq. 3–4" and "Fig. 7b" do not end one).
_SENTENCE = re.compile(r"^(.+?\.)(\s+(?=[A-Z`(\[])|$)", re.S)
_WIDTH = 120


def layer_of(module: str) -> int:
    """0 geometry … 4 the command line (the order imports may point down)."""
    if module == "mrclutch.__main__" or module.startswith("mrclutch.cli"):
        return 4
    if module.startswith("mrclutch.haptics"):
        return 2
    return {"geometry": 0, "magnetics": 1, "mrclutch": 3}[module.split(".")[0]]


def modules() -> dict[str, Path]:
    """Every module of the three packages (dotted name → file), sorted by name."""
    out = {}
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(f.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            out[".".join(parts)] = f
    return dict(sorted(out.items()))


def summary(path: Path) -> str:
    """The first sentence of the module's docstring, on one line ("" if it has none)."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    first = doc.strip().split("\n\n")[0].replace("\n", " ")
    first = re.sub(r"\s+", " ", first).strip()
    m = _SENTENCE.match(first)
    text = (m.group(1) if m else first).rstrip(":;.")
    if len(text) > _WIDTH:  # a long first sentence: cut at a word, marked
        text = text[: text.rfind(" ", 0, _WIDTH)].rstrip(",;:") + " …"
    return text.replace("|", "\\|")


def table() -> str:
    """The Markdown module map: layer, module (its file), what it holds."""
    rows = ["| layer | module | what it holds |", "|---|---|---|"]
    for name, path in sorted(modules().items(), key=lambda kv: (layer_of(kv[0]), kv[0])):
        rel = path.relative_to(ROOT).as_posix()
        rows.append(f"| {LAYER_NAMES[layer_of(name)]} | `{rel}` | {summary(path)} |")
    return "\n".join(rows)


def block() -> str:
    """The generated block, with its markers and the command that writes it."""
    return docblock.block(BEGIN, END, "python -m mrclutch.docs_architecture --write", table())


def replaced(text: str) -> str:
    """``text`` with its map block replaced by the current one."""
    return docblock.replaced(text, BEGIN, END, block())


def main(argv: list[str] | None = None) -> int:
    """Print the map, or rewrite it in docs/architecture.md (``--write``)."""
    return docblock.main(argv, "python -m mrclutch.docs_architecture", DOC, table, replaced)


if __name__ == "__main__":
    raise SystemExit(main())
