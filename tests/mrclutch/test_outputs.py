"""One output-name table: every key the tool writes is named, with a unit, once."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mrclutch.cli.main import main
from mrclutch.haptics.model import METRIC_KEYS
from mrclutch.outputs import CLUTCH_ROWS, HAND_ROWS, OUTPUTS, SWEEP_COLUMNS, output, row_label
from mrclutch.pipeline import evaluate, evaluate_batch


def test_every_haptic_metric_and_row_has_an_entry() -> None:
    for key in (*METRIC_KEYS, *CLUTCH_ROWS, *HAND_ROWS, *SWEEP_COLUMNS):
        assert key in OUTPUTS, key


def test_the_evaluate_json_and_the_sweep_columns_use_the_same_names() -> None:
    ev = evaluate_default()
    data = ev.as_json()
    clutch_keys = set(data["clutch"]) - {"envelope_m", "methods", "notes", "drag"}
    assert clutch_keys <= set(OUTPUTS)
    assert set(data["haptic"]) <= set(OUTPUTS)
    row = evaluate_batch({"gap": np.array([0.3e-3])})
    assert tuple(row) == SWEEP_COLUMNS
    # a quantity in both is one key with one value: the batch of one is the design
    for key in set(row) & (clutch_keys | set(data["haptic"])) - {"valid"}:
        v = data["clutch"].get(key, data["haptic"].get(key))
        assert row[key][0] == pytest.approx(v, rel=1e-9, nan_ok=True), key


def evaluate_default():  # type: ignore[no-untyped-def]
    from dataclasses import replace

    from mrclutch.design import ClutchDesign

    d = ClutchDesign()
    return evaluate(replace(d, clutch=replace(d.clutch, gap=0.3e-3)))


def test_display_scales_flags_and_nones() -> None:
    assert output("rotor_inertia_kg_m2").display(2.587e-7) == "2.587"  # g·cm²
    assert row_label("m1_kg") == "m1 (g)"
    assert output("passive").display(np.bool_(False)) == "no"
    assert output("bandwidth_hz").display(None) == "—"
    assert output("bandwidth_hz").display(math.nan) == "—"
    assert output("max_stable_K_N_per_m").display(math.inf) == "∞"
    with pytest.raises(KeyError, match="no output named"):
        output("torque")


def test_the_sweep_meta_file_says_each_columns_unit(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    spec = tmp_path / "s.toml"
    spec.write_text(
        '[sweep]\nmode = "random"\nsamples = 4\nseed = 1\nbase = "paper"\n'
        "[parameters]\ngap_mm = {min = 0.2, max = 1.0}\n"
    )
    out = tmp_path / "r.csv"
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress"]) == 0
    meta = json.loads((tmp_path / "r.csv.meta.json").read_text())
    header = out.read_text().split("\n", 1)[0].split(",")
    for key in SWEEP_COLUMNS:
        assert key in header
        assert meta["columns"][key]["unit"] == OUTPUTS[key].unit
