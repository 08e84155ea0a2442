"""Design files: every bad key is named, nothing silently defaulted."""

import math

import pytest

from geometry import ParameterError, preset
from mrclutch.cli.main import main
from mrclutch.design import ClutchDesign, Operating, design_from_mapping, load_design


def test_full_design_file_round_trip(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text(
        '[clutch]\nbase = "paper"\ngap_mm = 0.5\nn_drums = 3\n'
        "[operating]\nmax_current_A = 5\ninput_speed_rpm = 600\ndelay_ms = 2\n"
        "[transmission]\nlever_mm = 75\ngearing = 2\nworkspace_mm = 40\nm2_g = 12\n"
    )
    d = load_design(f)
    assert d.clutch.gap == 0.5e-3 and d.clutch.n_drums == 3
    assert d.clutch.drum_thickness == preset("paper").drum_thickness
    assert d.operating.max_current == 5.0
    assert d.operating.input_speed == pytest.approx(600 * 2 * math.pi / 60)
    assert d.operating.delay == pytest.approx(2e-3)
    assert d.transmission.lever == pytest.approx(0.075)
    assert d.transmission.gearing == 2.0 and d.transmission.m2 == pytest.approx(12e-3)
    assert d.name == "d"


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("[clutch]\ngap_mm = 0.3\n", "n_drums: missing"),
        ('[clutch]\nbase = "paper"\ngapp_mm = 0.3\n', "gapp_mm: unknown key"),
        ('[clutch]\nbase = "paper"\ngap = 0.3\n', "gap: lengths need their unit"),
        ('[clutch]\nbase = "paper"\ngap_mm = -0.3\n', "gap_mm = -0.3 mm: must be in"),
        ('[clutch]\nbase = "paper"\ngap_mm = "wide"\n', "gap_mm = 'wide': must be a number"),
        ('[clutch]\nbase = "paper"\ndrum_inner_diameter_mm = 1.0\n', "must exceed 2·gap"),
        ('[clutch]\nbase = "paper"\n[operating]\nmax_current = 3\n', "write max_current_A"),
        ('[clutch]\nbase = "paper"\n[operating]\nmax_current_A = -3\n', "max_current = -3"),
        ('[clutch]\nbase = "paper"\n[transmission]\nlever_mm = true\n', "must be a number"),
        ('[clutch]\nbase = "nope"\n', "preset = 'nope': unknown"),
        ('[clutch]\nbase = "paper"\n[extra]\nx = 1\n', "extra: unknown table"),
        ("gap_mm = 0.3\n", "gap_mm: not in a table; dimensions go under [clutch]"),
        ("[operating]\nmax_current_A = 3\n", "missing the [clutch] table"),
        ("[clutch\n", "not valid TOML"),
    ],
)
def test_bad_design_files_name_the_key(tmp_path, capsys, text, fragment):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ParameterError) as exc:
        load_design(f)
    assert fragment in str(exc.value)
    # the CLI: one line, exit 2, no traceback
    assert main(["evaluate", str(f)]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err and err.count("\n") == 1


def test_current_density_caps_the_current():
    wire = math.pi * preset("paper").wire_diameter ** 2 / 4
    d = ClutchDesign(operating=Operating(max_current=7.0, max_current_density=20e6))
    assert d.current_limit == pytest.approx(20e6 * wire)
    assert ClutchDesign().current_limit == 7.0


def test_operating_validation_names_the_parameter():
    with pytest.raises(ParameterError, match="delay = 2 s: must be in"):
        Operating(delay=2.0)
    with pytest.raises(ParameterError, match="max_current_density = -1"):
        Operating(max_current_density=-1.0)


def test_mapping_without_operating_uses_defaults():
    d = design_from_mapping({"clutch": {"base": "paper"}}, "x")
    assert d.operating == Operating()


def test_design_file_writer_round_trips(tmp_path):
    from dataclasses import replace

    from mrclutch.design import design_to_toml

    d = ClutchDesign(
        clutch=replace(preset("paper"), gap=0.43e-3, n_drums=3),
        operating=Operating(max_current=5.5, delay=2e-3),
        name="x y",
    )
    f = tmp_path / "d.toml"
    f.write_text(design_to_toml(d))
    back = load_design(f)
    assert back.clutch == d.clutch and back.name == "x y"
    assert back.operating.max_current == d.operating.max_current
    assert back.operating.input_speed == pytest.approx(d.operating.input_speed, rel=1e-12)
    assert back.transmission.ratio == pytest.approx(d.transmission.ratio, rel=1e-12)


@pytest.mark.parametrize(
    ("table", "says", "digits"),
    [({"amplifier": {"supply_voltage_V": 3.0}}, "the amplifier's 3 V supply holds at most", 3),
     ({"operating": {"max_current_density_A_per_mm2": 5.0}},
      "the current-density limit caps the current at", 4)],
)  # fmt: skip
def test_current_notes_say_what_caps_the_limit(table, says, digits):
    """``current_notes`` (beside the current limit, so ``torque`` reads it without
    mrclutch.clutch, issue 40) says which limit binds, with the limit's own value; the paper
    design has none; ``clutch`` and ``pipeline`` read the same function."""
    from mrclutch import clutch, pipeline
    from mrclutch.design import current_notes, design_from_mapping, design_preset

    d = design_from_mapping({"clutch": {"base": "paper"}, **table})
    (note,) = current_notes(d)
    assert note.startswith(f"{says} {d.current_limit:.{digits}g} A")
    assert d.current_limit < d.operating.max_current
    assert current_notes(design_preset("paper")) == ()
    assert clutch.current_notes is current_notes and pipeline.current_notes is current_notes
