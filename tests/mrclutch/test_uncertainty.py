"""``[uncertainty]`` and ``[measured]`` in design files, the paper's bench, the thresholds that
decide a verdict, and bad input in the new sections (one line, exit 2)."""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mrclutch.cli.main import main
from mrclutch.design import design_from_mapping, design_preset, design_to_toml, load_design
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.haptics.model import max_passive_stiffness, max_stable_stiffness
from mrclutch.pipeline import evaluate
from mrclutch.robust import hand_box_batch, measured_comparison, robust_verdicts, threshold
from mrclutch.uncertainty import (
    PAPER_BENCH,
    SOURCES,
    Uncertainty,
    default_uncertainty,
    paper_unexplained_b1,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_paper_bench_example_is_the_paper_preset_bench():
    d = load_design(EXAMPLES / "paper_bench.toml")
    assert d.measured == PAPER_BENCH
    assert design_preset("paper").measured == PAPER_BENCH
    assert d.clutch == design_preset("paper").clutch


def test_design_file_round_trip_with_both_sections():
    text = (
        '[clutch]\nbase = "paper"\n[uncertainty]\nviscosity_spread_pct = 10\n'
        "fluid_temperature_C = [15, 35]\ndelay_ms = [0.8, 2.5]\n"
        "bench_damping_N_s_per_m = [0, 0.5]\n[measured]\n"
        "torque = [{current_A = 3, torque_N_m = 0.2}, {current_A = 7, torque_N_m = 0.4}]\n"
        "m1_g = 1.5\nuse_in_model = true\n"
    )
    d = design_from_mapping(tomllib.loads(text), "x.toml")
    u = d.uncertainty
    assert u.viscosity_spread == pytest.approx(0.10)
    assert u.fluid_temperature == (15.0, 35.0)
    assert u.delay == pytest.approx((0.8e-3, 2.5e-3))
    assert u.bench_damping == (0.0, 0.5)
    assert u.gap_tolerance == default_uncertainty(d).gap_tolerance  # not given: the default
    assert d.measured.m1 == pytest.approx(1.5e-3) and d.measured.use_in_model
    assert [p.current for p in d.measured.torque] == [3.0, 7.0]
    back = design_from_mapping(tomllib.loads(design_to_toml(d)), "x.toml")
    assert back.uncertainty == d.uncertainty
    assert back.measured == replace(d.measured, source=back.measured.source)


def test_default_bench_damping_is_table2_less_the_model():
    """The default top of the bench damping: Table 2's b1 less the fast model's b1 of the
    paper clutch, so the b1 range reaches the bench's identified value."""
    ev = evaluate(design_preset("paper"))
    assert paper_unexplained_b1() == pytest.approx(float(TABLE2_MR.b1) - float(ev.mr.b1), rel=1e-9)
    assert set(SOURCES) == set(vars(Uncertainty()))  # every input has its documented source


def test_hull_of_the_geometry_corners_holds_interior_points():
    """The box takes the hull of the gap × drum-thickness corners: m1, b1, F_max and the
    delay at interior points of the tolerances lie inside it (what the corners rest on)."""
    d = design_preset("paper")
    u = Uncertainty(viscosity_spread=0.0, fluid_temperature=(20.0, 20.0), runout=0.0,
                    gap_tolerance=0.1e-3, drum_thickness_tolerance=0.1e-3,
                    yield_stress_spread=0.0, bh_spread=0.0)  # fmt: skip
    gaps = np.array([0.4e-3, 0.7e-3, 1.0e-3])
    box = hand_box_batch({"gap": gaps}, d, u)
    rng = np.random.default_rng(3)
    for _ in range(4):
        dg, dt = rng.uniform(-1e-4, 1e-4, 2)
        fixed = replace(u, gap_tolerance=0.0, drum_thickness_tolerance=0.0)
        inner = hand_box_batch({"gap": gaps + dg, "drum_thickness": 0.3e-3 + dt}, d, fixed)
        for name in ("m1", "b1", "K"):
            v = getattr(inner, name)[0]
            _, lo, hi = getattr(box, name)
            assert np.all(lo * (1 - 1e-9) <= v) and np.all(v <= hi * (1 + 1e-9)), name


@pytest.fixture(scope="module")
def paper_robust():
    ev = evaluate(design_preset("paper"))
    return ev, robust_verdicts(ev)


def test_paper_verdict_names_b1_and_the_delay_with_thresholds(paper_robust):
    _, r = paper_robust
    head = r["headline"]
    for v in ("stable", "passive"):
        assert r["verdicts"][v]["holds"] == "depends"
        assert set(r["verdicts"][v]["thresholds"]) == {"b1", "delay"}
        b1, delay = (r["verdicts"][v]["thresholds"][f] for f in ("b1", "delay"))
        # b1's threshold lies inside its range, the delay's (≈ 0.67 ms) below the typed 1 ms
        assert b1["range"][0] < b1["value"] < b1["range"][1]
        assert delay["value"] < delay["range"][0]
    # the sentence names only a threshold inside its range (issue 39), as the verdict line
    assert head.count("b1 ≥") == 2 and "the delay ≤" not in head and "outside" not in head
    # worst ≤ nominal ≤ best
    for key in ("max_stable_K_N_per_m", "max_passive_K_N_per_m", "bandwidth_hz"):
        assert r[key]["worst"] <= r[key]["nominal"] <= r[key]["best"]


@pytest.mark.parametrize("verdict", ["stable", "passive"])
@pytest.mark.parametrize("field", ["b1", "delay"])
def test_each_threshold_flips_the_nominal_verdict_within_one_percent(paper_robust, verdict, field):
    """The nominal model at threshold × (1 ± 1 %): the verdict at K is different on the two
    sides, and the side the threshold's sense names is the one where it holds."""
    ev, r = paper_robust
    K = r["K_N_per_m"]
    t = r["verdicts"][verdict]["thresholds"][field]
    limit = {"stable": max_stable_stiffness, "passive": max_passive_stiffness}[verdict]
    x = t["value"]
    below = K <= limit(replace(ev.mr, **{field: x * 0.99}))
    above = K <= limit(replace(ev.mr, **{field: x * 1.01}))
    assert below != above
    assert above == (t["sense"] == "≥")


def test_threshold_is_none_where_no_value_flips_it():
    p = replace(TABLE2_MR, delay=1e-3)
    assert threshold(p, 1e-3, "stable", "b1") is None  # stable at any b1


def test_no_uncertainty_prints_the_nominal_verdict(capsys):
    assert main(["evaluate", "--preset", "paper", "--no-uncertainty", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["robust"] is None
    assert main(["evaluate", "--preset", "paper", "--no-uncertainty"]) == 0
    out = capsys.readouterr().out
    first = out.splitlines()[0]  # the one verdict, at nominal values
    assert first.startswith(
        "VERDICT: FAIL — unstable at nominal values; not passive at nominal values"
    )


def test_bench_printed_model_against_measurement(paper_robust, capsys):
    ev, _ = paper_robust
    rows = {r["quantity"]: r for r in measured_comparison(ev)}
    assert set(rows) == {"torque at 7 A", "delay of a torque step", "m1 at the hand",
                         "b1 at the hand"}  # fmt: skip
    b1 = rows["b1 at the hand"]
    assert b1["error"] == pytest.approx(float(ev.mr.b1) / 1.0 - 1, rel=1e-12)
    assert rows["torque at 7 A"]["model"] == ev.clutch.max_torque
    assert main(["evaluate", "--preset", "paper", "--no-uncertainty"]) == 0
    out = capsys.readouterr().out
    assert "model against the bench" in out
    assert f"{b1['error'] * 100:+.1f} %" in out


def test_measured_values_used_in_the_model_are_labelled(tmp_path, capsys):
    f = tmp_path / "d.toml"
    f.write_text('[clutch]\nbase = "paper"\n[measured]\nm1_g = 1.5\nb1_N_s_per_m = 1.0\n'
                 "step_delay_ms = 1.0\ntorque = [{current_A = 7, torque_N_m = 0.4}]\n"
                 "use_in_model = true\n")  # fmt: skip
    ev = evaluate(load_design(f))
    assert float(ev.mr.b1) == 1.0 and float(ev.mr.m1) == 1.5e-3
    assert ev.source == "measured (m1, b1, delay, torque) + fast model"
    # the torque at the current limit measured: K_max = F_max/d from 0.4 N·m (Eq. 4)
    assert float(ev.mr.k_max) == pytest.approx(0.4 * ev.design.transmission.reduction / 0.05)
    # the model's own figures still compared with the bench
    rows = {r["quantity"]: r for r in measured_comparison(ev)}
    assert rows["b1 at the hand"]["model"] == pytest.approx(float(ev.model_mr.b1))
    assert main(["evaluate", str(f), "--no-uncertainty"]) == 0
    assert "[MR pair, measured (m1, b1, delay, torque) + fast model]" in capsys.readouterr().out


def test_other_currents_compared_with_the_network(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text('[clutch]\nbase = "paper"\n[measured]\n'
                 "torque = [{current_A = 2, torque_N_m = 0.15}]\n")  # fmt: skip
    ev = evaluate(load_design(f))
    (row,) = measured_comparison(ev)
    assert row["model_source"] == "fast model"
    assert 0 < row["model"] < ev.clutch.max_torque
    assert math.isclose(row["error"], row["model"] / 0.15 - 1)


@pytest.mark.parametrize(
    ("table", "fragment"),
    [
        ("[uncertainty]\nfluid_temperature_C = [40, 20]", "temperature_C = [40, 20]: low > high"),
        ("[uncertainty]\ndelay_ms = [2, 1]", "uncertainty.delay_ms = [2, 1]: low > high"),
        ("[uncertainty]\nviscosity_spread_pct = -5", "viscosity_spread_pct = -5: must be >= 0"),
        ("[uncertainty]\nbench_damping_N_s_per_m = [-1, 0]", "bench_damping"),
        ("[uncertainty]\ndelay_ms = 1", "delay_ms = 1: must be [low, high]"),
        ("[uncertainty]\nviscosity_spread_pct = 150", "viscosity_spread = 1.5: must be in [0, 1)"),
        ("[uncertainty]\ngap_mm = 1", "uncertainty.gap_mm: unknown key"),
        ("[measured]\ntorque = [{torque_N_m = 0.4}]", "torque[0]: no current_A"),
        ("[measured]\ntorque = [{current_A = -7, torque_N_m = 0.4}]", "current = -7 A: must be"),
        ("[measured]\nm1_g = -1", "measured.m1_g = -1: m1 = -0.001 kg: must be in [1e-06, 100] kg"),
        ("[measured]\nuse_in_model = 1", "use_in_model = 1: must be true or false"),
        ("[measured]\nm1 = 1", "measured.m1: unknown key"),
    ],
)  # fmt: skip
def test_bad_input_in_the_new_sections_is_one_line_exit_2(tmp_path, capsys, table, fragment):
    f = tmp_path / "bad.toml"
    f.write_text(f'[clutch]\nbase = "paper"\n{table}\n')
    assert main(["evaluate", str(f)]) == 2
    err = capsys.readouterr().err
    assert fragment in err, err
    assert "Traceback" not in err and err.count("\n") == 1, err


def test_sweep_with_the_robust_columns_equals_robust_columns_batch(tmp_path):
    """``sweep --with`` the robust columns: the same numbers as ``robust_columns_batch`` on
    the same designs, over the ranges the spec's ``[uncertainty]`` table declares."""
    import csv

    from mrclutch.robust import ROBUST_COLUMNS, robust_columns_batch

    spec = tmp_path / "s.toml"
    spec.write_text('[sweep]\nmode = "grid"\nbase = "paper"\n[parameters]\n'
                    "gap_mm = {values = [0.5, 0.7]}\n"
                    "[uncertainty]\ndelay_ms = [1, 3]\n")  # fmt: skip
    out = tmp_path / "r.csv"
    argv = ["sweep", str(spec), "--out", str(out), "--no-progress"]
    for k in ROBUST_COLUMNS:
        argv += ["--with", k]
    assert main(argv) == 0
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    d = design_preset("paper")
    unc = replace(default_uncertainty(d), delay=(1e-3, 3e-3))
    want = robust_columns_batch({"gap": np.array([0.5e-3, 0.7e-3])}, d, unc)
    for k in ROBUST_COLUMNS:
        got = np.array([float(r[k]) for r in rows])
        np.testing.assert_allclose(got, want[k], rtol=1e-8)  # the CSV's 9 digits
