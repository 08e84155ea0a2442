"""Every value of the material library is sourced or said to be unsourced (issue 41, item
3 of the closing round): in geometry/data/materials/*.toml,

* every reference key a file names ([key], in a source or a comment) is an entry of
  docs/references.md;
* a stored value whose source says NOT (NOT READ, NOT FOUND, NOT MEASURED: no source was
  read for it) is listed in the file's ``unverified`` — and, the converse, every listed
  value has such a source (``test_material_library.py::
  test_every_unverified_value_is_said_in_its_source_field``);
* a stored value whose source does not say NOT names a reference key — unless the source
  states a modelling choice rather than a datum (``CHOICES``: an insulator's 0 S/m).

Derived figures (``tau_y_temperature_source``: τy(T) from Carlson's law and the carrier's
expansion) are not stored values; they are unverified through the value they derive from
(``carrier_expansion``), which the rules above hold.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
LIBRARY = ROOT / "geometry" / "data" / "materials"
REFS = ROOT / "docs" / "references.md"
KEY = re.compile(r"\[([a-z][a-z0-9-]{4,})\]")
ENTRY = re.compile(r"^### \[([a-z][a-z0-9-]{4,})\]", flags=re.M)
#: Sources that state a modelling choice, not a datum (no reference to cite).
CHOICES = ("not modelled as a conductor", "an electrical insulator")


def _known() -> set[str]:
    return set(ENTRY.findall(REFS.read_text()))


def _sources(rec: dict[str, Any], prefix: str = "") -> Iterator[tuple[str, str, bool]]:
    """(value name, source text, stored) for each source of a record: ``x_source`` is the
    source of ``x`` (``thermal_source`` of the thermal values), a table's ``source`` of
    the table's values (``table.*``); ``stored``: the record holds the value it sources."""
    for k, v in rec.items():
        if isinstance(v, dict):
            yield from _sources(v, f"{prefix}{k}.")
        elif isinstance(v, str) and k == "source" and prefix:
            yield prefix.rstrip("."), v, True
        elif isinstance(v, str) and k.endswith("_source"):
            name = k[: -len("_source")]
            stored = name in rec or name == "thermal"
            yield f"{prefix}{name}", v, stored


def problems(path: Path, known: set[str]) -> list[str]:
    """What breaks the rules (module docstring) in one material file."""
    text = path.read_text()
    rec = tomllib.loads(text)
    out = []
    for line in text.splitlines():
        if line.lstrip().startswith("["):  # a TOML table header, not a citation
            continue
        out += [f"{path.name}: [{k}] is not in docs/references.md"
                for k in KEY.findall(line) if k not in known]  # fmt: skip
    unverified = set(rec.get("unverified", []))
    thermal = {"specific_heat", "thermal_conductivity"}
    for name, src, stored in _sources(rec):
        if not stored:
            continue
        listed = (name in unverified or any(u.startswith(name + ".") for u in unverified)
                  or (name == "thermal" and bool(unverified & thermal)))  # fmt: skip
        if "NOT" in src and not listed:
            out.append(f"{path.name}: {name}: its source says NOT but it is not unverified")
        if "NOT" not in src and not KEY.search(src) and not src.startswith(CHOICES):
            out.append(f"{path.name}: {name}: sourced without a reference key")
    return out


@pytest.mark.parametrize("path", sorted(LIBRARY.glob("*.toml")), ids=lambda p: p.stem)
def test_every_value_is_sourced_or_unverified(path: Path) -> None:
    assert problems(path, _known()) == []


def test_the_rules_catch_planted_faults(tmp_path: Path) -> None:
    """A made-up key, a NOT READ value left out of ``unverified``, a source with no key: each
    is reported; the same file with them mended is clean."""
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'name = "x"\nunverified = []\ndensity = 1.0\n'
        'density_source = "NOT READ: typical value"\n'
        'viscosity = 2.0\nviscosity_source = "a handbook [nosuchbook]"\n'
        'conductivity = 3.0\nconductivity_source = "somewhere"\n'
    )
    got = problems(bad, {"lebel"})
    assert got == [
        "bad.toml: [nosuchbook] is not in docs/references.md",
        "bad.toml: density: its source says NOT but it is not unverified",
        "bad.toml: conductivity: sourced without a reference key",
    ]
    good = tmp_path / "good.toml"
    good.write_text(
        'name = "x"\nunverified = ["density"]\ndensity = 1.0\n'
        'density_source = "NOT READ: typical value"\n'
        'viscosity = 2.0\nviscosity_source = "a handbook [lebel]"\n'
        'conductivity = 0.0\nconductivity_source = "not modelled as a conductor"\n'
    )
    assert problems(good, {"lebel"}) == []
