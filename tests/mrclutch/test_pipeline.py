"""The pipeline: batch fast path = per-design fast path; the haptic model fed by hand."""

from dataclasses import replace

import numpy as np
import pytest

from geometry import preset
from mrclutch.design import ClutchDesign, design_preset
from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.hand import hand_figures
from mrclutch.haptics.model import metrics
from mrclutch.outputs import SWEEP_COLUMNS
from mrclutch.pipeline import HAND_KEYS, evaluate, evaluate_batch, rendered

DESIGNS = [
    {},
    {"gap": 0.5e-3, "n_drums": 3},
    {"drum_thickness": 0.15e-3, "drum_inner_diameter": 10e-3},
    {"n_drums": 1, "zone_length": 4e-3},
]


@pytest.fixture(scope="module")
def batch():
    base = design_preset("paper")
    c0 = base.clutch
    fields = {
        k: np.array([d[k] if k in d else getattr(c0, k) for d in DESIGNS])
        for k in ("gap", "n_drums", "drum_thickness", "drum_inner_diameter", "zone_length")
    }
    return evaluate_batch(fields, base)


@pytest.mark.parametrize("i", range(len(DESIGNS)))
def test_batch_equals_single_design_fast_path(batch, i):
    d = ClutchDesign(clutch=replace(preset("paper"), **DESIGNS[i]))
    ev = evaluate(d, "fast")
    c, h = ev.clutch, ev.haptic
    assert batch["valid"][i] == 1
    pairs = {
        "rotor_inertia_kg_m2": c.rotor_inertia,
        "clutch_mass_kg": c.clutch_mass,
        "max_torque_N_m": c.max_torque,
        "fluid_inertia_kg_m2": c.fluid_inertia,
        "drag_damping_N_m_s": c.drag_damping,
        "off_state_torque_N_m": c.off_state_torque,
        "dynamic_range_dB": c.dynamic_range_db,
        "continuous_torque_N_m": c.thermal["continuous_torque_N_m"],
        "m1_kg": h["m1_kg"],
        "b1_N_s_per_m": h["b1_N_s_per_m"],
        "K_N_per_m": h["K_N_per_m"],
        "bandwidth_lumped_hz": h["bandwidth_lumped_hz"],
        "bandwidth_hz": h["bandwidth_hz"],
        "rendering_area_dB_decade": h["rendering_area_dB_decade"],
        "backdrive_force_N": ev.hand["mr"]["backdrive_force_N"],
        "torque_delay_s": ev.response["torque_delay_s"],
    }
    for key, single in pairs.items():
        assert batch[key][i] == pytest.approx(single, rel=1e-6), key


def test_invalid_rows_are_flagged_and_blank():
    out = evaluate_batch({"gap": np.array([0.3e-3, 0.01e-3, np.nan]), "n_drums": 2})
    assert out["valid"].tolist() == [1.0, 0.0, 0.0]
    for key in SWEEP_COLUMNS[1:]:
        assert np.isfinite(out[key][0]) or key == "resonance_hz", key
        assert np.isnan(out[key][1:]).all(), key


def test_evaluation_feeds_the_haptic_model_as_by_hand():
    """The MR pair's metrics equal the haptic model fed by hand with the same m1, b1, k, b, m2."""
    ev = evaluate(design_preset("paper"))
    h = ev.haptic
    tr = ev.design.transmission
    r = tr.reduction
    m1 = 2 * (ev.clutch.rotor_inertia + ev.clutch.fluid_inertia) * r**2  # Eq. 3, the pair
    b1 = 2 * ev.clutch.drag_damping * r**2
    assert h["m1_kg"] == pytest.approx(m1, rel=1e-12)
    assert h["b1_N_s_per_m"] == pytest.approx(b1, rel=1e-12)
    by_hand = metrics(
        HapticParams(m1=m1, b1=b1, k=tr.k, b=tr.b, m2=tr.m2, delay=1e-3),
        K=h["K_N_per_m"],
    )
    for key, v in by_hand.items():
        if isinstance(v, float) and np.isnan(v):
            assert np.isnan(h[key]), key
        else:
            assert h[key] == pytest.approx(v, rel=1e-9), key


def test_motor_is_geared_to_the_same_force_and_stiffness():
    ev = evaluate(design_preset("paper"))
    assert float(ev.motor.f_max) == pytest.approx(float(ev.mr.f_max), rel=1e-12)
    assert ev.motor_metrics["K_N_per_m"] == pytest.approx(ev.haptic["K_N_per_m"], rel=1e-12)
    # a heavier motor rotor: the motor's reflected mass dominates
    assert ev.motor_metrics["m1_kg"] > 10 * ev.haptic["m1_kg"]


@pytest.mark.parametrize(
    "change",
    [
        {},
        {"gap": 0.5e-3},
        {"zone_length": 5e-3, "n_drums": 2},
        # the optimum `mrclutch optimize` finds (4 drums at the bounds of the search box)
        {"n_drums": 4, "gap": 0.2008e-3, "drum_thickness": 0.1014e-3,
         "drum_inner_diameter": 16.45e-3, "zone_length": 3.964e-3},
    ],
)  # fmt: skip
def test_fast_bandwidth_within_its_stated_error_of_reference(change):
    from mrclutch.pipeline import FAST_BANDWIDTH_ERROR

    d = ClutchDesign(clutch=replace(preset("paper"), **change))
    fast = evaluate(d, "fast").haptic["bandwidth_hz"]
    ref = evaluate(d, "reference").haptic["bandwidth_hz"]
    assert abs(fast / ref - 1) <= FAST_BANDWIDTH_ERROR


def test_evaluation_carries_the_zwidth_of_both_sides():
    """The Z-width's K intercept is the largest passive K of the metrics (two methods that
    share no code path beyond the model), for the MR pair and for the motor; the rendered
    K lies inside the MR pair's Z-width exactly when the pair is passive at K."""
    ev = evaluate(design_preset("paper"))
    for side, m in (("mr", ev.haptic), ("motor", ev.motor_metrics)):
        zw = ev.zwidth[side]
        assert zw["K_max_at_B0_N_per_m"] == pytest.approx(m["max_passive_K_N_per_m"], rel=1e-6)
        assert zw["zwidth_area_N2_s_per_m2"] <= zw["zwidth_area_upper_N2_s_per_m2"]
    inside = ev.haptic["K_N_per_m"] <= ev.zwidth["mr"]["K_max_at_B0_N_per_m"]
    assert inside == ev.haptic["passive"]
    # the geared motor's larger b1 buys it a far larger passive set [colgate-brown1994]
    area = {side: zw["zwidth_area_N2_s_per_m2"] for side, zw in ev.zwidth.items()}
    assert area["motor"] > area["mr"]


def test_max_torque_is_the_network_curve_with_its_own_bound():
    """The sweep's max torque is the reluctance network's at the current limit and input
    speed (one design is a batch of one: torque_curve's default), with the network's own
    measured bound beside it; invalid rows are NaN."""
    from magnetics.error_map import circuit_error
    from magnetics.torque import torque_curve
    from mrclutch.design import current_limit

    base = design_preset("paper")
    f = {"gap": np.array([0.3e-3, 0.7e-3, 0.01e-3]), "n_drums": np.array([3.0, 2.0, 2.0])}
    out = evaluate_batch(f, base)
    op = base.operating
    for i in (0, 1):
        c = replace(base.clutch, gap=float(f["gap"][i]), n_drums=int(f["n_drums"][i]))
        i_max = current_limit(op, c.wire_diameter)
        tc = torque_curve(c, [i_max],
                          speed_rpm=op.input_speed_rpm, temperature=op.fluid_temperature,
                          support=base.support)  # fmt: skip
        assert tc.method == "network"
        assert out["max_torque_N_m"][i] == pytest.approx(tc.torque[0], rel=1e-9)
        # the sweep's Newton starts at the circuit-scaled linear start (fast_batch), the
        # single design's at the linear one: the same solution to the solve's tolerance
        assert out["torque_error_bound"][i] == pytest.approx(
            circuit_error(c, "network", i_max).bound, rel=1e-8
        )
    assert np.isnan(out["max_torque_N_m"][2]) and np.isnan(out["torque_error_bound"][2])


def test_a_current_density_cap_is_a_note_not_a_silent_change():
    """Issue 34: 60 A/mm² in the paper's 0.321 mm wire allows 4.856 A, not the typed 7 A;
    the evaluation runs at the cap and says so; an unbinding limit says nothing."""
    from mrclutch.design import Operating

    paper = design_preset("paper")
    capped = replace(paper, operating=Operating(max_current_density=60e6))
    cap = 60e6 * np.pi * paper.clutch.wire_diameter**2 / 4
    ev = evaluate(capped)
    assert ev.clutch.max_current == pytest.approx(cap, rel=1e-12)
    (note,) = [n for n in ev.clutch.notes if "current-density limit caps" in n]
    assert f"{cap:.4g} A" in note and "max_current_A = 7" in note
    assert "max_current_density_A_per_mm2" in note
    # the default limit (IEC 60949) binds too below a thin enough wire: its source is named
    thin = replace(paper, clutch=replace(paper.clutch, wire_diameter=0.2e-3))
    (note,) = [n for n in evaluate(thin).clutch.notes if "current-density limit" in n]
    assert "IEC 60949" in note
    assert not [n for n in evaluate(paper).clutch.notes if "current-density" in n]
    loose = replace(paper, operating=Operating(max_current_density=1e9))
    assert not [n for n in evaluate(loose).clutch.notes if "current-density" in n]


def test_hand_keys_are_the_keys_hand_figures_returns():
    """HAND_KEYS (the keys of a side whose hand figures are unavailable) is a hand-written
    copy of ``hand_figures``' keys: it must follow them, nested ones included, or an
    unavailable side's JSON would differ in shape from an available one's."""

    def shape(d):
        return {k: shape(v) if isinstance(v, dict) else None for k, v in d.items()}

    full = shape(hand_figures(TABLE2_MR, float(TABLE2_MR.k_max)))
    full.pop("notes")  # the unavailable side writes its own (empty) notes and a note
    assert shape(HAND_KEYS) == full


def test_sweep_max_stable_K_column_is_the_per_design_limit():
    """The sweep's ``max_stable_K_N_per_m`` column (``evaluate_batch(stability=True)``, the
    batch kernel ``robust_search.stable_stiffness_batch``, issue 40) equals the exact
    per-design kernel ``max_stable_stiffness`` of each design's pair at the hand
    (``mr_at_hand`` of the row's figures) to 1e-9, on 12 random designs of 1–4 drums."""
    from mrclutch.haptics.model import max_stable_stiffness
    from mrclutch.pipeline import mr_at_hand

    rng = np.random.default_rng(3)
    n = 12
    f = {"gap": rng.uniform(0.3e-3, 0.9e-3, n), "n_drums": rng.integers(1, 5, n),
         "drum_thickness": rng.uniform(0.15e-3, 0.5e-3, n)}  # fmt: skip
    base = design_preset("paper")
    rows = evaluate_batch(f, base, stability=True)
    ok = rows["valid"] > 0
    assert ok.sum() >= 8  # most random designs are buildable: the check compares many
    hp = mr_at_hand(base, rows["rotor_inertia_kg_m2"] + rows["fluid_inertia_kg_m2"],
                    rows["drag_damping_N_m_s"], rows["max_torque_N_m"], rows["clutch_mass_kg"],
                    rows["torque_delay_s"])  # fmt: skip
    exact = np.array([max_stable_stiffness(hp.item(i)) for i in np.nonzero(ok)[0]])
    assert np.all(np.isfinite(exact))
    np.testing.assert_allclose(rows["max_stable_K_N_per_m"][ok], exact, rtol=1e-9)


def test_rendered_at_another_K_reuses_the_hand_search_with_the_same_figures():
    # issue 40: the verdict re-renders at the worst-case K; the hands' search does not
    # depend on K, so its figures are taken to the new K, equal to a search made there
    ev = evaluate(design_preset("paper"))
    lim = ev.hand["mr"]["max_stable_K_all_hands_N_per_m"]
    for K in (100.0, 0.5 * lim, 2.0 * lim):
        again = rendered(ev, K)
        fresh = {"mr": hand_figures(ev.mr, K), "motor": hand_figures(ev.motor, K)}
        assert again.hand == fresh
        assert again.hand_of[0] is ev.mr
    assert rendered(ev, 2.0 * lim).hand["mr"]["coupled_stable"] is False
    # a pair replaced on the evaluation is searched again, not taken from the old figures
    heavier = replace(ev, mr=replace(ev.mr, m2=ev.mr.m2 + 0.05))
    assert rendered(heavier, 100.0).hand["mr"] == hand_figures(heavier.mr, 100.0)
    assert rendered(heavier, 100.0).hand["mr"] != ev.hand["mr"]
