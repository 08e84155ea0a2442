"""The hand on the lever (mrclutch.haptics.hand): the coupled characteristic equation
reduces to the hands-off model, a mass-only hand is a heavier lever, the coupled-stability
theorem holds (passive device ⇒ stable with any passive hand), the D-subdivision limits
agree with independent root counts (np.roots, Padé for the delay); then the backdrive
force's closed forms and the paper preset's figures."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest

from geometry.validation import ParameterError
from mrclutch.design import design_preset
from mrclutch.haptics import hand_scan
from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.hand import (
    HAND_RANGE,
    Hand,
    HandRange,
    _chi_h,
    _crossings_h,
    _hand_rows,
    _p_hand,
    backdrive_force,
    coupled_stability,
    felt_impedance,
    hand_figures,
    is_stable_coupled,
    max_stable_stiffness_coupled,
)
from mrclutch.haptics.hand_scan import _limits_hands
from mrclutch.haptics.impedance import passive_impedance
from mrclutch.haptics.limits import _chi, is_stable, max_passive_stiffness, max_stable_stiffness
from mrclutch.pipeline import evaluate

TAU = 1e-3


def _random(n: int, seed: int, delay: float = 0.0, sample_period: float = 0.0) -> list:
    rng = np.random.default_rng(seed)
    return [
        HapticParams(
            m1=rng.uniform(0.3e-3, 50e-3),
            m2=rng.uniform(1e-3, 50e-3),
            b1=rng.uniform(0.05, 5.0),
            k=rng.uniform(500.0, 2e4),
            b=rng.uniform(0.0, 40.0),
            delay=delay,
            sample_period=sample_period,
        )
        for _ in range(n)
    ]


def _pade(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(n, n) Padé approximant of e^{−z}: numerator, denominator coefficients descending."""
    c = [
        math.factorial(2 * n - k) * math.factorial(n)
        / (math.factorial(2 * n) * math.factorial(k) * math.factorial(n - k))
        for k in range(n + 1)
    ]  # fmt: skip
    num = np.array([c[k] * (-1) ** k for k in range(n + 1)])[::-1]
    den = np.array(c)[::-1]
    return num, den


def _det_poly(p: HapticParams, hand: Hand) -> np.ndarray:
    """The K-free part of det of the two equations of motion with the hand (descending):
    [[D1, KE − (bs+k)], [−(bs+k), (m2+m_h)s² + (b+b_h)s + k + k_h]] → D1·M2 − (bs+k)²,
    built here from the equations, independently of the module's P_h."""
    d1 = np.array([p.m1, p.b1 + p.b, p.k])
    m2 = np.array([p.m2 + hand.m, p.b + hand.b, p.k + hand.k])
    q = np.array([p.b, p.k])
    return np.polysub(np.polymul(d1, m2), np.polymul(q, q))


def _max_re_root(p: HapticParams, hand: Hand, K: float, order: int = 8) -> float:
    """Largest Re s of the coupled loop, independently of the D-subdivision: the
    polynomial det + K (bs + k) (np.roots), the delay by an (order, order) Padé."""
    ph = _det_poly(p, hand)
    q = np.array([p.b, p.k])
    if p.delay == 0.0:
        return float(np.max(np.roots(np.polyadd(ph, K * q)).real))
    # z = sτ: P_h(z/τ) and (b z/τ + k), then D(z) P_h + K N(z) q
    t = p.delay
    phz = ph * t ** -np.arange(ph.size - 1, -1, -1.0)
    qz = q * np.array([1.0 / t, 1.0])
    num, den = _pade(order)
    chi = np.polyadd(np.polymul(den, phz), K * np.polymul(num, qz))
    return float(np.max(np.roots(chi).real)) / t


# --- the characteristic equation ------------------------------------------------------


def test_chi_hands_off_is_model_chi() -> None:
    p = replace(TABLE2_MR, sample_period=1e-3)
    s = np.array([0.3 + 2.0j, -5.0 + 80.0j, 1j * 700.0])
    for K in (0.0, 150.0, 1234.5):
        np.testing.assert_allclose(_chi_h(p, Hand(), K, s), _chi(p, K, s), rtol=1e-13)


def test_chi_is_s_d1_times_zp_plus_zh() -> None:
    # χ_h(s) = s D1 (Z_p + Z_h) + K E (bs + k): check at K = 0 on the imaginary axis
    p, h = TABLE2_MR, Hand(0.4, 6.0, 300.0)
    w = np.geomspace(1.0, 1e4, 9)
    s = 1j * w
    d1 = (p.m1 * s + p.b1 + p.b) * s + p.k
    zh = h.m * s + h.b + h.k / s
    want = s * d1 * (passive_impedance(p, w) + zh)
    np.testing.assert_allclose(_chi_h(p, h, 0.0, s), want, rtol=1e-12)


@pytest.mark.parametrize(
    ("delay", "sample_period"), [(0.0, 0.0), (TAU, 0.0), (TAU, 5e-4), (0.0, 1e-3)]
)
def test_hands_off_limit_is_model_limit(delay: float, sample_period: float) -> None:
    for p in _random(12, seed=4, delay=delay, sample_period=sample_period):
        want = max_stable_stiffness(p)
        got = max_stable_stiffness_coupled(p)
        assert got == pytest.approx(want, rel=1e-9) or (math.isinf(want) and math.isinf(got))
        for f in (0.9, 1.1):
            K = min(f * want, 1e7)
            assert is_stable_coupled(p, K) == is_stable(p, K)


def test_mass_only_hand_is_a_heavier_lever() -> None:
    for p in _random(8, seed=5, delay=TAU) + _random(8, seed=6):
        for m_h in (0.05, 0.6):
            want = max_stable_stiffness(replace(p, m2=p.m2 + m_h))
            got = max_stable_stiffness_coupled(p, Hand(m=m_h))
            assert got == pytest.approx(want, rel=1e-9) or (math.isinf(want) and math.isinf(got))


def test_vectorised_designs_one_by_one() -> None:
    ps = _random(4, seed=7, delay=TAU)
    q = HapticParams.stack(ps)
    h = Hand(0.3, 5.0, 200.0)
    got = max_stable_stiffness_coupled(q, h)
    assert got.shape == (4,)
    np.testing.assert_allclose(got, [max_stable_stiffness_coupled(p, h) for p in ps])


# --- invariants and independent checks ------------------------------------------------


def test_passive_device_is_stable_with_any_passive_hand() -> None:
    # Colgate–Hogan: Z_cl passive at K ⇒ Z_cl + Z_h positive real ⇒ coupled stable
    rng = np.random.default_rng(8)
    designs = _random(15, seed=9, delay=TAU) + _random(15, seed=10)
    for p in designs:
        kp = max_passive_stiffness(p)
        h = Hand(rng.uniform(0.0, 1.0), rng.uniform(0.0, 20.0), rng.uniform(0.0, 1000.0))
        assert max_stable_stiffness_coupled(p, h) >= kp * (1 - 1e-6)


def test_limit_agrees_with_roots_without_delay() -> None:
    hands = [Hand(), Hand(0.3, 0.0, 0.0), Hand(0.0, 5.0, 0.0), Hand(0.5, 8.0, 400.0)]
    for p in _random(6, seed=11):
        for h in hands:
            lim = max_stable_stiffness_coupled(p, h)
            if not math.isfinite(lim):
                assert _max_re_root(p, h, 1e7) < 0
                continue
            assert _max_re_root(p, h, 0.98 * lim) < 0
            assert _max_re_root(p, h, 1.02 * lim) > 0


def test_limit_agrees_with_pade_roots_with_delay() -> None:
    hands = [Hand(), Hand(0.05, 2.0, 20.0), Hand(1.0, 2.0, 20.0), Hand(0.5, 20.0, 1000.0)]
    for p in [TABLE2_MR, *_random(3, seed=12, delay=TAU)]:
        for h in hands:
            lim = max_stable_stiffness_coupled(p, h)
            assert math.isfinite(lim)
            assert _max_re_root(p, h, 0.98 * lim) < 0
            assert _max_re_root(p, h, 1.02 * lim) > 0
            assert is_stable_coupled(p, 0.98 * lim, h)
            assert not is_stable_coupled(p, 1.02 * lim, h)


def test_p_hand_is_the_determinant() -> None:
    for p in _random(4, seed=14):
        h = Hand(0.3, 4.0, 250.0)
        np.testing.assert_allclose(_p_hand(p, h), _det_poly(p, h), rtol=1e-12)


def test_crossing_directions_match_root_motion() -> None:
    # every crossing of delay-free designs: the root at jω_c moves as sign says when K grows
    seen = 0
    for p in _random(10, seed=15):
        h = Hand(0.2, 3.0, 150.0)
        wc, Kc, dirs = _crossings_h(p, h, k_stop=1e9)
        for w, K, d in zip(wc, Kc, dirs, strict=True):
            r = np.roots(np.polyadd(_det_poly(p, h), K * (1 + 1e-5) * np.array([p.b, p.k])))
            near = r[np.argmin(np.abs(r - 1j * w))]
            assert np.sign(near.real) == d
            seen += 1
    assert seen >= 10


def test_hand_damping_raises_the_limit_of_the_delayed_mr_pair() -> None:
    # the delayed rigid-body mode needs K τ ≲ b1 + b_h: hand damping raises the limit
    lims = [max_stable_stiffness_coupled(TABLE2_MR, Hand(b=b)) for b in (0.0, 1.0, 3.0, 10.0)]
    assert all(b > a for a, b in itertools.pairwise(lims))
    assert lims[0] == pytest.approx(max_stable_stiffness(TABLE2_MR), rel=1e-9)


def test_hand_damping_can_lower_the_limit_without_delay() -> None:
    # not an invariant: on a heavy actuator behind a light lever (non-collocated sensor)
    # grounding damping at x2 lowers the delay-free limit; confirmed by np.roots
    p = HapticParams(m1=0.0475, b1=4.247, k=17060.0, b=8.763, m2=3.108e-3)
    off = max_stable_stiffness_coupled(p)
    on = max_stable_stiffness_coupled(p, Hand(b=8.0))
    assert on < 0.8 * off
    K = 0.5 * (on + off)
    assert _max_re_root(p, Hand(), K) < 0 < _max_re_root(p, Hand(b=8.0), K)


# --- coupled_stability ----------------------------------------------------------------


def test_coupled_stability_bisection_agrees() -> None:
    p = TABLE2_MR
    r = coupled_stability(p, 500.0, n=2)
    lo, hi = 0.5 * r.max_stable_K, 2.0 * r.max_stable_K
    for _ in range(40):  # bisection on K with the stability check at the worst hand
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if is_stable_coupled(p, mid, r.worst_hand) else (lo, mid)
    assert lo == pytest.approx(r.max_stable_K, rel=1e-8)
    # no hand of a finer grid is worse than the search's worst (to 1 %)
    finer = min(max_stable_stiffness_coupled(p, h) for h in HAND_RANGE.grid(4))
    assert r.max_stable_K <= finer * 1.01
    assert r.stable is (500.0 <= r.max_stable_K)
    assert coupled_stability(p, 1.01 * r.max_stable_K, n=2).stable is False


def test_coupled_stability_hands_off_box_is_model() -> None:
    box = HandRange(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    r = coupled_stability(TABLE2_MR, 100.0, box, n=2)
    assert r.max_stable_K == pytest.approx(max_stable_stiffness(TABLE2_MR), rel=1e-9)
    assert r.hands_off_max_stable_K == r.max_stable_K


def test_validation_names_the_parameter() -> None:
    with pytest.raises(ParameterError, match="b_h = -1"):
        Hand(b=-1.0)
    with pytest.raises(ParameterError, match="k_max"):
        HandRange(0.1, 1.0, 1.0, 2.0, 100.0, 50.0)
    with pytest.raises(ParameterError, match="n = 1"):
        HAND_RANGE.grid(1)
    with pytest.raises(ParameterError, match="K = -5"):
        coupled_stability(TABLE2_MR, -5.0)
    with pytest.raises(ParameterError, match="design shape"):
        coupled_stability(HapticParams.stack(_random(2, seed=1)), 100.0)
    with pytest.raises(ParameterError, match="amplitude = 0"):
        backdrive_force(TABLE2_MR, amplitude=0.0)
    with pytest.raises(ParameterError, match="frequency = -2"):
        felt_impedance(TABLE2_MR, frequency=np.array([1.0, -2.0]))


def test_hand_range_contains_the_measured_anchor() -> None:
    # van Beek et al. 2015, one trial: 0.554 kg, 6.45 N·s/m, 135 N/m
    r = HAND_RANGE
    assert r.m_min <= 0.554 <= r.m_max
    assert r.b_min <= 6.45 <= r.b_max
    assert r.k_min <= 135.0 <= r.k_max
    assert len(r.grid(3)) == 27


# --- transparency ---------------------------------------------------------------------


def test_backdrive_rigid_coupling_closed_form() -> None:
    p = replace(TABLE2_MR, k=1e12)
    X, f = 0.01, 2.0
    w = 2 * math.pi * f
    want = w * X * abs(p.b1 + 1j * w * (p.m1 + p.m2))  # Z_p → (m1 + m2) s + b1
    assert backdrive_force(p, X, f) == pytest.approx(want, rel=1e-7)
    felt = felt_impedance(p, f)
    assert felt.damping == pytest.approx(p.b1, rel=1e-7)
    assert felt.mass == pytest.approx(p.m1 + p.m2, rel=1e-7)


def test_backdrive_massless_lever_is_series_of_actuator_and_transmission() -> None:
    # m2 → 0: Z_p = (m1 s + b1)(b + k/s)/(m1 s + b1 + b + k/s), the two in series
    p = replace(TABLE2_MR, m2=1e-12)
    f = np.array([0.5, 2.0, 50.0, 400.0])
    s = 2j * np.pi * f
    za, zt = p.m1 * s + p.b1, p.b + p.k / s
    want = np.abs(za * zt / (za + zt)) * np.abs(s) * 0.003
    np.testing.assert_allclose(backdrive_force(p, 0.003, f), want, rtol=1e-8)


def test_backdrive_vectorised_and_linear_in_amplitude() -> None:
    q = HapticParams.stack(_random(5, seed=13, delay=TAU))
    F = backdrive_force(q)
    assert F.shape == (5,)
    np.testing.assert_allclose(backdrive_force(q, 0.02), 2 * F, rtol=1e-14)
    for i in range(5):
        assert backdrive_force(q.item(i)) == pytest.approx(F[i], rel=1e-14)
    felt = felt_impedance(q)
    w = 2 * math.pi * 2.0
    np.testing.assert_allclose(np.hypot(felt.damping, w * felt.mass) * w * 0.01, F, rtol=1e-12)


# --- the paper preset -----------------------------------------------------------------


def test_paper_preset_figures() -> None:
    fig = hand_figures(evaluate(design_preset("paper"), "fast").mr)
    K = fig["K_N_per_m"]
    # hands off the pair is unstable at its K_max (253 < 363 N/m); any hand in the range
    # adds ≥ 2 N·s/m and makes it stable, with a wide margin
    assert fig["max_stable_K_hands_off_N_per_m"] < K
    assert fig["coupled_stable"] is True
    assert fig["max_stable_K_all_hands_N_per_m"] > 3 * K
    assert fig["max_stable_K_all_hands_N_per_m"] >= fig["max_passive_K_N_per_m"]
    assert fig["worst_hand"]["b_N_s_per_m"] == HAND_RANGE.b_min
    # free motion: 10 mm at 2 Hz costs a few tens of mN, mostly the drag b1
    assert 0.01 < fig["backdrive_force_N"] < 0.1
    assert fig["felt_mass_kg"] == pytest.approx(0.0155, rel=0.05)
    # the table of docs/hand.md (to 1 %: it moves with the drag and inertia models)
    assert fig["max_stable_K_hands_off_N_per_m"] == pytest.approx(253.4, rel=0.01)
    assert fig["max_stable_K_all_hands_N_per_m"] == pytest.approx(2126.0, rel=0.01)
    assert fig["backdrive_force_N"] == pytest.approx(0.0416, rel=0.01)


# --- the batched scan (issue 40: one scan for the grid and the compass's polls) ----------


def _designs_for_batch() -> list[HapticParams]:
    """Delay-free (b = 0: the crossing polynomial's degree drops), delayed, sampled and the
    paper pair: every path of the scan."""
    return [
        TABLE2_MR,
        replace(_random(1, seed=39)[0], b=0.0),
        *_random(2, seed=40),
        *_random(2, seed=41, delay=TAU),
        *_random(2, seed=42, delay=2e-4, sample_period=1e-3),
    ]


def test_batched_limits_equal_one_hand_at_a_time() -> None:
    # 27 grid hands + hands off + one-parameter hands in one scan, against each hand
    # scanned alone (its own grid, its own Illinois brackets): the same crossing to the
    # scan's tolerance (Illinois rtol 1e-13 on ω)
    hands = [*HAND_RANGE.grid(3), Hand(), Hand(m=0.3), Hand(b=5.0), Hand(k=100.0)]
    for p in _designs_for_batch():
        together = _limits_hands(p, _hand_rows(hands))
        alone = np.array([max_stable_stiffness_coupled(p, h) for h in hands])
        assert together.shape == (len(hands),)
        np.testing.assert_array_equal(np.isfinite(together), np.isfinite(alone))
        fin = np.isfinite(alone)
        np.testing.assert_allclose(together[fin], alone[fin], rtol=1e-9)


def test_batched_limits_against_the_model_limit() -> None:
    # independent code (limits.max_stable_stiffness, the scan without a hand): hands off it
    # is the model's limit, and a mass-only hand is the lever with m2 -> m2 + m_h
    for p in _designs_for_batch():
        lims = _limits_hands(p, _hand_rows([Hand(), Hand(m=0.2), Hand(m=0.02)]))
        ref = [max_stable_stiffness(replace(p, m2=p.m2 + m)) for m in (0.0, 0.2, 0.02)]
        np.testing.assert_allclose(lims, ref, rtol=1e-9)


def _compass_one_at_a_time(p: HapticParams, hr: HandRange, n: int) -> tuple[Hand, float, int]:
    """The compass search polling one neighbour at a time (the pre-batch procedure)."""
    hands = hr.grid(n)
    lims = [max_stable_stiffness_coupled(p, h) for h in hands]
    j = int(np.argmin(lims))
    worst, best, checked = hands[j], lims[j], len(hands)
    bounds = {"m": (hr.m_min, hr.m_max), "b": (hr.b_min, hr.b_max), "k": (hr.k_min, hr.k_max)}
    step = 0.5 * math.log(2.0)
    for _ in range(8):
        moved = True
        while moved:
            moved = False
            for name, (lo, hi) in bounds.items():
                if hi <= lo:
                    continue
                for sgn in (-1.0, 1.0):
                    v = getattr(worst, name)
                    new = min(max(v * math.exp(sgn * step) if v > 0 else lo + 0.1 * (hi - lo),
                                  lo), hi)  # fmt: skip
                    if new == v:
                        continue
                    cand = replace(worst, **{name: new})
                    lim = max_stable_stiffness_coupled(p, cand)
                    checked += 1
                    if lim < best * (1 - 1e-9):
                        worst, best, moved = cand, lim, True
        step *= 0.5
    return worst, best, checked


@pytest.mark.parametrize("n", [2, 3])
def test_batched_compass_search_takes_the_same_steps(n: int) -> None:
    # the polls batched per step visit the same points in the same order: same worst hand,
    # same count of hands checked, the same limit to the scan's tolerance; a box with
    # k_h = 0 at its lower end exercises the "v = 0" start of an axis
    boxes = [HAND_RANGE, HandRange(0.05, 1.0, 0.0, 20.0, 0.0, 1000.0)]
    for p in _designs_for_batch()[:5]:
        for hr in boxes:
            worst, best, checked = _compass_one_at_a_time(p, hr, n)
            r = coupled_stability(p, 100.0, hr, n)
            assert r.hands_checked == checked
            assert (r.worst_hand.m, r.worst_hand.b, r.worst_hand.k) == pytest.approx(
                (worst.m, worst.b, worst.k), rel=1e-12
            )
            assert r.max_stable_K == pytest.approx(best, rel=1e-9)
            assert r.hands_off_max_stable_K == pytest.approx(
                max_stable_stiffness_coupled(p), rel=1e-12
            )


def test_the_scan_over_hands_in_row_chunks_finds_what_one_whole_scan_finds(monkeypatch) -> None:
    """The hands are scanned in chunks of rows under MAX_CELLS grid values (a 0.01 gearing
    took 1.7 GB scanning all hands at once): chunks of one row, or of all, give the same
    crossings in the same order, so the same limits."""
    p = replace(TABLE2_MR, delay=1e-3)
    hands = np.array([[0.1, 2.0, 100.0], [0.5, 5.0, 400.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1e3]])
    whole = hand_scan._crossings_hands(p, hands)
    monkeypatch.setattr(hand_scan, "MAX_CELLS", 1)  # one row a chunk
    rows = hand_scan._crossings_hands(p, hands)
    for a, b in zip(whole, rows, strict=True):
        np.testing.assert_array_equal(a, b)
    assert whole[0].size > 0 and set(whole[0]) <= {0, 1, 2, 3}


def test_a_hands_limit_is_its_own_in_any_scan_and_the_search_scans_ahead(monkeypatch) -> None:
    # coupled_stability scans the polls of the later steps ahead of need, beside the ones
    # asked now: that gives the same answer only because a hand's limit does not depend on
    # the hands scanned with it, to the bit
    hands = [*HAND_RANGE.grid(3), Hand(), Hand(m=0.3), Hand(b=5.0), Hand(k=100.0)]
    for p in _designs_for_batch()[:6]:
        together = _limits_hands(p, _hand_rows(hands))
        for i in (0, 13, 27, 30):
            alone = _limits_hands(p, _hand_rows(hands[i]))
            assert np.array_equal(together[i : i + 1], alone), (p, i)
    import mrclutch.haptics.hand as hand_mod

    scans = []
    real = hand_mod._limits_hands

    def counted(p, rows):
        scans.append(len(rows))
        return real(p, rows)

    monkeypatch.setattr(hand_mod, "_limits_hands", counted)
    r = coupled_stability(TABLE2_MR, 100.0)
    assert scans == [28, 24]  # the grid and hands off, then every step's 3 polls at once
    assert r.hands_checked == 27 + 8 * 3  # the polls of the search that never moves
