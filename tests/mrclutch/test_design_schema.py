"""docs/design-file.md is the code's own schema: regenerated, it is unchanged; every key it
lists is accepted by the design-file reader and every table the reader knows is in it."""

from pathlib import Path

import pytest

from geometry.validation import ParameterError
from mrclutch.design import design_from_mapping
from mrclutch.design_schema import in_file_unit, probe_range, reference_markdown, sections

DOC = Path(__file__).resolve().parents[2] / "docs" / "design-file.md"


def test_reference_is_current():
    assert DOC.read_text() == reference_markdown(), "run: python -m mrclutch.design_schema"


def test_every_table_of_the_reader_is_documented_and_unknown_ones_are_refused():
    names = {name for name, _, _ in sections()}
    for table in names - {"clutch"}:
        design_from_mapping({"clutch": {"base": "paper"}, table: {}}, "d.toml")
    with pytest.raises(ParameterError, match="unknown table"):
        design_from_mapping({"clutch": {"base": "paper"}, "bogus": {}}, "d.toml")
    assert {"clutch", "operating", "render", "uncertainty", "measured", "materials"} <= names


def test_every_numeric_key_listed_is_read_and_its_range_enforced():
    """Each numeric key of the simple tables with a quoted range: a value far outside it is
    refused, naming the key."""
    for name, _, rows in sections():
        if name in ("clutch", "uncertainty", "measured", "materials", "render"):
            continue
        for key, _unit, _default, allowed in rows:
            if not allowed.startswith(("[", "(")):
                continue
            with pytest.raises(ParameterError, match=key):
                design_from_mapping({"clutch": {"base": "paper"}, name: {key: 1e300}},
                                    "d.toml")  # fmt: skip


def test_probe_quotes_the_validators_range_in_the_files_unit():
    from mrclutch.process import Process

    assert probe_range(lambda v: Process(runout=v)) == "[0, 0.001] m"
    assert in_file_unit("[0, 0.001] m", "runout_mm", 1e-3) == "[0, 1] mm"
    assert in_file_unit("(0, 1e+04] A", "max_current_A", 1.0) == "(0, 1e+04] A"
