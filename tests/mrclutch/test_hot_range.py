"""The hot corner of ``[uncertainty]`` derived from the thermal model (issue 41, item 3):
``fluid_temperature_C = "duty"`` (mrclutch/hot_range.py)."""

from __future__ import annotations

import tomllib
from dataclasses import replace

import numpy as np
import pytest

from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.hot import march
from magnetics.materials import FLUIDS
from magnetics.torque import torque_curve
from mrclutch import duty as D
from mrclutch.cli.duty_format import duty_lines
from mrclutch.design import design_from_mapping, design_to_toml
from mrclutch.hot_range import duty_end_temperature, duty_range, resolved_ranges
from mrclutch.optimize import process_uncertainty
from mrclutch.pipeline import evaluate
from mrclutch.robust import hand_box_batch, robust_verdicts
from mrclutch.uncertainty import RANGE_FROM, range_from

TABLE = {"clutch": {"base": "paper"}, "uncertainty": {"fluid_temperature_C": "duty"},
         "duty": {"torque_N_m": 0.2, "time_s": 60}}  # fmt: skip


@pytest.fixture(scope="module")
def hot():
    return design_from_mapping(TABLE, "hot.toml")


def test_duty_range_hand_worked() -> None:
    """Operating 20 °C, the duty's end 55.5 °C, MRF-132DG's range [−40, 130] °C: the range is
    [20, 55.5]; a duty ending at 200 °C is capped at the fluid's 130; one ending below the
    operating temperature (a clutch run at 60 °C, the march from 20 °C ambient ending at
    40) leaves the point [60, 60]."""
    assert duty_range(20.0, 55.5, (-40.0, 130.0)) == (20.0, 55.5)
    assert duty_range(20.0, 200.0, (-40.0, 130.0)) == (20.0, 130.0)
    assert duty_range(60.0, 40.0, (-40.0, 130.0)) == (60.0, 60.0)


def test_the_range_ends_where_the_duty_hold_ends(hot) -> None:
    """The hot end is the fluid node's temperature after 0.2 N·m held 60 s: the same march
    as ``evaluate``'s duty figures (so the duty is covered, to the last bit), above the
    default's 40 °C; the cold end the operating 20 °C; the typed and the default ranges
    are left alone."""
    u = resolved_ranges(hot)
    ev = evaluate(hot)
    t_duty = ev.duty["duty"]["fluid_temperature_C"]
    assert u.fluid_temperature == (20.0, t_duty)
    assert 40.0 < t_duty < FLUIDS[hot.materials.fluid].temperature_range[1]
    want = {"range_C": [20.0, t_duty], "range_from": "duty", "duty_fluid_temperature_C": t_duty,
            "covered": True}  # fmt: skip
    assert ev.duty["hot_corner"] == want
    assert robust_verdicts(ev)["uncertainty"]["fluid_temperature"] == (20.0, t_duty)
    typed = design_from_mapping({**TABLE, "uncertainty": {"fluid_temperature_C": [20, 45]}}, "t")
    assert resolved_ranges(typed).fluid_temperature == (20.0, 45.0)
    assert range_from(typed) == "typed"
    plain = design_from_mapping({"clutch": {"base": "paper"}}, "p")
    assert resolved_ranges(plain).fluid_temperature == (20.0, 40.0)
    assert range_from(plain) == "default"
    text = "\n".join(duty_lines(ev.duty))
    assert f"20–{t_duty:.3g} °C, {RANGE_FROM['duty']}" in text


def test_end_temperature_is_the_thermal_march_of_the_duty(hot) -> None:
    """Redone by hand from the pieces: the network's cold yield curve on 17 currents, the
    context, the duty's load and 300 steps of the march; without a duty torque the hold is
    the current limit for peak_time_s (the paper: ~92 °C after 30 s, past 55 °C)."""
    op = hot.operating
    s = build_section(hot.clutch, hot.materials)
    cur = np.linspace(0.0, hot.current_limit, D.GRID)
    tc = torque_curve(s, cur, method="network", speed_rpm=op.input_speed_rpm, support=hot.support)
    ctx = D.context(s.table, cur, tc.yield_torque, hot.current_limit, op.input_speed,
                    hot.support, hot.amplifier, op.ambient_temperature, 130.0,
                    op.wire_temperature_limit)  # fmt: skip
    want = march(ctx.net, D.duty_load(ctx, 0.2), 60.0, D.STEPS).final[1]
    assert duty_end_temperature(hot) == (pytest.approx(want, rel=1e-12), "duty")
    peak = replace(hot, duty=D.Duty())
    t_peak, which = duty_end_temperature(peak)
    assert which == "peak"
    assert t_peak == pytest.approx(march(ctx.net, D.peak_load(ctx), 30.0, D.STEPS).final[1])
    assert t_peak > 80.0 > duty_end_temperature(hot)[0]
    assert resolved_ranges(peak).fluid_temperature == (20.0, t_peak)


def test_the_verdicts_box_takes_the_derived_range(hot) -> None:
    """η(T) falls with T, so the b1 floor of the box over [20, 55.5] °C lies below the one
    over the default [20, 40] by the films' drag ratio η(55.5)/η(40) < 1 (the other terms
    alike): the derived range reaches the verdicts."""
    fields = {f: np.array([v]) for f, v in vars(hot.clutch).items()}
    derived = hand_box_batch(fields, hot, resolved_ranges(hot))
    typed = replace(resolved_ranges(hot), fluid_temperature=(20.0, 40.0),
                    fluid_temperature_from="range")  # fmt: skip
    default = hand_box_batch(fields, hot, typed)
    assert derived.b1[1][0] < default.b1[1][0]  # (nominal, low, high)
    assert derived.b1[2][0] == pytest.approx(default.b1[2][0], rel=1e-12)  # the top: 20 °C


def test_the_optimiser_and_the_sweep_take_the_derived_range(hot) -> None:
    """The optimiser's worst case and the sweep's robust columns take the base design's
    ranges: with "duty", the derived one (never the unresolved None, which would judge
    every candidate at the operating temperature alone), its hot end then each row's own
    (``test_each_row_takes_its_own_duty_range``)."""
    assert process_uncertainty(hot).fluid_temperature == resolved_ranges(hot).fluid_temperature
    assert process_uncertainty(hot).fluid_temperature_from == "duty"
    assert resolved_ranges(hot).fluid_temperature[1] > 40.0


def _row(design, n_drums: int, gap: float, fluid: str = "mrf_132dg"):  # type: ignore[no-untyped-def]
    clutch = replace(design.clutch, n_drums=n_drums, gap=gap)
    return replace(design, clutch=clutch, materials=replace(design.materials, fluid=fluid))


def test_each_row_takes_its_own_duty_range(hot) -> None:
    """A sweep or optimiser batch around a "duty" design: each row's hot end is the end of
    its own duty hold (``hot_rows.duty_hot_ends``, all rows marched at once), the same as
    the design-by-design ``resolved_ranges`` of that row's design to 1e-9 — 1, 2 and 4
    drums, two gaps, a second fluid (its own march), an invalid row (NaN); the 1- and 4-drum
    rows' ends differ from the base's by more than 5 K, so the base's range misjudged them. The
    hand box's b1 floor of each row is the one over that row's own typed range; without a
    duty torque the hold is the current limit's (the peak)."""
    from mrclutch.hot_rows import duty_hot_ends

    rows = [(2, 0.7e-3, "mrf_132dg"), (1, 0.7e-3, "mrf_132dg"), (4, 0.5e-3, "mrf_132dg"),
            (2, 1.0e-3, "mrf_132dg"), (2, 0.7e-3, "mrf_140cg"), (2, 1e-6, "mrf_132dg")]  # fmt: skip
    fields = {"n_drums": np.array([r[0] for r in rows]), "gap": np.array([r[1] for r in rows]),
              "fluid": np.array([r[2] for r in rows])}  # fmt: skip
    ends = duty_hot_ends(fields, hot)
    assert np.isnan(ends[5])
    want = np.array([resolved_ranges(_row(hot, *r)).fluid_temperature[1] for r in rows[:5]])
    np.testing.assert_allclose(ends[:5], want, rtol=1e-9)
    assert ends[0] == pytest.approx(resolved_ranges(hot).fluid_temperature[1], rel=1e-9)
    assert np.all(np.abs(ends[1:3] - ends[0]) > 5.0)  # 1 drum: capped at 130 °C; 4 drums
    box = hand_box_batch(fields, hot, resolved_ranges(hot))
    for i in range(5):
        one = {k: v[i : i + 1] for k, v in fields.items()}
        typed = replace(resolved_ranges(hot), fluid_temperature=(20.0, float(want[i])),
                        fluid_temperature_from="range")  # fmt: skip
        assert box.b1[1][i] == pytest.approx(hand_box_batch(one, hot, typed).b1[1][0], rel=1e-9)
    peak = replace(hot, duty=D.Duty())
    two = {k: v[:2] for k, v in fields.items()}
    np.testing.assert_allclose(
        duty_hot_ends(two, peak),
        [resolved_ranges(_row(peak, *r)).fluid_temperature[1] for r in rows[:2]],
        rtol=1e-9,
    )


def test_round_trip_and_bad_values(hot) -> None:
    """The file keeps "duty" (not the resolved numbers); any other string is refused with
    the key named; an unresolved range never reaches the checks of the typed one."""
    back = design_from_mapping(tomllib.loads(design_to_toml(hot)), "hot.toml")
    assert back.uncertainty == hot.uncertainty
    assert back.uncertainty.fluid_temperature is None
    assert back.uncertainty.fluid_temperature_from == "duty"
    bad = {**TABLE, "uncertainty": {"fluid_temperature_C": "hot"}}
    with pytest.raises(ParameterError, match=r'fluid_temperature_C = .hot.: must be .*"duty"'):
        design_from_mapping(bad, "bad.toml")
    with pytest.raises(ParameterError, match="fluid_temperature_from = 'warm'"):
        replace(hot.uncertainty, fluid_temperature_from="warm")
