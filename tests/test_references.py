"""Citations resolve inside the repository: every [key] in a comment, a docstring or a doc
is an entry of docs/references.md, and nothing points outside the repository."""

from __future__ import annotations

import io
import re
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REFS = ROOT / "docs" / "references.md"
# [lebel], [femm-matlib]; not [m], [kg], an index a[name] or code ``[table]``
KEY = re.compile(r"(?<![\w`])\[([a-z][a-z0-9-]{4,})\](?!`)")


def defined_keys() -> set[str]:
    return set(re.findall(r"^### \[([a-z0-9-]+)\]", REFS.read_text(), flags=re.M))


def _keys(text: str) -> set[str]:
    """Keys in prose: not a TOML table header (a line that starts with [) nor a
    ``type: ignore[code]``."""
    out: set[str] = set()
    for line in text.splitlines():
        if not line.lstrip().startswith("["):
            out |= set(KEY.findall(re.sub(r"ignore\[[^\]]*\]", "", line)))
    return out


def cited_keys(path: Path) -> set[str]:
    """Keys in a Markdown file (outside code blocks), or in a Python file's comments and
    docstrings."""
    text = path.read_text()
    if path.suffix == ".md":
        return _keys(re.sub(r"```.*?```", "", text, flags=re.S))
    out: set[str] = set()
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        is_doc = tok.type == tokenize.STRING and tok.string.lstrip("rbuRBU")[:3] in ('"""', "'''")
        if tok.type == tokenize.COMMENT or is_doc:
            out |= _keys(tok.string)
    return out


def sources() -> list[Path]:
    dirs = ("geometry", "magnetics", "mrclutch", "tests", "benchmarks", "examples", "docs")
    files = [f for d in dirs for f in (ROOT / d).rglob("*") if f.suffix in (".py", ".md")]
    return [*files, ROOT / "README.md"]


def test_every_cited_key_is_in_the_references() -> None:
    known = defined_keys()
    assert {"lebel", "materials", "femm-matlib", "lord-mrf132dg", "carlson"} <= known
    missing = {f"{p.relative_to(ROOT)}: [{k}]" for p in sources() for k in cited_keys(p) - known}
    assert not missing, "\n".join(sorted(missing))


def test_nothing_points_outside_the_repository() -> None:
    bad = [
        f"{p.relative_to(ROOT)}:{i}"
        for p in [*sources(), ROOT / "pyproject.toml"]
        if p != Path(__file__)
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if "shared/" in line
    ]
    assert not bad, "\n".join(bad)


def test_a_planted_unknown_key_would_be_caught(tmp_path: Path) -> None:
    f = tmp_path / "m.py"
    f.write_text(
        '"""Doc [nosuchsource].\n\n[sweep]\n"""\n'
        "x = a[index]  # [lebel], [m]; type: ignore[no-any-return]\n"
    )
    assert cited_keys(f) == {"nosuchsource", "lebel"}
    assert "nosuchsource" not in defined_keys()
