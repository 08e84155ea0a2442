"""Issue 41, items 3–5 wired: the hot holds (η(T), τy(T), the coil's R(T) fed back), the
fluid's life, the b1 budget's new terms, ``[duty]`` and ``--duty``."""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from dataclasses import replace

import numpy as np
import pytest

from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.amplifier import supply_current
from magnetics.drag import drag_terms, totals
from magnetics.hot import tau_y_factor
from magnetics.materials import FLUIDS
from magnetics.torque import torque_curve
from mrclutch import duty as D
from mrclutch.design import design_from_mapping, design_preset, design_to_toml
from mrclutch.hot_range import resolved_ranges
from mrclutch.pipeline import evaluate

PAPER = design_preset("paper")


@pytest.fixture(scope="module")
def ctx() -> D.Context:
    d, op = PAPER, PAPER.operating
    s = build_section(d.clutch, d.materials)
    cur = np.linspace(0.0, d.current_limit, D.GRID)
    tc = torque_curve(s, cur, method="network", speed_rpm=op.input_speed_rpm, support=d.support)
    return D.context(s.table, cur, tc.yield_torque, d.current_limit, op.input_speed,
                     d.support, d.amplifier, op.ambient_temperature, 130.0,
                     op.wire_temperature_limit)  # fmt: skip


@pytest.fixture(scope="module")
def ev():
    return evaluate(replace(PAPER, duty=D.Duty(torque=0.2, time=60.0)))


def test_drag_follows_the_viscosity_law(ctx: D.Context) -> None:
    """The closed form (films ∝ η(T), bearings and seal apart) is the drag module's own sum
    at 20, 60 and 120 °C; a planted η at 20 °C would miss 60 °C by a factor 2.5."""
    for t in (20.0, 60.0, 120.0):
        off, damp = totals(drag_terms(ctx.rg, ctx.slip_speed, t, PAPER.support))
        got = D.drag_at(ctx, t)
        assert got[0] == pytest.approx(float(off), rel=1e-12)
        assert got[1] == pytest.approx(float(damp), rel=1e-12)
    assert D.drag_at(ctx, 20.0)[1] / D.drag_at(ctx, 60.0)[1] > 2.0


def test_peak_hold_current_is_capped_by_the_hot_coil(ctx: D.Context) -> None:
    """At the end of 30 s at the limit the current is min(7 A, 24 V / R(T_coil)): the hot
    coil's R(T) (copper law) is what caps it; a planted R at 20 °C would leave 7 A."""
    h = D.hold(ctx, D.peak_load(ctx), 30.0, evaluate(PAPER).mr, PAPER.transmission.reduction,
               100.0)  # fmt: skip
    cap = float(supply_current(ctx.rg.fields, ctx.rg.at, PAPER.amplifier,
                               h["coil_temperature_C"]))  # fmt: skip
    assert h["current_A"] == pytest.approx(min(PAPER.current_limit, cap), rel=1e-12)
    assert h["current_A"] < PAPER.current_limit  # the paper's 24 V cannot hold 7 A hot
    assert h["beyond_wire_limit"]


def test_torque_at_scales_the_yield_by_tau_y_and_adds_the_hot_drag(ctx: D.Context) -> None:
    """At (coil, fluid, housing) = (60, 80, 50) °C and 3 A: τy factor × the cold yield
    interpolated at 3 A + the drag at 80 °C. Each part is checked against its own module."""
    temps = np.array([60.0, 80.0, 50.0])
    f = float(tau_y_factor(FLUIDS["mrf_132dg"], 80.0))
    y = float(np.interp(3.0, ctx.currents, ctx.yield_cold))
    off = float(totals(drag_terms(ctx.rg, ctx.slip_speed, 80.0, PAPER.support))[0])
    assert D.torque_at(ctx, 3.0, temps) == pytest.approx(f * y + off, rel=1e-12)
    assert f < 1.0  # the hot fluid is weaker


def test_duty_hold_holds_its_torque_with_a_rising_current(ctx: D.Context, ev) -> None:
    """0.2 N·m for 60 s: the torque is held to the end and the current at the end is more
    than at the start (τy(T) falls as the fluid warms; with τy(T) planted away it would not
    rise at all beyond what the falling drag asks)."""
    h = ev.duty["duty"]
    assert h["torque_N_m"] == pytest.approx(0.2, rel=1e-9) and h["held"]
    cold = D.duty_current(ctx, 0.2, np.full(3, 20.0))
    assert h["current_A"] > cold * 1.01
    assert h["fluid_temperature_C"] > 40.0


def test_hot_b1_is_the_cold_b1_plus_the_films_change(ctx: D.Context, ev) -> None:
    """b1(T) = b1(20 °C) + 2 r² (c(T) − c(20 °C)), r the transmission's reduction (Eq. 3):
    recomputed from the fluid temperature the hold reports."""
    h = ev.duty["duty"]
    r2 = 2 * PAPER.transmission.reduction**2
    dc = D.drag_at(ctx, h["fluid_temperature_C"])[1] - D.drag_at(ctx, 20.0)[1]
    assert h["b1_N_s_per_m"] == pytest.approx(float(ev.mr.b1) + r2 * dc, rel=1e-9)
    assert h["b1_N_s_per_m"] < float(ev.mr.b1)


def test_b1_budget_hand_worked() -> None:
    """Films 0.268, seal 0, plastic 0, warmed −0.2: total 0.068 against Table 2's 1.0,
    unexplained 0.932; each share is value / 1.0. A seal's Coulomb torque adds nothing."""
    b = D.b1_budget(0.268, 0.0, 0.05, -0.2)
    assert b["total"] == pytest.approx(0.068, rel=1e-12)
    assert b["unexplained"] == pytest.approx(0.932, rel=1e-12)
    assert [t["share_of_table2"] for t in b["terms"]] == pytest.approx([0.268, 0, 0, -0.2])
    assert "50 mN·m" in b["terms"][1]["source"]
    assert len(D.b1_budget(0.268, 0.0, 0.0, None)["terms"]) == 3


def test_life_in_the_evaluation(ev) -> None:
    """The life is LDE·V/P̄ with P̄ = (0.25 × 0.2 + 0.75 × T_off) ω, the evaluation's own
    volume and drag."""
    f = ev.duty["fluid"]
    w = PAPER.operating.input_speed
    p = (0.25 * 0.2 + 0.75 * float(ev.clutch.off_state_torque)) * w
    assert f["mean_power_W"] == pytest.approx(p, rel=1e-6)
    assert f["life_h"] == pytest.approx(5e12 * f["volume_m3"] / p / 3600, rel=1e-6)
    assert f["volume_mL"] == pytest.approx(2.8, rel=0.02)


def test_duty_in_the_design_file_round_trips_and_is_checked() -> None:
    d = replace(PAPER, duty=D.Duty(torque=0.2, time=60.0, on_fraction=0.5))
    back = design_from_mapping(tomllib.loads(design_to_toml(d)))
    assert back.duty == d.duty
    with pytest.raises(ParameterError, match=r"duty\.on_fraction"):
        design_from_mapping({"clutch": {"base": "paper"}, "duty": {"on_fraction": 2.0}})
    with pytest.raises(ParameterError, match="unknown key"):
        design_from_mapping({"clutch": {"base": "paper"}, "duty": {"torque": 0.2}})
    assert D.parse_duty("0.3:10") == D.Duty(torque=0.3, time=10.0)
    with pytest.raises(ParameterError, match="NM:S"):
        D.parse_duty("0.3")


def test_evaluate_json_and_bad_duty_on_the_command_line() -> None:
    run = [sys.executable, "-m", "mrclutch", "evaluate", "--preset", "paper", "--no-uncertainty"]
    out = subprocess.run([*run, "--duty", "0.2:60", "--json"], capture_output=True, text=True,
                         check=True)  # fmt: skip
    data = json.loads(out.stdout)["duty"]
    assert data["asked"]["torque_N_m"] == 0.2 and data["duty"]["held"]
    assert data["peak"]["time_s"] == 30.0
    bad = subprocess.run([*run, "--duty=0.2:0"], capture_output=True, text=True)
    assert bad.returncode == 2
    assert bad.stderr.count("\n") == 1 and "--duty '0.2:0': time = 0 s" in bad.stderr


def test_batch_columns_are_the_evaluations_figures(ev) -> None:
    """The sweep's fluid volume and life of the paper row equal ``evaluate``'s (same
    duty: 0.2 N·m a quarter of the time); a wider gap holds more fluid and lasts longer."""
    from mrclutch.pipeline import BatchEvaluator

    base = ev.design
    gap = base.clutch.gap
    be = BatchEvaluator(base, optional=D.DUTY_COLUMNS)
    rows = be({"gap": np.array([gap, 1.3 * gap])})
    assert rows["fluid_volume_m3"][0] == pytest.approx(ev.duty["fluid"]["volume_m3"], rel=1e-9)
    assert rows["fluid_life_h"][0] == pytest.approx(ev.duty["fluid"]["life_h"], rel=1e-6)
    assert rows["fluid_volume_m3"][1] > rows["fluid_volume_m3"][0]
    assert rows["fluid_life_h"][1] > rows["fluid_life_h"][0]


def test_optimiser_life_limit_splits_two_gaps() -> None:
    """A limit between the lives of two gaps: the thinner gap (less fluid, more drag)
    fails it (g > 0), the wider passes (g < 0); a planted sign error would swap them."""
    from mrclutch.optimize import Constraints, evaluate_rows

    base = replace(PAPER, duty=D.Duty(torque=0.2, time=60.0))
    gap = base.clutch.gap
    f = {"gap": np.array([0.6 * gap, 1.4 * gap])}
    lives = D.duty_batch(f, base, evaluate_rows(f, base, Constraints().resolved(base)))
    limit = float(np.sqrt(lives["fluid_life_h"][0] * lives["fluid_life_h"][1]))
    cons = Constraints(min_life=limit).resolved(base)
    g = cons.terms(evaluate_rows(f, base, cons))["fluid life"]
    assert g[0] > 0 > g[1]
    with pytest.raises(ParameterError, match="min_life"):
        Constraints(min_life=-1.0)


def test_text_and_report_section_carry_the_figures(ev) -> None:
    """The evaluate text and the report's section show the holds, the volume, the life and
    the b1 terms from the same JSON."""
    from mrclutch.cli.duty_format import duty_html, duty_lines

    text = "\n".join(duty_lines(ev.duty))
    f = ev.duty["fluid"]
    assert f"fluid: {f['volume_mL']:.3g} mL" in text
    assert f"{f['life_h']:.4g} h" in text
    assert "after 60 s holding 0.2 N·m" in text and "after 30 s at the current limit" in text
    page = duty_html(ev.duty)
    assert page.startswith("<h2>") and page.count("<li>") == len(duty_lines(ev.duty)) - 2
    assert "N·s/m" in page and "&lt;" not in text


def test_hot_corner_says_when_the_duty_leaves_the_uncertainty_range(ev) -> None:
    """The paper's default range is 20–40 °C (20 K of warming, typed); the 0.2 N·m duty
    warms the fluid past 40 °C, so it is not covered and the text says so; with the range
    widened to the duty's temperature it is."""
    from mrclutch.cli.duty_format import duty_lines

    hc = ev.duty["hot_corner"]
    assert hc["range_C"] == [20.0, 40.0]
    assert hc["duty_fluid_temperature_C"] == ev.duty["duty"]["fluid_temperature_C"] > 40.0
    assert hc["covered"] is False
    assert any("past the [uncertainty] range" in s for s in duty_lines(ev.duty))
    wide = replace(resolved_ranges(ev.design), fluid_temperature=(20.0, 90.0))
    widened = replace(ev.design, uncertainty=wide)
    assert D.hot_corner(widened, ev.duty["duty"], resolved_ranges(widened))["covered"]
    assert D.hot_corner(ev.design, None, resolved_ranges(ev.design))["covered"] is None


def test_a_hold_moves_b1_from_the_operating_fluid_temperature() -> None:
    """b1 of the evaluation is taken at the operating fluid temperature; a hold changes it
    by the films' damping from there to the hold's own temperature (it was taken from
    20 °C: a design run hot, fluid_temperature_C = 130, got b1 = -0.22 N·s/m and was
    refused). With the films' damping falling as the fluid warms, b1 stays positive and no
    hold's b1 lies on the wrong side of the evaluation's for its temperature."""
    table = {"clutch": {"base": "paper"}, "operating": {"fluid_temperature_C": 130}}
    d = design_from_mapping(table, "hot.toml")
    ev = evaluate(d)
    duty = ev.duty
    b1 = float(ev.mr.b1)
    peak = duty["peak"]
    assert 0 < peak["b1_N_s_per_m"]
    ctx_t = peak["fluid_temperature_C"]
    # the hold's fluid is cooler than 130 °C (it starts from ambient): thicker films, more b1
    assert (peak["b1_N_s_per_m"] >= b1) == (ctx_t <= 130.0)


def test_sweep_hot_columns_are_evaluate_json_of_the_same_design() -> None:
    """``sweep --with`` the hot columns (``BatchEvaluator`` with ``HOT_COLUMNS``, what a
    sweep runs) of the paper row equal ``evaluate --json --duty 0.2:60`` of the paper
    design: the torque and b1 after the 30 s peak hold and after the duty hold. The
    duty's torque is held (0.2 N·m); a 1.3× gap gives another design (less peak torque:
    the fluid's τy fills a wider gap with a weaker field), so the row is its own."""
    run = [sys.executable, "-m", "mrclutch", "evaluate", "--preset", "paper", "--no-uncertainty",
           "--duty", "0.2:60", "--json"]  # fmt: skip
    data = json.loads(subprocess.run(run, capture_output=True, text=True, check=True).stdout)
    from mrclutch.pipeline import BatchEvaluator

    base = replace(PAPER, duty=D.Duty(torque=0.2, time=60.0))
    gap = base.clutch.gap
    rows = BatchEvaluator(base, optional=D.HOT_COLUMNS)({"gap": np.array([gap, 1.3 * gap])})
    d = data["duty"]
    want = {"hot_peak_torque_N_m": d["peak"]["torque_N_m"],
            "hot_peak_b1_N_s_per_m": d["peak"]["b1_N_s_per_m"],
            "duty_end_torque_N_m": d["duty"]["torque_N_m"],
            "duty_end_b1_N_s_per_m": d["duty"]["b1_N_s_per_m"]}  # fmt: skip
    for key, value in want.items():
        assert rows[key][0] == pytest.approx(value, rel=1e-9), key
    assert rows["duty_end_torque_N_m"][0] == pytest.approx(0.2, rel=1e-3)
    assert rows["hot_peak_torque_N_m"][1] < rows["hot_peak_torque_N_m"][0]
    none = BatchEvaluator(PAPER, optional=D.HOT_COLUMNS)({"gap": np.array([gap])})
    assert np.isnan(none["duty_end_torque_N_m"][0]) and np.isnan(none["duty_end_b1_N_s_per_m"][0])
    assert none["hot_peak_torque_N_m"][0] == pytest.approx(rows["hot_peak_torque_N_m"][0])


def test_batched_hot_columns_are_the_per_design_figures() -> None:
    """``mrclutch.hot_rows.hot_batch`` (what the sweep runs: every design of a fluid marched
    at once) gives ``duty.hot_batch``'s figures (design by design) to 1e-9 on varied rows:
    1, 2 and 5 drums, two gaps, two fluids (two marches), an invalid row (NaN in both), a
    1-drum row whose duty current is capped (min(limit, V/R(T)): the 0.2 N·m not held) and a
    0.25 mm wire row whose peak current is capped by the supply, V/R(T) of the hot coil,
    below its current limit at the hold's end (both checked on the per-design hold)."""
    from mrclutch import hot_rows
    from mrclutch.at_hand import mr_at_hand
    from mrclutch.fast_batch import evaluate_batch

    base = replace(PAPER, duty=D.Duty(torque=0.2, time=60.0))
    fields = {"n_drums": np.array([2, 1, 5, 2, 2, 2, 3]),
              "gap": np.array([0.7, 0.7, 0.5, 0.4, 0.7, 0.7, 0.001]) * 1e-3,
              "wire_diameter": np.array([0.321, 0.321, 0.321, 0.321, 0.25, 0.321, 0.321]) * 1e-3,
              "fluid": np.array(["mrf_132dg"] * 5 + ["mrf_140cg", "mrf_132dg"])}  # fmt: skip
    r = evaluate_batch(fields, base)
    assert list(r["valid"] > 0) == [True] * 6 + [False]
    ok = r["valid"] > 0
    mr = mr_at_hand(base, r["rotor_inertia_kg_m2"][ok] + r["fluid_inertia_kg_m2"][ok],
                    r["drag_damping_N_m_s"][ok], r["max_torque_N_m"][ok],
                    r["clutch_mass_kg"][ok], r["torque_delay_s"][ok])  # fmt: skip
    ref = D.hot_batch(fields, base, r, mr)
    got = hot_rows.hot_batch(fields, base, r, mr)
    for key in D.HOT_COLUMNS:
        assert np.isnan(got[key][6]) and np.isnan(ref[key][6]), key
        np.testing.assert_allclose(got[key][:6], ref[key][:6], rtol=1e-9, err_msg=key)
    # the caps bind where the docstring says (the per-design holds of those rows)
    one = replace(base, clutch=replace(base.clutch, n_drums=1))
    c1 = D.design_context(one, one.current_limit)
    end = D.hold(c1, D.duty_load(c1, 0.2), 60.0, mr.item(1), 1.0, 1e3)
    cap = min(one.current_limit, D.supply_at(c1, end["coil_temperature_C"]))
    assert end["current_A"] == pytest.approx(cap) and end["torque_N_m"] < 0.2
    many = replace(base, clutch=replace(base.clutch, wire_diameter=0.25e-3))
    c4 = D.design_context(many, many.current_limit)
    peak = D.hold(c4, D.peak_load(c4), 30.0, mr.item(4), 1.0, 1e3)
    assert peak["current_A"] < many.current_limit * 0.99
    assert peak["current_A"] == pytest.approx(D.supply_at(c4, peak["coil_temperature_C"]))


def test_interp_rows_is_np_interp_per_row() -> None:
    """Row by row np.interp, ends and a flat run (repeated knots) included."""
    from mrclutch.hot_rows import interp_rows

    xp = np.array([[0.0, 1.0, 2.0, 3.0], [0.0, 0.5, 0.5, 2.0], [1.0, 2.0, 4.0, 8.0]])
    fp = np.array([[0.0, 2.0, 3.0, 7.0], [1.0, 2.0, 5.0, 6.0], [0.0, 1.0, 2.0, 3.0]])
    for x in (-1.0, 0.0, 0.25, 0.5, 1.5, 2.0, 3.0, 5.0, 9.0):
        got = interp_rows(np.full(3, x), xp, fp)
        want = [np.interp(x, xp[k], fp[k]) for k in range(3)]
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-15, err_msg=str(x))


def test_march_batch_is_march_of_each_design() -> None:
    """Two networks stacked, each with its own load law: march_batch's temperatures are
    march's of each one (1e-12)."""
    from magnetics.hot import Load, march, march_batch
    from magnetics.thermal import Network, network

    rg = build_section(PAPER.clutch, PAPER.materials).table
    one = network(rg, 25.0, 130.0)
    two = replace(one, capacity=np.asarray(one.capacity) * 1.7, r20=float(one.r20) * 0.8)
    nets = (one, two)
    stack = Network(np.stack([np.asarray(n.capacity).reshape(3) for n in nets]),
                    np.stack([np.asarray(n.conductance).reshape(3, 3) for n in nets]),
                    np.array([float(n.to_air) for n in nets]),
                    np.array([float(n.r20) for n in nets]), 25.0,
                    np.stack([np.asarray(n.inverse).reshape(3, 3) for n in nets]))  # fmt: skip
    laws = [lambda t: (7.0 - 0.01 * t[0], 0.5 + 0.01 * t[1]), lambda t: (3.0, 2.0 - 0.005 * t[2])]
    m = march_batch(stack, lambda t: tuple(np.array([laws[k](t[k])[j] for k in range(2)])
                                            for j in range(2)), 40.0, 50)  # fmt: skip
    for k, net in enumerate((one, two)):
        ref = march(net, lambda t, k=k: Load(*laws[k](t)), 40.0, 50)
        np.testing.assert_allclose(m.temperatures[:, k], ref.temperatures, rtol=1e-12)
        np.testing.assert_allclose(m.currents[:, k], ref.currents, rtol=1e-12)
