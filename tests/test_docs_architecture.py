"""docs/architecture.md cannot drift from the code: its module map is generated
(``python -m mrclutch.docs_architecture --write``), every module says in its docstring the
one concept it holds, and every path and dotted name the hand-written parts cite exists."""

from __future__ import annotations

import importlib
import re

import pytest

from mrclutch import docs_architecture as da

TEXT = da.DOC.read_text(encoding="utf-8")
TICKED = sorted(set(re.findall(r"`([^`\s]+)`", TEXT)))
PATHS = [
    t
    for t in TICKED
    if re.fullmatch(r"(geometry|magnetics|mrclutch|benchmarks|docs|tests)/[\w/.-]+", t)
]
DOTTED = [t for t in TICKED if re.fullmatch(r"(geometry|magnetics|mrclutch)(\.\w+)+", t)]


def test_the_doc_holds_the_generated_map() -> None:
    """Regenerate with ``python -m mrclutch.docs_architecture --write``."""
    assert da.block() in TEXT
    assert da.replaced(TEXT) == TEXT


def test_every_module_says_what_it_holds() -> None:
    empty = [name for name, path in da.modules().items() if not da.summary(path)]
    assert empty == []


def test_the_map_has_a_row_per_module_in_layer_order() -> None:
    rows = [r for r in da.table().splitlines()[2:]]
    assert len(rows) == len(da.modules())
    layers = [da.LAYER_NAMES.index(r.split(" | ")[0].lstrip("| ")) for r in rows]
    assert layers == sorted(layers)
    assert any(
        "`mrclutch/verdict.py`" in r and r.startswith("| mrclutch (application)") for r in rows
    )
    assert any("`magnetics/network/solve.py`" in r and r.startswith("| magnetics |") for r in rows)


def test_summary_is_the_first_sentence_and_keeps_abbreviations(tmp_path) -> None:
    f = tmp_path / "m.py"
    f.write_text('"""The 2-DOF model ([lebel] Eq. 1–4): a|b. Second sentence.\n\nMore."""\n')
    assert da.summary(f) == "The 2-DOF model ([lebel] Eq. 1–4): a\\|b"
    f.write_text('"""' + "word " * 40 + '"""\n')
    s = da.summary(f)
    assert s.endswith(" …") and len(s) <= da._WIDTH + 2


@pytest.mark.parametrize("path", PATHS)
def test_every_cited_path_exists(path: str) -> None:
    assert (da.ROOT / path).exists(), f"docs/architecture.md cites {path}, which is not there"


@pytest.mark.parametrize("name", DOTTED)
def test_every_cited_dotted_name_exists(name: str) -> None:
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            assert hasattr(obj, attr), f"docs/architecture.md cites {name}: no {attr}"
            obj = getattr(obj, attr)
        return
    pytest.fail(f"docs/architecture.md cites {name}: no such module")


def test_the_block_writer_rewrites_only_its_block_and_refuses_a_doc_without_one(
    tmp_path, capsys
) -> None:
    from geometry import docblock

    doc = tmp_path / "d.md"
    doc.write_text("head\n<!-- b -->\nold\n<!-- /b -->\ntail\n")
    new = docblock.block("<!-- b -->", "<!-- /b -->", "cmd --write", "| x |")
    assert new == "<!-- b -->\n`cmd --write`:\n\n| x |\n<!-- /b -->"

    def rewrite(t: str) -> str:
        return docblock.replaced(t, "<!-- b -->", "<!-- /b -->", new)

    assert docblock.main(["--write"], "prog", doc, lambda: "| x |", rewrite) == 0
    assert doc.read_text() == f"head\n{new}\ntail\n"
    assert docblock.main([], "prog", doc, lambda: "| x |", rewrite) == 0
    assert capsys.readouterr().out.endswith("| x |\n")
    doc.write_text("no markers\n")
    assert docblock.main(["--write"], "prog", doc, lambda: "", rewrite) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "d.md: no <!-- b --> … <!-- /b --> block" in err
    assert doc.read_text() == "no markers\n"
