"""The material registry's parse, cached across processes (geometry.materials._parsed,
issue 40 item 1): keyed on the files' content, so the cache gives what parsing gives, any
change to a file is read afresh, and a cache that is broken or cannot be written is passed
over."""

import marshal
import os
import shutil
import stat
from pathlib import Path

import pytest

from geometry import materials
from geometry.reading import read_toml


@pytest.fixture
def registry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> list[Path]:
    """A copy of the registry's files and an empty cache folder, both in ``tmp_path``."""
    folder = tmp_path / "data"
    folder.mkdir()
    for p in materials.DATA.glob("*.toml"):
        shutil.copy(p, folder / p.name)
    monkeypatch.setattr(materials, "CACHE", tmp_path / "cache")
    return sorted(folder.glob("*.toml"))


def _no_parse(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*_: object) -> None:
        raise AssertionError("parsed, not read from the cache")

    monkeypatch.setattr(materials, "parse_toml", refuse)


def test_the_cache_gives_what_parsing_gives(registry, monkeypatch) -> None:
    fresh = [(p.name, read_toml(p, "material file")) for p in registry]
    assert materials._parsed(registry) == fresh  # parsed, and written
    assert len(list(materials.CACHE.glob("*.marshal"))) == 1
    _no_parse(monkeypatch)
    again = materials._parsed(registry)
    assert again == fresh
    assert repr(again) == repr(fresh)  # floats to the bit, keys in the file's order


def test_the_registry_is_the_same_from_the_cache(registry, monkeypatch) -> None:
    """What the registry checks and registers from a cached parse is what it registers from
    the files (the library's own files, each through check_record)."""
    materials._parsed(registry)
    _no_parse(monkeypatch)
    for name, rec in materials._parsed(registry):
        assert materials.check_record(rec, name) == dict(materials.RECORDS[name[:-5]])


@pytest.mark.parametrize("change", ["edit", "add", "remove", "rename"])
def test_any_change_to_the_files_is_read_afresh(registry, change) -> None:
    materials._parsed(registry)
    first = registry[0]
    if change == "edit":  # one digit of a density
        text = first.read_text()
        first.write_text(text.replace("density = ", "density = 1", 1))
    elif change == "add":
        shutil.copy(first, first.with_name("zz_extra.toml"))
    elif change == "remove":
        first.unlink()
    else:
        first.rename(first.with_name("zz_" + first.name))
    paths = sorted(first.parent.glob("*.toml"))
    want = [(p.name, read_toml(p, "material file")) for p in paths]
    assert materials._parsed(paths) == want
    assert len(list(materials.CACHE.glob("*.marshal"))) == 2  # one file per content
    if change == "edit":
        assert want[0][1]["density"] != read_toml(materials.DATA / first.name, "m")["density"]


@pytest.mark.parametrize(
    "content",
    [b"", b"not marshal data", marshal.dumps([("x.toml", {})]), marshal.dumps({"a": 1}),
     marshal.dumps([1, 2]), marshal.dumps(None), marshal.dumps([["another content", [], []], []])],
)  # fmt: skip
def test_a_broken_cache_is_passed_over(registry, content) -> None:
    fresh = materials._parsed(registry)
    (cache,) = materials.CACHE.glob("*.marshal")
    cache.write_bytes(content)
    assert materials._parsed(registry) == fresh
    assert marshal.loads(cache.read_bytes())[1] == [rec for _, rec in fresh]  # written again


def test_a_fifo_in_the_caches_place_is_passed_over(registry) -> None:
    """Read through the bounded reader: a FIFO (no writer) is refused, not waited on."""
    fresh = materials._parsed(registry)
    (cache,) = materials.CACHE.glob("*.marshal")
    cache.unlink()
    os.mkfifo(cache)
    assert materials._parsed(registry) == fresh  # parsed; the FIFO is not replaced
    assert stat.S_ISFIFO(cache.lstat().st_mode)


def test_a_cache_that_cannot_be_written_is_passed_over(registry, monkeypatch) -> None:
    blocker = materials.CACHE.parent / "a_file"
    blocker.write_text("")
    monkeypatch.setattr(materials, "CACHE", blocker / "cache")  # mkdir fails: NotADirectory
    assert materials._parsed(registry) == [(p.name, read_toml(p, "m")) for p in registry]


def test_a_bad_file_is_still_one_line_naming_it(registry) -> None:
    registry[0].write_text("name = [unclosed")
    with pytest.raises(materials.ParameterError, match=rf"material file .*{registry[0].name}: "
                       "not valid TOML"):  # fmt: skip
        materials._parsed(registry)


def test_reading_the_cache_imports_no_hash_library(fresh_python, tmp_path) -> None:
    """The cache is found by a CRC-32 and checked by comparing bytes: hashlib (OpenSSL)
    would cost a good part of the parse it saves. A fresh process, its cache written by
    the one before, loads the registry from it, without importing the TOML parser
    (geometry.reading imports tomllib where it parses; the first process parsed)."""
    code = (
        f"import os, sys\nos.environ['XDG_CACHE_HOME'] = {str(tmp_path)!r}\n"
        "import geometry.reading\n"
        "if AGAIN:  # the second process: a parse would fail it\n"
        "    geometry.reading.parse_toml = None\n"
        "from geometry import materials\n"
        "print('hashlib' in sys.modules, 'tomllib' in sys.modules,\n"
        "      len(list(materials.CACHE.glob('*.marshal'))), len(materials.RECORDS))"
    )
    for again, parser in (("False", "True"), ("True", "False")):
        p = fresh_python(code.replace("AGAIN", again))
        assert p.stdout.split() == ["False", parser, "1", "12"], again
