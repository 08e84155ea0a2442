"""Citations resolve inside the repository.

* Every citation key in a comment, a docstring or a doc is an entry of docs/references.md.
* Every entry of docs/references.md is cited somewhere else in the repository.
* No Python, Markdown or TOML file names a path outside the repository (the shared notes
  the data first came from, or an absolute checkout path).

A citation key is a lowercase word of five or more characters, digits and hyphens in
square brackets, in prose: ``[lebel]``, ``[femm-matlib]``, ``[carlson-jolly2000]``. Not a
key: units and short indices (``[m]``, ``[kg]``, ``[5]``), an index ``a[name]``, code in
backticks, a TOML table header (a line starting with ``[``), ``type: ignore[code]``, and
anything inside Markdown code fences or outside Python comments and docstrings.
"""

from __future__ import annotations

import io
import re
import tokenize
from collections.abc import Iterable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REFS = ROOT / "docs" / "references.md"
KEY = re.compile(r"(?<![\w`])\[([a-z][a-z0-9-]{4,})\](?!`)")
ENTRY = re.compile(r"^### \[([a-z][a-z0-9-]{4,})\]", flags=re.M)
# Paths outside the repository; built from parts so that this file does not match itself.
OUTSIDE = re.compile("|".join(re.escape(s) for s in ("shared" + "/", "/" + "work/")))
SKIP_DIRS = {"__pycache__", "build", "dist", "node_modules", "site-packages"}


def defined_keys(refs: Path = REFS) -> set[str]:
    """The keys of the entries (``### [key]`` headings) of a references page."""
    return set(ENTRY.findall(refs.read_text()))


def _keys(text: str) -> set[str]:
    """Keys in prose: not a TOML table header (a line that starts with [) nor a
    ``type: ignore[code]``."""
    out: set[str] = set()
    for line in text.splitlines():
        if not line.lstrip().startswith("["):
            out |= set(KEY.findall(re.sub(r"ignore\[[^\]]*\]", "", line)))
    return out


def cited_keys(path: Path) -> set[str]:
    """Keys in a Markdown file (outside code blocks, entry headings excepted), or in a
    Python file's comments and docstrings."""
    text = path.read_text()
    if path.suffix == ".md":
        return _keys(ENTRY.sub("", re.sub(r"```.*?```", "", text, flags=re.S)))
    out: set[str] = set()
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        is_doc = tok.type == tokenize.STRING and tok.string.lstrip("rbuRBU")[:3] in ('"""', "'''")
        if tok.type == tokenize.COMMENT or is_doc:
            out |= _keys(tok.string)
    return out


def repo_files(root: Path = ROOT, suffixes: tuple[str, ...] = (".py", ".md")) -> list[Path]:
    """The repository's files with these suffixes, hidden and build folders left out."""
    return sorted(
        f
        for f in root.rglob("*")
        if f.suffix in suffixes
        and f.is_file()
        and not any(
            part.startswith(".") or part in SKIP_DIRS or part.endswith(".egg-info")
            for part in f.relative_to(root).parts[:-1]
        )
    )


def unresolved(files: Iterable[Path], known: set[str], root: Path = ROOT) -> set[str]:
    """``file: [key]`` for every key cited in files that is not an entry."""
    return {f"{p.relative_to(root)}: [{k}]" for p in files for k in cited_keys(p) - known}


def uncited(files: Iterable[Path], known: set[str], refs: Path = REFS) -> set[str]:
    """Entries that no file other than the references page cites."""
    used = set().union(*(cited_keys(p) for p in files if p != refs))
    return known - used


def outside_paths(files: Iterable[Path], root: Path = ROOT) -> list[str]:
    """``file:line`` for every line that names a path outside the repository."""
    return [
        f"{p.relative_to(root)}:{i}"
        for p in files
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if OUTSIDE.search(line)
    ]


def test_every_cited_key_is_in_the_references() -> None:
    known = defined_keys()
    assert {"lebel", "materials", "femm-matlib", "lord-mrf132dg", "carlson"} <= known
    missing = unresolved(repo_files(), known)
    assert not missing, "cited but not in docs/references.md:\n" + "\n".join(sorted(missing))


def test_every_reference_is_cited() -> None:
    idle = uncited(repo_files(), defined_keys())
    assert not idle, f"entries of docs/references.md that nothing cites: {sorted(idle)}"


def test_nothing_points_outside_the_repository() -> None:
    bad = outside_paths(repo_files(suffixes=(".py", ".md", ".toml")))
    assert not bad, "paths outside the repository:\n" + "\n".join(bad)


def test_the_checks_catch_planted_faults(tmp_path: Path) -> None:
    refs = tmp_path / "references.md"
    refs.write_text("### [lebel]\nL.-P. Lebel et al.\n\n### [unused-entry]\nNobody.\n")
    code = tmp_path / "m.py"
    code.write_text(
        '"""Doc [nosuchsource].\n\n[sweep]\n"""\n'
        "x = a[index]  # [lebel], [m], [5]; type: ignore[no-any-return]\n"
        's = "[stringvalue]"\n'
    )
    doc = tmp_path / "d.md"
    outside = "../" + "shared" + "/paper"  # in parts, or this file would name it
    doc.write_text(f"Cites [lebel] and `[codekey]`.\n```\n[fencedkey]\n```\nSee {outside}.\n")
    known = defined_keys(refs)
    assert known == {"lebel", "unused-entry"}
    assert cited_keys(code) == {"nosuchsource", "lebel"}
    assert cited_keys(doc) == {"lebel"}
    assert cited_keys(refs) == set()
    assert unresolved([code, doc], known, tmp_path) == {"m.py: [nosuchsource]"}
    assert uncited([refs, code, doc], known, refs) == {"unused-entry"}
    assert outside_paths([code, doc, refs], tmp_path) == ["d.md:5"]
    assert repo_files(tmp_path) == [doc, code, refs]
