"""docs/materials.md's generated table (magnetics.materials_table): the doc holds what the
command prints, and each cell says unverified where the data file does."""

from __future__ import annotations

from magnetics import materials_table as mt
from magnetics.materials import FLUIDS


def test_the_doc_holds_the_generated_table() -> None:
    """Regenerate with ``python -m magnetics.materials_table --write``."""
    text = mt.DOC.read_text()
    assert mt.block() in text
    assert mt.replaced(text) == text


def test_fluid_row_hand_worked() -> None:
    """MRF-132DG: −1.5239 × (1 − 0.32) × 7e-4 = −7.254e-4 1/K, printed −0.073 %/K; LDE
    5e12 J/m³ = 5 MJ/mL; both listed unverified in its file, so marked."""
    row = {r[0]: r for r in mt.rows()}["`mrf_132dg` (MRF-132DG)"]
    assert FLUIDS["mrf_132dg"].phi == 0.32
    assert row[4] == "-0.073 (unverified)"
    assert row[5] == "5 (unverified)"
    assert "[durability2022]" in row[6] and "[ocalan-mckinley2013]" in row[6]


def test_cells_mark_only_what_the_file_lists() -> None:
    rec = {"unverified": ["hysteresis.remanence_T"]}
    assert mt._cell("1.2", "hysteresis.remanence_T", rec) == "1.2 (unverified)"
    assert mt._cell("80", "hysteresis.coercivity_A_per_m", rec) == "80"
    assert mt._keys("a [carlson] b [carlson] [lebel]", None) == "[carlson] [lebel]"
    assert mt._keys("no key") == "—"


def test_every_steel_and_fluid_has_a_row_and_others_none() -> None:
    names = {r[0].split("`")[1] for r in mt.rows()}
    assert {"steel_1018", "hiperco_50", "mrf_132dg", "mrf_140cg"} <= names
    assert "stainless_304" not in names and "pla" not in names


def test_a_users_material_loaded_earlier_has_no_row(tmp_path) -> None:
    """The doc lists the library only: a fluid file a user (or another test in the same
    worker) loaded must not change it (CI failed on exactly this ordering)."""
    from geometry.materials import DATA, RECORDS, is_builtin
    from magnetics.materials import load_fluid

    before = mt.block()
    text = (DATA / "mrf_132dg.toml").read_text()
    path = tmp_path / "table_probe_fluid.toml"
    path.write_text(
        text.replace('name = "mrf_132dg"', 'name = "table_probe_fluid"').replace(
            'label = "MRF-132DG"', 'label = "table probe fluid"'
        )
    )
    name = load_fluid(path)
    assert name == "table_probe_fluid" and name in RECORDS and not is_builtin(name)
    assert is_builtin("mrf_132dg")
    assert "table_probe_fluid" not in mt.block()
    assert mt.block() == before
