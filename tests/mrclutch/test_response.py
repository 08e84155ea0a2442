"""The torque response in the pipeline (issue 14): evaluate's block, the sweep column,
delay_source = "geometry", and the error of the equivalent delay τ_eq = Σ T_i."""

from dataclasses import replace

import numpy as np
import pytest

from magnetics.amplifier import Amplifier
from magnetics.laminations import Laminations
from mrclutch.design import ClutchDesign, Operating, design_preset
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.haptics.delay import lag_stable_stiffness
from mrclutch.haptics.model import max_stable_stiffness
from mrclutch.pipeline import evaluate, evaluate_batch

PAPER = design_preset("paper")
GEOMETRY = replace(PAPER, operating=Operating(delay_source="geometry"))

#: Stated error of τ_eq on the largest stable K, against the lags themselves: τ_eq is
#: conservative (never more K than the lags allow); within 5 % below on the paper preset,
#: within 15 % below on random lags of 0.05–2 ms each (measured: −2 … −12 %).
TAU_EQ_K_ERROR = 0.05
TAU_EQ_K_ERROR_RANDOM = 0.15


@pytest.fixture(scope="module")
def paper_eval():
    return evaluate(GEOMETRY)


def test_evaluate_response_block(paper_eval):
    r = paper_eval.as_json()["response"]
    assert r["inductance_0A_H"] > r["inductance_peak_H"] > 0  # saturation
    lags = r["electrical_time_constant_s"] + r["eddy_time_constant_s"] + r["fluid_time_constant_s"]
    assert r["torque_delay_s"] == pytest.approx(lags)
    assert paper_eval.mr.delay == pytest.approx(r["torque_delay_s"])  # geometry feeds the model
    k_eq, k_lags = r["max_stable_K_torque_delay_N_per_m"], r["max_stable_K_lags_N_per_m"]
    assert k_eq <= k_lags * (1 + 1e-6)
    assert k_eq == pytest.approx(k_lags, rel=TAU_EQ_K_ERROR)
    assert paper_eval.haptic["max_stable_K_N_per_m"] == pytest.approx(k_eq, rel=1e-6)


def test_fixed_source_keeps_the_typed_delay():
    ev = evaluate(PAPER)
    assert ev.mr.delay == PAPER.operating.delay
    assert ev.response["typed_delay_s"] == PAPER.operating.delay


def test_tau_eq_error_on_random_designs():
    """Random lags and haptic parameters around Table 2: K with τ_eq against K with the
    lags (exact polynomial roots, no Padé: no pure delay)."""
    rng = np.random.default_rng(14)
    errs = []
    for _ in range(40):
        lags = rng.uniform(0.05e-3, 2e-3, 3)
        m1, b1, k = (getattr(TABLE2_MR, f) * rng.uniform(0.3, 3) for f in ("m1", "b1", "k"))
        p = replace(TABLE2_MR, delay=0.0, m1=m1, b1=b1, k=k)
        ref = lag_stable_stiffness(p, lags)
        eq = max_stable_stiffness(replace(p, delay=float(lags.sum())))
        errs.append(eq / ref - 1)
    errs = np.array(errs)
    assert np.all(errs <= 1e-6)  # conservative
    assert np.all(errs > -TAU_EQ_K_ERROR_RANDOM)
    print(f"τ_eq: K error {errs.min():+.1%} … {errs.max():+.1%}, median {np.median(errs):+.1%}")


@pytest.mark.parametrize(
    "faster",
    [
        {"laminations": Laminations(shell=0.5e-3, core=0.5e-3)},
        {"amplifier": Amplifier(supply_voltage=48.0)},
    ],
)
def test_faster_design_shorter_delay_larger_stable_k(faster):
    """A laminated core and shell, or a higher supply voltage: shorter τ_eq, and with
    delay_source = "geometry" a larger largest-stable K, in evaluate and evaluate_batch."""
    fast = replace(GEOMETRY, **faster)
    a, b = evaluate(GEOMETRY).response, evaluate(fast).response
    assert b["torque_delay_s"] < a["torque_delay_s"]
    assert b["max_stable_K_torque_delay_N_per_m"] > a["max_stable_K_torque_delay_N_per_m"]
    fields = {"gap": [0.5e-3, 0.7e-3]}
    ra = evaluate_batch(fields, GEOMETRY, stability=True)
    rb = evaluate_batch(fields, fast, stability=True)
    assert np.all(rb["torque_delay_s"] < ra["torque_delay_s"])
    assert np.all(rb["max_stable_K_N_per_m"] > ra["max_stable_K_N_per_m"])


def test_batch_column_matches_evaluate():
    row = evaluate_batch({"gap": [PAPER.clutch.gap]}, GEOMETRY, stability=True)
    ev = evaluate(GEOMETRY).response
    # one quadrature for both (RISE_NODES); only the solved ends' tolerance differs
    assert row["torque_delay_s"][0] == pytest.approx(ev["torque_delay_s"], rel=1e-6)


def test_design_default_is_fixed():
    assert ClutchDesign().operating.delay_source == "fixed"
    with pytest.raises(Exception, match="delay_source"):
        Operating(delay_source="geo")


def test_plot_torque_step(tmp_path):
    from mrclutch.cli.plots.dynamics import plot_torque_step

    out = tmp_path / "step.png"
    from geometry.section import build_section
    from magnetics.dynamics import torque_response

    resp = torque_response(build_section(PAPER.clutch).table, PAPER.current_limit)
    plot_torque_step([("paper", resp)], out, typed_delay=1e-3)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
