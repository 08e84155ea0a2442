"""mrclutch.feel: the residual torque, the loop and the ripple of a design, at the hand."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from geometry.materials import MaterialChoice
from mrclutch.design import design_preset
from mrclutch.feel import FORCE_JND_PCT, feel_batch, feel_figures
from mrclutch.pipeline import clutch_figures


@pytest.fixture(scope="module")
def paper() -> tuple:
    d = design_preset("paper")
    f = clutch_figures(d)
    return d, f, feel_figures(d, f.max_torque, f.yield_torque, f.off_state_torque, 1.0)


def test_paper_hysteresis_is_negligible(paper: tuple) -> None:
    """The paper's "negligible magnetic hysteresis" (Fig. 2b): the loop's widest gap is
    below the hand's 7 % force JND of the full-scale torque; the pulse train leaves less
    than a tenth of the residual; the residual adds its force to the backdrive force."""
    d, f, out = paper
    h = out["hysteresis"]
    assert h["negligible"] and 0 < h["hysteresis_width_pct"] < FORCE_JND_PCT
    assert 0 < h["residual_torque_after_pulse_N_m"] < h["residual_torque_N_m"] / 10
    assert h["residual_force_N"] == pytest.approx(
        h["residual_torque_N_m"] * d.transmission.reduction
    )
    assert h["backdrive_force_with_residual_N"] == pytest.approx(1.0 + h["residual_force_N"])
    assert h["dynamic_range_with_residual_dB"] < f.dynamic_range_db


def test_paper_ripple(paper: tuple) -> None:
    """Ripple at the slip frequency 530/60 = 8.83 Hz; its force is its torque × nG/l."""
    d, _, out = paper
    r = out["ripple"]
    assert r["ripple_frequency_hz"] == pytest.approx(530 / 60)
    assert r["ripple_force_N"] == pytest.approx(r["ripple_torque_N_m"] * d.transmission.reduction)
    e = d.process.runout / 2
    assert r["ripple_torque_N_m"] == pytest.approx(e * e * r["d2_torque_d_gap2_N_m_per_m2"] / 2)


def test_batch_is_the_single_design(paper: tuple) -> None:
    d, _, out = paper
    b = feel_batch({"gap": np.array([d.clutch.gap])}, d)
    assert b["residual_torque_N_m"][0] == pytest.approx(out["hysteresis"]["residual_torque_N_m"],
                                                        rel=1e-6)  # fmt: skip
    assert b["hysteresis_width_pct"][0] == pytest.approx(
        out["hysteresis"]["hysteresis_width_pct"], rel=1e-6
    )
    assert b["ripple_torque_N_m"][0] == pytest.approx(out["ripple"]["ripple_torque_N_m"],
                                                      rel=1e-3)  # fmt: skip


def test_a_harder_steel_leaves_more_torque() -> None:
    """steel 1117 (Hc 320 A/m) against pure iron (80 A/m) in every steel part."""
    d = design_preset("paper")
    soft = replace(d, materials=MaterialChoice(core="pure_iron", drums="pure_iron",
                                               shell="pure_iron"))  # fmt: skip
    hard = replace(d, materials=MaterialChoice(core="steel_1117", drums="steel_1117",
                                               shell="steel_1117"))  # fmt: skip
    r = [feel_batch({"gap": np.array([d.clutch.gap])}, x, ("residual_torque_N_m",))
         ["residual_torque_N_m"][0] for x in (soft, hard)]  # fmt: skip
    assert r[1] > 2 * r[0] > 0


def test_the_optimiser_limits_residual_torque_and_ripple() -> None:
    """A limit between two designs' figures passes one and fails the other: the residual
    torque falls as the gap widens (0.5 → 0.9 mm), the ripple too (T'' ∝ 1/g³-like)."""
    from mrclutch.optimize import Constraints, evaluate_rows

    d = design_preset("paper")
    fields = {"gap": np.array([0.5e-3, 0.9e-3])}
    probe = feel_batch(fields, d)
    res, rip = probe["residual_torque_N_m"], probe["ripple_force_N"]
    assert res[0] > res[1] and rip[0] > rip[1]
    cons = Constraints(max_residual_torque=float(res.mean()), max_ripple_force=float(rip.mean()),
                       passive=False, stable=False).resolved(d)  # fmt: skip
    g = cons.terms(evaluate_rows(fields, d, cons))
    assert g["residual torque"][0] > 0 > g["residual torque"][1]
    assert g["ripple"][0] > 0 > g["ripple"][1]
    plain = Constraints(passive=False, stable=False).resolved(d)
    assert "ripple" not in plain.terms(evaluate_rows(fields, d, plain))
