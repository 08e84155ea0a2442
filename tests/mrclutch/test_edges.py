"""Which edge of the hand box each uncertain input moves, and by how much, from its stated
source (mrclutch/uncertainty.py's SOURCES, mrclutch/process.py), independent of the robust
search: each input is switched on alone (``no_uncertainty`` elsewhere) and the box's edges
are compared with a hand-worked factor or with the nominal pipeline evaluated at the
input's end value (``evaluate_batch`` at another gap, temperature or thickness), never
with the robust module's own arithmetic.

The paper preset's nominal figures used below (``mrclutch evaluate --preset paper --json``):
K_max = F_max/d = 367.32 N/m, b1 = 0.26839 N·s/m, m1 = 1.4791 g, typed delay 1 ms, the
torque response's equivalent delay 2.1503 ms, gap 0.7 mm, fluid at 20 °C.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from magnetics.materials import FLUIDS
from mrclutch.design import ClutchDesign, design_preset
from mrclutch.optimize import process_uncertainty, search_box
from mrclutch.pipeline import evaluate_batch, mr_at_hand
from mrclutch.process import MAX_ECCENTRICITY, Process
from mrclutch.robust import hand_box_batch
from mrclutch.uncertainty import WARMING, Uncertainty, default_uncertainty, no_uncertainty


@pytest.fixture(scope="module")
def paper() -> ClutchDesign:
    return design_preset("paper")


def _fields(d: ClutchDesign, **change: float) -> dict[str, np.ndarray]:
    return {f: np.array([change.get(f, v)]) for f, v in vars(d.clutch).items()}


def _box(d: ClutchDesign, **inputs):
    """The hand box of ``d`` with only ``inputs`` uncertain (every other range nominal)."""
    return hand_box_batch(_fields(d), d, replace(no_uncertainty(d), **inputs))


def _edges(t) -> tuple[float, float, float]:
    return tuple(float(x[0]) for x in t)


def _hand(d: ClutchDesign, **change: float) -> tuple[float, float, float]:
    """(m1, b1, K_max) at the hand of ``d`` with fields changed, by the nominal pipeline."""
    rows = evaluate_batch(_fields(d, **change), d)
    hp = mr_at_hand(d, rows["rotor_inertia_kg_m2"] + rows["fluid_inertia_kg_m2"],
                    rows["drag_damping_N_m_s"], rows["max_torque_N_m"],
                    rows["clutch_mass_kg"], rows["torque_delay_s"])  # fmt: skip
    w = d.transmission.workspace
    return float(hp.m1[0]), float(hp.b1[0]), float(np.ravel(hp.f_max)[0] / w)


def test_with_no_uncertainty_every_edge_is_the_nominal(paper):
    """The reference point of the tests below: the paper preset's nominal at the hand
    (K 367.32 N/m, b1 0.26839 N·s/m, m1 1.4791 g, delay 1 ms) is every edge of the box."""
    box = _box(paper)
    m1, b1, K = _hand(paper)
    assert _edges(box.m1) == pytest.approx((m1, m1, m1), rel=1e-12)
    assert _edges(box.b1) == pytest.approx((b1, b1, b1), rel=1e-12)
    assert _edges(box.K) == pytest.approx((K, K, K), rel=1e-12)
    assert _edges(box.delay) == pytest.approx((1e-3, 1e-3, 1e-3), rel=1e-12)
    assert K == pytest.approx(367.32, rel=1e-4) and b1 == pytest.approx(0.26839, rel=1e-4)


# ---- the torque factor: yield stress and B–H lots move both K edges ----------------------


@pytest.mark.parametrize(
    "inputs, low, high",
    [
        ({"bh_spread": 0.05}, 0.95, 1.05),
        ({"yield_stress_spread": 0.10}, 0.90, 1.10),
        ({"yield_stress_spread": 0.10, "bh_spread": 0.05}, 0.855, 1.155),
    ],
)
def test_lot_spreads_scale_the_K_edges_down_and_up(paper, inputs, low, high):
    """Torque rises with the fluid's yield stress and with the steel's saturation
    (SOURCES: ±10 % yield-stress lot, ±5 % B–H lot, read as torque), and K_max = F_max/d
    (Eq. 4) is proportional to the torque. Both at their low ends: K⁻ = K (1 − 0.10)(1 −
    0.05) = 0.855 K = 314.06 N/m; at their high ends K⁺ = (1.10)(1.05) K = 1.155 K =
    424.25 N/m. Each spread alone: 0.95/1.05 (B–H) and 0.90/1.10 (yield stress). A sign
    slip on either lot at either end moves an edge by 10 % or 20 % of the spread."""
    box = _box(paper, **inputs)
    _, _, K = _hand(paper)
    assert _edges(box.K) == pytest.approx((K, low * K, high * K), rel=1e-12)
    u = replace(no_uncertainty(paper), **inputs)
    assert u.torque_factor == pytest.approx((low, high), rel=1e-12)


def test_default_lot_spreads_give_0855_and_1155():
    """The defaults (±10 % yield stress, ±5 % B–H): (0.9)(0.95) = 0.855 and (1.1)(1.05)
    = 1.155."""
    u = Uncertainty()
    assert (u.yield_stress_spread, u.bh_spread) == (0.10, 0.05)
    assert u.torque_factor == pytest.approx((0.855, 1.155), rel=1e-12)


def test_lot_spreads_leave_m1_b1_and_the_delay_alone(paper):
    box = _box(paper, yield_stress_spread=0.1, bh_spread=0.05)
    for t in (box.m1, box.b1, box.delay):
        lo_hi = _edges(t)
        assert lo_hi[1] == lo_hi[0] == lo_hi[2]


# ---- viscosity, fluid temperature, runout and bench damping move b1 ----------------------


def test_viscosity_spread_lowers_b1s_low_edge_and_raises_its_high_edge(paper):
    """Every drag term the fast model counts is ∝ η at a fixed temperature, so ±18 % on η
    (SOURCES, [lord-mrf132dg]) scales b1 by 0.82 and 1.18: 0.26839 → 0.22008 and 0.31670
    N·s/m. m1 and K do not move."""
    box = _box(paper, viscosity_spread=0.18)
    _, b1, K = _hand(paper)
    assert _edges(box.b1) == pytest.approx((b1, 0.82 * b1, 1.18 * b1), rel=1e-12)
    assert _edges(box.b1)[1] == pytest.approx(0.22008, rel=1e-4)
    assert _edges(box.K) == pytest.approx((K, K, K), rel=1e-12)


def test_a_warmer_fluid_lowers_b1s_low_edge_to_the_b1_evaluated_warm(paper):
    """η falls with temperature (ASTM D341's Walther line), so the fluid at 20–40 °C moves
    only b1's low edge, to the b1 that the nominal pipeline gives with the fluid at 40 °C;
    the high edge stays at 20 °C's b1."""
    box = _box(paper, fluid_temperature=(20.0, 40.0))
    _, b1, _ = _hand(paper)
    warm = replace(paper, operating=replace(paper.operating, fluid_temperature=40.0))
    _, b1_warm, _ = _hand(warm)
    assert b1_warm < 0.8 * b1  # the viscosity law's own direction, by a clear margin
    assert _edges(box.b1) == pytest.approx((b1, b1_warm, b1), rel=1e-9)


def test_a_colder_fluid_raises_b1s_high_edge_to_the_b1_evaluated_cold(paper):
    """The range 0–20 °C: only the high edge moves, to b1 at 0 °C."""
    box = _box(paper, fluid_temperature=(0.0, 20.0))
    _, b1, _ = _hand(paper)
    cold = replace(paper, operating=replace(paper.operating, fluid_temperature=0.0))
    _, b1_cold, _ = _hand(cold)
    assert b1_cold > 1.2 * b1
    assert _edges(box.b1) == pytest.approx((b1, b1, b1_cold), rel=1e-9)


def test_runout_raises_only_b1s_high_edge_by_the_eccentric_films_mean_1_over_h(paper):
    """A drum eccentricity e in a film of gap g: the mean of 1/(g − e cos θ) around the drum
    is 1/√(g² − e²) [abramowitz-stegun], so the drag (∝ 1/h) rises by g/√(g² − e²). At
    g = 0.7 mm, e = 0.02 mm: 1/√(1 − (0.02/0.7)²) = 1/√(1 − 8.1633e-4) = 1.000408. The low
    edge does not move (a centred drum is the least drag)."""
    box = _box(paper, runout=0.02e-3)
    _, b1, _ = _hand(paper)
    factor = 1 / math.sqrt(1 - (0.02 / 0.7) ** 2)
    assert factor == pytest.approx(1.000408, abs=1e-6)
    assert _edges(box.b1) == pytest.approx((b1, b1, b1 * factor), rel=1e-12)


def test_bench_damping_adds_its_range_to_b1s_edges(paper):
    """What the bench adds (lever, cables): b1 + [0, 0.7316] N·s/m, Table 2's 1.0 less the
    model's 0.2684 (SOURCES' bench_damping): 0.26839 … 1.0000 N·s/m."""
    box = _box(paper, bench_damping=(0.0, 0.7316068764194514))
    _, b1, _ = _hand(paper)
    assert _edges(box.b1) == pytest.approx((b1, b1, b1 + 0.7316068764194514), rel=1e-12)
    assert _edges(box.b1)[2] == pytest.approx(1.0, rel=1e-6)
    box = _box(paper, bench_damping=(0.1, 0.2))
    assert _edges(box.b1)[1:] == pytest.approx((b1 + 0.1, b1 + 0.2), rel=1e-12)


def test_the_b1_edges_of_the_default_ranges_compose_as_stated(paper):
    """The default ranges together on the paper preset (tolerances off): b1⁻ = b1(40 °C) ×
    0.82 + 0, b1⁺ = b1(20 °C) × 1.18 × 1.000408 + 0.7316 N·s/m."""
    u = replace(default_uncertainty(paper), gap_tolerance=0.0, drum_thickness_tolerance=0.0)
    box = hand_box_batch(_fields(paper), paper, u)
    _, b1, _ = _hand(paper)
    warm = replace(paper, operating=replace(paper.operating, fluid_temperature=40.0))
    _, b1_warm, _ = _hand(warm)
    top = b1 * 1.18 / math.sqrt(1 - (0.02 / 0.7) ** 2) + u.bench_damping[1]
    assert _edges(box.b1)[1:] == pytest.approx((0.82 * b1_warm, top), rel=1e-9)


# ---- the geometry's tolerances: the hull of the pipeline at the corners -----------------


def test_gap_tolerance_puts_b1_and_K_high_at_the_thin_gap(paper):
    """±0.02 mm on the gap (IT7, [iso286]): the thinner film (0.68 mm) drags more (Couette
    ∝ 1/g) and carries more flux (less reluctance), so b1⁺ and K⁺ are the pipeline's values
    at 0.68 mm, b1⁻ and K⁻ at 0.72 mm."""
    box = _box(paper, gap_tolerance=0.02e-3)
    thin, thick = _hand(paper, gap=0.68e-3), _hand(paper, gap=0.72e-3)
    assert thin[1] > thick[1] and thin[2] > thick[2]
    assert _edges(box.b1)[1:] == pytest.approx((thick[1], thin[1]), rel=1e-12)
    assert _edges(box.K)[1:] == pytest.approx((thick[2], thin[2]), rel=1e-12)


def test_drum_thickness_tolerance_puts_m1_high_at_the_thick_drum(paper):
    """±0.02 mm on the output drums' wall: more steel on the output rotor, more m1 at the
    hand, so m1⁺ is the pipeline's m1 with 0.02 mm thicker drums."""
    box = _box(paper, drum_thickness_tolerance=0.02e-3)
    t = paper.clutch.drum_thickness
    thick, thin = _hand(paper, drum_thickness=t + 0.02e-3), _hand(paper, drum_thickness=t - 0.02e-3)
    assert thick[0] > thin[0]
    assert _edges(box.m1)[1:] == pytest.approx((thin[0], thick[0]), rel=1e-12)


# ---- the delay ---------------------------------------------------------------------------


def test_default_delay_spans_the_typed_delay_and_the_geometrys(paper):
    """Not declared: from the typed 1 ms to the torque response's equivalent delay Σ T =
    2.1503 ms (``evaluate``'s torque_delay_s; SOURCES' delay)."""
    box = hand_box_batch(_fields(paper), paper, replace(no_uncertainty(paper), delay=None))
    rows = evaluate_batch(_fields(paper), paper)
    assert _edges(box.delay) == pytest.approx((1e-3, 1e-3, float(rows["torque_delay_s"][0])))
    assert _edges(box.delay)[2] == pytest.approx(2.1503e-3, rel=1e-4)


def test_a_declared_delay_range_is_the_box_edges(paper):
    box = _box(paper, delay=(0.5e-3, 3e-3))
    assert _edges(box.delay)[1:] == pytest.approx((0.5e-3, 3e-3), rel=1e-12)


# ---- the fluid temperature range ---------------------------------------------------------


def test_default_fluid_temperature_is_20_K_above_the_operating_value(paper):
    """SOURCES' fluid_temperature: the operating value to 20 K above it: 20 → 40 °C on the
    paper preset."""
    assert WARMING == 20.0
    assert default_uncertainty(paper).fluid_temperature == (20.0, 40.0)
    assert default_uncertainty(None).fluid_temperature == (20.0, 40.0)


@pytest.mark.parametrize("t_op, top", [(100.0, 120.0), (120.0, 130.0), (129.0, 130.0)])
def test_default_fluid_temperature_is_capped_at_the_fluids_limit(paper, t_op, top):
    """Capped at the fluid's rated top, 130 °C for MRF-132DG ([lord-mrf132dg]): the range
    never reaches past it, and never below the operating value + 20 K where that is
    lower."""
    assert FLUIDS[paper.materials.fluid].temperature_range[1] == 130.0
    d = replace(paper, operating=replace(paper.operating, fluid_temperature=t_op))
    assert default_uncertainty(d).fluid_temperature == (t_op, top)


# ---- the process: the optimiser's lower edges and its worst-case ranges -----------------


def test_process_min_gap_is_runout_plus_tolerance_over_a_quarter():
    """ε = (R + T)/g ≤ 1/4: (0.03 + 0.02)/0.25 = 0.2 mm by default; 0.05 mm more runout
    adds 0.2 mm, 0.01 mm more tolerance 0.04 mm. The wall's edge is min_wall itself."""
    assert MAX_ECCENTRICITY == 0.25
    assert Process().min_gap == pytest.approx(0.2e-3, rel=1e-12)
    assert Process(runout=0.08e-3).min_gap == pytest.approx(0.4e-3, rel=1e-12)
    assert Process(tolerance=0.03e-3).min_gap == pytest.approx(0.24e-3, rel=1e-12)
    assert Process(min_wall=0.4e-3).lower_bounds() == pytest.approx(
        {"gap": 0.2e-3, "drum_thickness": 0.4e-3, "input_drum_thickness": 0.4e-3}, rel=1e-12
    )


def test_process_raises_the_search_boxs_lower_gap_edge(paper):
    """runout 0.06 + tolerance 0.02 mm: the smallest gap is 0.08/0.25 = 0.32 mm, which
    replaces a range's lower edge below it (0.2 mm) and leaves its upper edge."""
    base = replace(paper, process=Process(runout=0.06e-3, tolerance=0.02e-3))
    box, source = search_box(base, {"gap": (0.2e-3, 1.0e-3)})
    assert box["gap"] == pytest.approx((0.32e-3, 1.0e-3), rel=1e-12)
    assert source["gap"] == "process"
    box, source = search_box(base, {"gap": (0.4e-3, 1.0e-3)})
    assert box["gap"] == (0.4e-3, 1.0e-3) and source["gap"] == "range"


def test_process_moves_the_worst_cases_runout_and_gap_tolerance(paper):
    """The optimiser's worst case without a declared `[uncertainty]`: the defaults with the
    process's runout as the drums' eccentricity and its tolerance as the gap's."""
    base = replace(paper, process=Process(runout=0.05e-3, tolerance=0.01e-3), uncertainty=None)
    u = process_uncertainty(base)
    assert (u.runout, u.gap_tolerance) == (0.05e-3, 0.01e-3)
    assert u.viscosity_spread == 0.18 and u.fluid_temperature == (20.0, 40.0)


def test_a_fluid_temperature_range_below_the_operating_point_raises_b1s_high_edge():
    """A range reaching below the operating temperature (0–20 °C on the paper preset, at
    20 °C) raises b1's high edge by the drag's ratio between the range's cold end and the
    operating point, read here from two fast-path evaluations at 20 and 0 °C (η(T) of the
    carrier: ×3.08), every other spread zero; its low edge stays b1 (the factor at 20 °C is
    the smaller). The default ranges start at the operating point, where the cold factor
    is 1, so only such a range tells ×factor from ÷factor (mutation survivor
    hand_box.py:144)."""
    base = design_preset("paper")
    op = base.operating
    cold = op.fluid_temperature - 20.0
    unc = Uncertainty(viscosity_spread=0.0, fluid_temperature=(cold, op.fluid_temperature),
                      gap_tolerance=0.0, runout=0.0, drum_thickness_tolerance=0.0)  # fmt: skip
    gap = {"gap": np.array([base.clutch.gap])}
    b1, lo, hi = hand_box_batch(gap, base, unc).b1
    colder = replace(base, operating=replace(op, fluid_temperature=cold))
    ratio = (evaluate_batch(gap, colder)["drag_damping_N_m_s"]
             / evaluate_batch(gap, base)["drag_damping_N_m_s"])  # fmt: skip
    assert ratio[0] > 2.0  # the carrier is much thicker at 0 °C
    assert hi[0] == pytest.approx(b1[0] * ratio[0], rel=1e-9)
    assert lo[0] == pytest.approx(b1[0], rel=1e-12)
