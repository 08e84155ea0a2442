"""Z-width of the 2-DOF lever (mrclutch.haptics.zwidth): closed forms first (the rigid
damped mass behind a pure delay, Colgate–Schenkel's d = 0 and B = 0 forms), then the
invariants (agreement with max_passive_stiffness and is_stable, passivity at the
boundary and its tightness, convexity of the passive set, the area's bracket)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geometry.validation import ParameterError
from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.impedance import _num_coeffs
from mrclutch.haptics.limits import is_stable, max_passive_stiffness, max_stable_stiffness
from mrclutch.haptics.sampled import (
    encoder_stiffness_limit,
    sampled_max_passive_stiffness,
    sampled_passivity_margin,
)
from mrclutch.haptics.zwidth import (
    ZWIDTH_KEYS,
    is_stable_spring_damper,
    max_passive_damping,
    passive_stiffness_interval,
    zwidth,
)

TAU = 1e-3
B1 = 2.0


def _random(n: int, seed: int = 1, sampled: bool = False) -> HapticParams:
    rng = np.random.default_rng(seed)
    return HapticParams(
        m1=rng.uniform(0.3e-3, 50e-3, n),
        m2=rng.uniform(1e-3, 50e-3, n),
        b1=rng.uniform(0.03, 5.0, n),
        k=rng.uniform(500.0, 2e4, n),
        b=rng.uniform(0.05, 30.0, n),
        delay=rng.uniform(0.0, 2e-3, n),
        sample_period=rng.uniform(0.0, 1e-3, n) if sampled else 0.0,
    )


def _re_zcl(p: HapticParams, K: float, B: float, w: np.ndarray) -> np.ndarray:
    """Re Z_cl with the spring–damper, straight from its definition (independent of the
    module): [s Num + e^{−sτ}(K + Bs)(bs + k)] / (s D1), pure delay."""
    s = 1j * w
    a3, a2, a1, a0 = _num_coeffs(p)
    num = ((a3 * s + a2) * s + a1) * s + a0
    d1 = (p.m1 * s + (p.b1 + p.b)) * s + p.k
    E = np.exp(-s * p.delay)
    return ((s * num + E * (K + B * s) * (p.b * s + p.k)) / (s * d1)).real


def _rigid_k_max(B: float) -> float:
    """Closed form for Z = ms + b1 behind a pure delay: K_max(B) = min over x ∈ (0, π) of
    x (b1 + B cos x)/(τ sin x) (x = ωτ; later lobes of sinc > 0 are larger)."""
    x = np.linspace(1e-7, math.pi - 1e-9, 100_001)
    return float(np.min(x * (B1 + B * np.cos(x)) / (TAU * np.sin(x))))


def _stiff(k: float) -> HapticParams:
    # k → ∞: Z_cl → (m1 + m2)s + b1 + (K/s + B)e^{−sτ}, Re = b1 + B cos ωτ − K sin(ωτ)/ω
    return HapticParams(m1=1e-3, b1=B1, k=k, b=1.0, m2=0.05, delay=TAU)


# --- closed forms ----------------------------------------------------------------------


def test_stiff_transmission_reaches_the_rigid_closed_form() -> None:
    r = zwidth(_stiff(1e9))
    assert r["K_max_at_B0_N_per_m"] == pytest.approx(B1 / TAU, rel=1e-5)  # b/τ
    assert r["B_max_at_K0_N_s_per_m"] == pytest.approx(B1, abs=1e-4)  # x = π: B ≤ b
    assert r["B_top_N_s_per_m"] == pytest.approx(B1, abs=1e-4)
    B, K = r["B_N_s_per_m"], r["K_max_N_per_m"]
    cf = np.array([_rigid_k_max(b) for b in B[:-1]])
    # within 1e-5 where K_max is flat, 5e-4 where it falls steeply to 0 at B = b
    np.testing.assert_allclose(K[:-1], cf, rtol=1e-3)
    np.testing.assert_allclose(K[:8], cf[:8], rtol=1e-5)
    assert K[1] > K[0]  # a little virtual damping raises the passive spring
    # area: ∫_0^b K_cf(B) dB on a fine grid (K_cf concave: trapezoid from below)
    Bf = np.linspace(0.0, B1, 201)
    area = np.trapezoid([_rigid_k_max(b) for b in Bf], Bf)
    assert r["zwidth_area_N2_s_per_m2"] == pytest.approx(area, rel=1e-2)
    assert r["zwidth_area_N2_s_per_m2"] <= area * (1 + 1e-4)
    assert r["zwidth_area_upper_N2_s_per_m2"] >= area * (1 - 1e-4)


def test_rigid_limit_error_falls_as_one_over_k() -> None:
    errs = []
    for k in (1e7, 1e8, 1e9):
        r = zwidth(_stiff(k), n_b=5)
        errs.append(abs(r["K_max_at_B0_N_per_m"] * TAU / B1 - 1.0))
    assert errs[0] > 5 * errs[1] > 25 * errs[2]


def test_colgate_schenkel_d0_closed_form() -> None:
    rng = np.random.default_rng(3)
    b = rng.uniform(0.5, 20.0, 200)
    T = 10.0 ** rng.uniform(-4.5, -2.0, 200)
    B = rng.uniform(-0.9, 0.9, 200) * b
    K = sampled_max_passive_stiffness(b, T, B, 0)
    np.testing.assert_allclose(K, 2.0 * (b - np.abs(B)) / T, rtol=1e-12)  # b > KT/2 + |B|
    margin = sampled_passivity_margin(b, T, 0.7 * K, B, 0)
    np.testing.assert_allclose(margin, b - 0.7 * K * T / 2 - np.abs(B), rtol=1e-9, atol=1e-12)


def test_colgate_schenkel_zero_damping_any_delay() -> None:
    b, T = 3.0, 1e-3
    d = np.arange(6)
    K = sampled_max_passive_stiffness(b, T, 0.0, d)
    np.testing.assert_allclose(K, 2.0 * b / ((2 * d + 1) * T), rtol=1e-12)
    assert np.all(np.diff(K) < 0)  # each sample of delay costs stiffness


def test_sampled_margin_changes_sign_at_the_boundary() -> None:
    b, T = 2.0, 5e-4
    for d in (0, 1, 3):
        for B in (0.0, 0.5, 1.5):
            K = sampled_max_passive_stiffness(b, T, B, d)
            assert sampled_passivity_margin(b, T, K * (1 - 1e-6), B, d) > 0
            assert sampled_passivity_margin(b, T, K * (1 + 1e-6), B, d) < 0
    assert math.isnan(sampled_max_passive_stiffness(b, T, 1.2 * b, 0))  # B > b: never


def test_encoder_resolution_caps_stiffness() -> None:
    assert encoder_stiffness_limit(0.1, 1e-5) == pytest.approx(2e4)  # 2 f_c/Δ
    assert encoder_stiffness_limit(0.1, 0.0) == math.inf  # ideal encoder
    free = sampled_max_passive_stiffness(5.0, 1e-4, 0.0)
    capped = sampled_max_passive_stiffness(
        5.0, 1e-4, 0.0, coulomb_friction=0.05, encoder_resolution=1e-5
    )
    assert free == pytest.approx(1e5) and capped == pytest.approx(1e4)
    with pytest.raises(ParameterError):
        sampled_max_passive_stiffness(5.0, 1e-4, 0.0, 0.5)  # d not an integer


# --- invariants ------------------------------------------------------------------------


def test_k_max_at_zero_damping_is_max_passive_stiffness() -> None:
    for p in (_random(300), _random(300, seed=2, sampled=True)):
        r = zwidth(p, n_b=3)
        np.testing.assert_allclose(r["K_max_at_B0_N_per_m"], max_passive_stiffness(p), rtol=1e-12)
        _, hi = passive_stiffness_interval(p, 0.0)
        np.testing.assert_allclose(hi, max_passive_stiffness(p), rtol=1e-12)
    assert set(ZWIDTH_KEYS) == set(r)


def test_boundary_is_passive_and_tight() -> None:
    p = _random(40, seed=4)
    w = 2 * np.pi * np.logspace(-3, 6, 200_001)
    B = max_passive_damping(p) * np.linspace(0.05, 0.95, 40)
    lo, hi = passive_stiffness_interval(p, B)
    for i in range(40):
        q = p.item(i)
        assert lo[i] == 0.0  # below B_max, K = 0 is passive
        scale = float(np.max(np.abs(_re_zcl(q, hi[i], B[i], w[::100]))))
        assert np.min(_re_zcl(q, hi[i] * (1 - 1e-6), B[i], w)) > -1e-9 * scale
        assert np.min(_re_zcl(q, hi[i] * (1 + 1e-3), B[i], w)) < 0  # tight


def test_damping_intercept() -> None:
    p = _random(50, seed=5)
    bm = max_passive_damping(p)
    lo, hi = passive_stiffness_interval(p, bm * (1 - 1e-4))
    assert np.all(lo == 0) and np.all(hi >= 0)
    lo2, _ = passive_stiffness_interval(p, bm * (1 + 1e-3))
    assert np.all(np.isnan(lo2) | (lo2 > 0))  # past B_max, K = 0 is not passive


def test_passive_set_is_convex() -> None:
    p = _random(200, seed=6)
    r = zwidth(p, n_b=17)
    B, K, Kmin = r["B_N_s_per_m"], r["K_max_N_per_m"], r["K_min_N_per_m"]
    # divided differences on the (non-uniform) nodes: K_max concave, K_min convex
    s = np.diff(K, axis=1) / np.diff(B, axis=1)
    smin = np.diff(Kmin, axis=1) / np.diff(B, axis=1)
    ok = np.all(np.isfinite(s), axis=1)
    tol = 1e-6 * np.abs(s).max(axis=1, keepdims=True)
    assert np.all(np.diff(s[ok], axis=1) <= tol[ok])
    assert np.all(np.diff(smin[ok], axis=1) >= -tol[ok])
    # midpoint of two boundary points is passive
    i, j = 3, 12
    mid_B = 0.5 * (B[:, i] + B[:, j])
    mid_K = 0.5 * (K[:, i] + K[:, j])
    _, hi = passive_stiffness_interval(p, mid_B)
    assert np.all(mid_K <= hi * (1 + 1e-9))


def test_area_is_bracketed_and_converges() -> None:
    p = _random(200, seed=7)
    a17 = zwidth(p, n_b=17)
    a65 = zwidth(p, n_b=65)
    lo17, up17 = a17["zwidth_area_N2_s_per_m2"], a17["zwidth_area_upper_N2_s_per_m2"]
    lo65 = a65["zwidth_area_N2_s_per_m2"]
    assert np.all(lo17 <= up17)
    assert np.all(lo17 <= lo65 * (1 + 1e-9))  # trapezoid of a concave width: from below
    assert np.all(lo65 <= up17 * (1 + 1e-9))
    assert np.max(up17 / lo17 - 1) < 0.02
    assert np.max(lo65 / lo17 - 1) < 0.01


def test_extended_set_has_positive_k_min() -> None:
    p = _random(300, seed=8)
    r = zwidth(p, n_b=9)
    ext = r["B_top_N_s_per_m"] > r["B_max_at_K0_N_s_per_m"] * (1 + 1e-6)
    assert ext.any()  # with a delay, the set reaches past B_max in some designs
    last = r["K_min_N_per_m"][ext, -1]
    assert np.all(last > 0)
    assert np.all(r["K_min_N_per_m"][~ext] == 0)


def test_scalar_design_and_bad_input() -> None:
    r = zwidth(TABLE2_MR)
    assert r["B_N_s_per_m"].shape == (17,)
    assert float(r["K_max_at_B0_N_per_m"]) == pytest.approx(max_passive_stiffness(TABLE2_MR))
    with pytest.raises(ParameterError):
        passive_stiffness_interval(TABLE2_MR, -1.0)
    with pytest.raises(ParameterError):
        zwidth(TABLE2_MR, n_b=1)


# --- stability -------------------------------------------------------------------------


def test_ray_at_zero_damping_matches_model() -> None:
    for q in (TABLE2_MR, _random(3, seed=9).item(0)):
        ks = max_stable_stiffness(q)
        for f in (0.3, 0.9, 1.1, 3.0):
            assert is_stable_spring_damper(q, f * ks, 0.0) == is_stable(q, f * ks)


def test_ray_without_delay_matches_polynomial_roots() -> None:
    rng = np.random.default_rng(10)
    p = _random(20, seed=10)
    for i in range(20):
        q = HapticParams(m1=p.m1[i], b1=p.b1[i], k=p.k[i], b=p.b[i], m2=p.m2[i])
        for _ in range(5):
            K, B = 10.0 ** rng.uniform(1, 5), 10.0 ** rng.uniform(-1, 2)
            # χ(s) = s Num + (K + Bs)(bs + k), a quartic
            num = np.array(_num_coeffs(q), dtype=float)
            chi = np.polyadd(np.append(num, 0.0), np.polymul([B, K], [q.b, q.k]))
            stable = bool(np.all(np.roots(chi).real < 0))
            assert is_stable_spring_damper(q, K, B) == stable


def test_zwidth_boundary_points_stability() -> None:
    # the MR bench (1 ms delay): the boundary points of its Z-width, checked one by one
    r = zwidth(TABLE2_MR, n_b=9)
    flags = [
        is_stable_spring_damper(TABLE2_MR, float(k), float(b))
        for k, b in zip(r["K_max_N_per_m"], r["B_N_s_per_m"], strict=True)
    ]
    assert all(flags)
    assert not is_stable_spring_damper(TABLE2_MR, 10 * max_stable_stiffness(TABLE2_MR), 0.0)


@pytest.mark.parametrize(
    ("b", "T", "K", "B", "d"),
    [(2.0, 1e-3, 100.0, 1.0, 1), (1.0, 2e-3, 250.0, 0.7, 3)],
)
def test_sampled_margin_is_the_true_maximum_not_the_grids(b, T, K, B, d):
    """With B large against K·T the right side's maximum lies inside (0, π), between two
    of the 2049 grid points: the grid alone is ~4e-7 N·s/m off. The zoomed maximum must
    equal a bounded scalar maximisation of the same right side to 1e-10 (a mutant that
    dropped the zoom survived the suite)."""
    from scipy.optimize import minimize_scalar

    from mrclutch.haptics.sampled import _cs_terms, sampled_passivity_margin

    def rhs(th: float) -> float:
        dk, cb = _cs_terms(np.array([th]), d)
        return float(K * T * dk[0] + B * cb[0])

    grid = np.linspace(0.0, np.pi, 2049)
    j = int(np.argmax([rhs(t) for t in grid]))
    assert 0 < j < 2048  # an interior maximum
    best = minimize_scalar(lambda t: -rhs(t), bounds=(grid[j - 1], grid[j + 1]),
                           method="bounded", options={"xatol": 1e-14})  # fmt: skip
    exact = b + best.fun
    assert abs((b - rhs(grid[j])) - exact) > 1e-8  # the grid alone is measurably off
    assert sampled_passivity_margin(b, T, K, B, d) == pytest.approx(exact, abs=1e-10)


@pytest.mark.parametrize(("K", "B"), [(-1.0, 0.0), (0.0, -1.0), (math.nan, 1.0), (1.0, math.inf)])
def test_spring_damper_stability_refuses_a_negative_or_non_finite_gain(K, B):
    """K and B must each be finite and ≥ 0 (a mutant that accepted any one of the four
    conditions in place of all survived the suite)."""
    from mrclutch.haptics.zwidth import is_stable_spring_damper

    with pytest.raises(ParameterError, match="need finite K, B >= 0"):
        is_stable_spring_damper(TABLE2_MR, K, B)


def test_passive_set_ends_at_b_top_past_b_max() -> None:
    """Where the set reaches past B_max (with K_min > 0), B_top is where it closes: just
    below it some K is passive, just past it none, by ``passive_stiffness_interval`` (its
    own five 41-point zooms, not zwidth's bracket). A mutant whose bracket 'doubling'
    divided (2/B) left B_top at the grid's B_max and survived the suite."""
    p = _random(300, seed=8)
    r = zwidth(p, n_b=9)
    bt = r["B_top_N_s_per_m"]
    ext = np.nonzero(bt > r["B_max_at_K0_N_s_per_m"] * (1 + 1e-6))[0]
    assert ext.size >= 10
    q = HapticParams(**{n: getattr(p, n)[ext] for n in ("m1", "b1", "k", "b", "m2", "delay")})
    lo, hi = passive_stiffness_interval(q, bt[ext] * (1 - 1e-3))
    assert np.all(np.isfinite(hi) & (lo <= hi))  # inside: a passive K exists
    lo, hi = passive_stiffness_interval(q, bt[ext] * (1 + 1e-4))
    assert np.all(np.isnan(hi) & np.isnan(lo))  # past the end: none


def test_closing_node_keeps_the_refined_bound() -> None:
    """Where the set closes at B_max (K = 0 reaches it), the last node's K_max is the
    refined bound there as the module docstring defines it (the 361-point grid and three
    21-point zooms at B_top), unaltered: ``_bound`` at the same B gives it bit for bit.
    A mutant of the closure test (K_lo + K_hi in place of K_lo − K_hi) rounded those small
    K_max (1e-14 … 1e-6 of K_max(0)) to 0 and survived the suite."""
    from mrclutch.haptics.zwidth import _bound, _columns

    p = _random(300, seed=8)
    r = zwidth(p, n_b=9)
    bt = r["B_top_N_s_per_m"]
    closes = np.nonzero(bt <= r["B_max_at_K0_N_s_per_m"] * (1 + 1e-6))[0]
    assert closes.size >= 200
    k_last = r["K_max_N_per_m"][closes, -1]
    assert np.all(k_last >= 0)
    assert np.sum(k_last < 1e-6 * r["K_max_N_per_m"][closes, 0]) >= 100  # ≈ 0: closed
    want = _bound(_columns(p), closes, bt[closes], -1.0, 3, 21)[0]
    np.testing.assert_array_equal(k_last, want)


@pytest.mark.parametrize("phi", [0.0, 0.5, 1.0, 1.5])
def test_ray_crossing_directions_match_the_quartics_roots(phi: float) -> None:
    """Without delay χ(s) = s Num(s) + ρ (c + σ s)(b s + k) is a quartic: at each crossing
    gain ρ_c the number of its roots with Re s > 0 (numpy.roots, independent of the
    module) must change by 2 × the crossing's direction between ρ_c (1 ∓ 1e-6). A mutant
    whose central difference added (χ(s+h) + χ(s−h)) flipped every direction; the
    stability verdicts, a sum of all directions, did not see it."""
    from mrclutch.haptics.zwidth import _ray_crossings

    p = _random(10, seed=10)
    c, sg = math.cos(phi), math.sin(phi)
    seen = 0
    for i in range(10):
        q = HapticParams(m1=p.m1[i], b1=p.b1[i], k=p.k[i], b=p.b[i], m2=p.m2[i])
        num = np.array(_num_coeffs(q), dtype=float)

        def unstable(rho: float, q: HapticParams = q, num: np.ndarray = num) -> int:
            chi = np.polyadd(np.append(num, 0.0), rho * np.polymul([sg, c], [q.b, q.k]))
            return int(np.sum(np.roots(chi).real > 0))

        rc, dirs = _ray_crossings(q, c, sg, 1e7)
        for r, d in zip(rc, dirs, strict=True):
            assert unstable(r * (1 + 1e-6)) - unstable(r * (1 - 1e-6)) == 2 * d
            seen += 1
    assert seen >= 3


def test_zwidth_reads_the_coarse_grid_once_and_its_damping_end_is_max_passive_damping(
    monkeypatch,
):
    """zwidth evaluates Re Z_p and the gains on U_GRID once for its lines and its B_max
    (issue 40: max_passive_damping evaluated them a second time), and its B_max is
    max_passive_damping's, bit for bit, on random designs (sampled ones too)."""
    from mrclutch.haptics import zwidth as zw

    for p in (_random(40, seed=3), _random(20, seed=4, sampled=True)):
        full = []
        real = zw._parts

        def counted(q, u, _real=real, _full=full):
            if u.shape[-1] == zw.U_GRID.size:
                _full.append(1)
            return _real(q, u)

        monkeypatch.setattr(zw, "_parts", counted)
        r = zw.zwidth(p)
        monkeypatch.setattr(zw, "_parts", real)
        assert len(full) == 1
        bm = np.asarray(max_passive_damping(p))
        assert np.asarray(r["B_max_at_K0_N_s_per_m"]).tobytes() == bm.tobytes()


def test_rows_of_checked_params_equal_checked_construction():
    """zwidth's rows (``_rows``, ``_columns``) are built without checking their fields a
    second time (``HapticParams._of_checked``): the same fields, float64 arrays and
    defaults as the checked construction gives, and the Z-width of a set equals the
    Z-width of its designs asked one by one, to the bit."""
    from mrclutch.haptics import zwidth as zw

    rng = np.random.default_rng(4)
    p = HapticParams(m1=1e-3 * (1 + rng.random(6)), b1=0.3 + rng.random(6), k=4000.0, b=20.0,
                     m2=14e-3, delay=1e-3 * rng.random(6), sample_period=0.0)  # fmt: skip
    q = zw._columns(p)
    idx = np.array([4, 1])
    for got in (q, zw._rows(q, idx)):
        names = ("m1", "b1", "k", "b", "m2", "delay", "sample_period")
        ref = HapticParams(**{n: getattr(got, n) for n in names})
        for f in ("m1", "b1", "k", "b", "m2", "delay", "f_max", "workspace", "sample_period"):
            a, b = getattr(got, f), getattr(ref, f)
            assert type(a) is type(b) and np.array_equal(a, b), f
        assert got.shape == ref.shape
    whole = zwidth(p)
    for i in range(6):
        one = zwidth(p.item(i))
        for key in ZWIDTH_KEYS:
            assert np.array_equal(whole[key][i], one[key], equal_nan=True), key
