"""Speed against accuracy: the delay approximations against the exact stability limit,
the registry and measure, the accuracy-target choice, and the fidelity command."""

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest

from mrclutch.design import design_preset
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.haptics.delay import (
    pade_coefficients,
    pade_phase_error,
    pade_stable_stiffness,
    simulate_growth,
    step_stable_stiffness,
)
from mrclutch.haptics.model import max_stable_stiffness
from mrclutch.pipeline import evaluate


@pytest.fixture(scope="module")
def paper():
    return design_preset("paper")


def test_pade_converges_to_the_exact_limit_and_faster_with_order():
    exact = max_stable_stiffness(TABLE2_MR)
    errs = [abs(pade_stable_stiffness(TABLE2_MR, n) / exact - 1) for n in (1, 2, 4)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-8


def test_pade_coefficients_match_the_exponential_series():
    num, den = pade_coefficients(3)
    x = 0.3
    approx = np.polyval(num[::-1], x) / np.polyval(den[::-1], x)
    assert approx == pytest.approx(math.exp(-x), rel=1e-7)  # error O(x^7)
    assert pade_phase_error(1e-3, 2, 0.0) == pytest.approx(0.0, abs=1e-15)
    # the approximant is all-pass: its phase lags less than ωτ at high frequency
    assert pade_phase_error(1e-3, 1, 1e4) == pytest.approx(10 - 2 * math.atan(5), rel=1e-9)


def test_time_stepping_converges_like_its_step_and_matches_a_simulation():
    exact = max_stable_stiffness(TABLE2_MR)
    e5 = abs(step_stable_stiffness(TABLE2_MR, 5) / exact - 1)
    e20 = abs(step_stable_stiffness(TABLE2_MR, 20) / exact - 1)
    assert e20 < e5 / 4  # at least first order in h (FOH: second order)
    k = step_stable_stiffness(TABLE2_MR, 5)
    assert (
        simulate_growth(TABLE2_MR, 0.97 * k, 0.6, 5)
        < 0
        < simulate_growth(TABLE2_MR, 1.03 * k, 0.6, 5)
    )


def test_measure_rows_and_reference(paper):
    from mrclutch.fidelity import measure, registry

    ms = [m for m in registry() if m.quantity in ("stability", "bandwidth")]
    rows = measure(paper, ("stability", "bandwidth"), repeats=1, methods=ms)
    assert [r.method for r in rows] == [m.name for m in ms]
    for q in ("stability", "bandwidth"):
        refs = [r for r in rows if r.quantity == q and r.reference]
        assert len(refs) == 1 and refs[0].error_rel == 0.0
    assert all(r.time_s > 0 and math.isfinite(r.value) for r in rows)
    lumped = next(r for r in rows if r.method == "lumped")
    assert 0 < lumped.error_rel < 0.05


def test_choose_picks_cheapest_meeting_target(paper):
    from mrclutch.trust import TORQUE_METHODS, choose, inertia_bound, torque_error_bound

    three = replace(paper, clutch=replace(paper.clutch, n_drums=3))
    for design in (paper, three):
        for target in (0.1, 0.01, 0.003):
            pick = choose(design, target)
            assert pick.inertia == "analytic"  # exact for the axisymmetric section
            assert pick.errors["torque"] <= target
            i = design.current_limit
            bounds = [torque_error_bound(design.clutch, n, s, i) for n, s, _ in TORQUE_METHODS]
            chosen = [(n, s) for n, s, _ in TORQUE_METHODS].index((pick.torque, pick.fem_size))
            assert all(b > target for b in bounds[:chosen])  # nothing cheaper meets it
    assert choose(paper, 0.01).torque == "circuit"
    pick = choose(paper, 0.003)  # neither fast model's bound meets it: the FEM, and why
    assert pick.torque == "fem" and any("reluctance network" in n for n in pick.notes)
    # the network's bound over every dimension: 2.1 % on the preset, 2.1 % on 3 drums,
    # 1.8 % on 6 (|estimate| + q·σ̂ with the network's solution among the inputs,
    # magnetics.network_bound; 3.0, 2.5 and 3.1 % on the dimensions alone)
    assert 0.019 < torque_error_bound(paper.clutch, "network", None, 7.0) < 0.023
    assert choose(three, 0.03).torque == "network"
    assert choose(three, 0.01).torque == "fem"  # past the network's bound: the FEM
    pick = choose(three, 0.1)  # the circuit is > 10 % off on 3 drums: it says so
    assert pick.torque == "network" and any("circuit" in n and "-12.1%" in n for n in pick.notes)
    six = replace(paper, clutch=replace(paper.clutch, n_drums=6))
    assert choose(six, 0.1).torque == "network"
    pick = choose(six, 0.003)  # past the network's bound there: the FEM, and why
    assert pick.torque == "fem" and any("reluctance network" in n for n in pick.notes)
    holes = replace(paper, clutch=replace(paper.clutch, hub_holes=6))
    assert inertia_bound(paper) == 0.0 and inertia_bound(holes) > 0.0


@pytest.mark.parametrize("n_drums", [2, 6])
def test_accuracy_target_is_met_against_the_reference(paper, n_drums):
    """Issue 6 acceptance, accuracy side: evaluate(accuracy=0.01) is within 1 % of the
    reference fidelity on inertia, torque and bandwidth — on the paper preset (circuit) and
    on a 6-drum variant where the circuit is 39 % off and the network's bound over every
    dimension (3.4 %, issue 31; its five-axis map claimed 0.9 %) misses 1 %: the FEM at
    0.35 mm."""
    d = replace(paper, clutch=replace(paper.clutch, n_drums=n_drums))
    ref, acc = evaluate(d, "reference"), evaluate(d, accuracy=0.01)
    assert acc.clutch.methods["torque"] == ("circuit" if n_drums == 2 else "fem@0.35mm")
    for a, r in (
        (acc.clutch.rotor_inertia, ref.clutch.rotor_inertia),
        (acc.clutch.max_torque, ref.clutch.max_torque),
        (acc.haptic["bandwidth_hz"], ref.haptic["bandwidth_hz"]),
    ):
        assert abs(a / r - 1) <= 0.01


def test_cli_fidelity_rejects_bad_input(tmp_path):
    from mrclutch.cli.main import main

    assert main(["fidelity", "--preset", "paper", "--out", str(tmp_path), "--repeats", "0"]) == 2
    assert main(["evaluate", "--accuracy", "0"]) == 2


def test_fidelity_table_writer(tmp_path):
    from mrclutch.cli.commands.fidelity import rows_csv
    from mrclutch.fidelity import Row

    rows = [Row("torque", "fem", "size 1 mm", 0.1, 0.44, 0.04, False)]
    text = rows_csv(rows)
    assert text.splitlines()[0].startswith("quantity,method,setting,time_s")
    assert "torque,fem,size 1 mm,0.1,0.44,N·m,0.04" in text
    assert json.loads(json.dumps(rows[0].as_json()))["error_rel"] == 0.04


def test_eddy_delay_rows_in_the_data_and_the_chart(paper, tmp_path):
    """The eddy lag's methods: the 1-D diffusion model and the time-harmonic FEM at two
    sizes against the finest FEM; the 1-D model within 15 % on the preset (measured +10 %),
    the FEM converging (1 mm within 6 %, 0.5 mm closer); CSV and chart carry the rows."""
    from mrclutch.cli.commands.fidelity import rows_csv
    from mrclutch.cli.plots.fidelity import COLOURS, plot_fidelity
    from mrclutch.fidelity import UNITS, measure, registry

    ms = [m for m in registry() if m.quantity == "eddy_delay"]
    assert [m.name for m in ms] == ["diffusion 1-D"] + ["harmonic fem"] * 3 and ms[-1].reference
    rows = measure(paper, ("eddy_delay",), repeats=1, methods=ms)
    by = {r.setting: r for r in rows}
    assert by["size 0.25 mm"].error_rel == 0.0 and 5e-4 < by["size 0.25 mm"].value < 3e-3
    assert 0.01 < by["1-D cuts per part"].error_rel < 0.15
    assert by["size 0.5 mm"].error_rel < by["size 1 mm"].error_rel < 0.06
    assert UNITS["eddy_delay"] == "s" and "eddy_delay" in COLOURS
    assert "eddy_delay,harmonic fem,size 0.25 mm" in rows_csv(rows)
    plot_fidelity(rows, tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 10_000


def test_a_setting_the_design_refuses_is_skipped_and_said(paper):
    """A 4-drum, 1 mm-gap clutch is 37.8 mm across: a 0.003 mm mesh is below its floor
    (1e-4 × its size). ``mrclutch fidelity`` used to stop there; the method is now left
    out and the progress says why. A refused reference still raises."""
    from geometry.validation import ParameterError
    from mrclutch.fidelity import Method, _mesh_inertia, measure

    big = replace(paper, clutch=replace(paper.clutch, n_drums=4, gap=1.0e-3))
    said: list[str] = []
    fine = Method("inertia", "mesh", "tolerance 0.003 mm", lambda d: _mesh_inertia(d, 3e-6))
    ref = Method("inertia", "stand-in", "1", lambda d: 1.0, 1, True)
    rows = measure(big, ("inertia",), repeats=1, methods=[fine, ref], progress=said.append)
    assert [r.method for r in rows] == ["stand-in"]
    assert any("skipped" in m and "must be >=" in m for m in said)
    with pytest.raises(ParameterError, match="must be >="):
        measure(big, ("inertia",), repeats=1,
                methods=[Method("inertia", "mesh", "0.003", fine.fn, 1, True)])  # fmt: skip


def test_cli_fidelity_progress_on_stderr_json_alone_on_stdout(tmp_path, capsys, monkeypatch):
    """``mrclutch fidelity --json`` (issue 40: a job over ~2 s says how long): each method
    is named on stderr as it starts, under a bar of the methods done and then the files
    written (the chart's drawing, silent after the bar before): the files named, then 4/4
    at the end, with tqdm's rate and estimate; stdout is the JSON document alone, the rows
    of the three methods (two bandwidths and the stand-in reference, exact: error 0)."""
    import mrclutch.cli.commands.fidelity as cmd
    from mrclutch.cli.main import main
    from mrclutch.fidelity import Method, registry

    ms = tuple(m for m in registry() if m.quantity == "bandwidth")
    ms += (Method("stability", "stand-in", "1", lambda d: 1.0, 1, True),)
    monkeypatch.setattr(cmd, "registry", lambda: ms)
    assert main(["fidelity", "--preset", "paper", "--out", str(tmp_path), "--repeats", "1",
                 "--json"]) == 0  # fmt: skip
    out, err = capsys.readouterr()
    doc = json.loads(out)  # nothing else on stdout
    assert [r["method"] for r in doc["rows"]] == ["lumped", "full response", "stand-in"]
    assert doc["rows"][2]["error_rel"] == 0.0
    assert "fidelity: bandwidth: lumped (√(K/(m1+m2)))" in err
    assert "fidelity: stability: stand-in (1)" in err
    files = "fidelity: writing fidelity.csv, fidelity.json, fidelity.png\n"
    assert err.index(files) < err.rindex("4/4")  # the files are a step of the bar
    assert re.search(r"fidelity: 100%\|[^|]*\| 4/4 \[\d\d:\d\d<\d\d:\d\d", err)
    assert "step/s" in err or "s/step" in err
    assert json.loads((tmp_path / "fidelity.json").read_text()) == doc
