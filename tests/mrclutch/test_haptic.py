"""The 2-DOF haptic model: closed forms, limits, two-method agreement, time domain."""

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mrclutch.haptics.actuator import (
    TABLE2_EM_118890,
    TABLE2_EM_136206,
    TABLE2_EM_136209,
    TABLE2_MR,
    HapticParams,
)
from mrclutch.haptics.model import (
    METRIC_KEYS,
    bandwidth,
    bandwidth_lumped,
    closed_loop_impedance,
    effective_impedance,
    is_passive,
    is_stable,
    max_passive_stiffness,
    max_stable_stiffness,
    metrics,
    metrics_batch,
    passive_impedance,
    rendering_area,
    resonance,
)

SETS = [TABLE2_MR, TABLE2_EM_118890, TABLE2_EM_136206, TABLE2_EM_136209]
W = 2 * np.pi * np.logspace(-1, 4, 2001)  # 0.1 Hz – 10 kHz


def _eq2(p, w):
    """Eq. 2 as printed in the paper, coefficient by coefficient."""
    s = 1j * w
    m1, m2, b1, b, k = p.m1, p.m2, p.b1, p.b, p.k
    num = m1 * m2 * s**3 + (m2 * b1 + m1 * b + m2 * b) * s**2 + (b1 * b + m1 * k + m2 * k) * s
    return (num + b1 * k) / (m1 * s**2 + (b1 + b) * s + k)


@pytest.mark.parametrize("p", SETS)
def test_closed_loop_at_zero_K_is_eq2(p):
    z0 = closed_loop_impedance(p, 0.0, W)
    assert np.max(np.abs(z0 / _eq2(p, W) - 1)) < 1e-12
    assert np.max(np.abs(passive_impedance(p, W) / _eq2(p, W) - 1)) < 1e-12


@settings(max_examples=25, deadline=None)
@given(K=st.floats(1.0, 5000.0), tau=st.floats(0.0, 3e-3), i=st.integers(0, 3))
def test_closed_loop_solves_the_equations_of_motion(K, tau, i):
    """Z_cl against a direct solve of the two force balances with F_a = −K e^{−sτ} x2."""
    p = replace(SETS[i], delay=tau)
    w = W[::50]
    s = 1j * w
    zs = []
    for sj in s:
        E = np.exp(-sj * tau)
        # unknowns x1, F_h for x2 = 1
        A = np.array(
            [[p.m1 * sj**2 + (p.b1 + p.b) * sj + p.k, 0], [-(p.b * sj + p.k), -1]], dtype=complex
        )
        rhs = np.array([-K * E + (p.b * sj + p.k), -(p.m2 * sj**2 + p.b * sj + p.k)])
        _x1, Fh = np.linalg.solve(A, rhs)
        zs.append(Fh / sj)
    assert np.max(np.abs(closed_loop_impedance(p, K, w) / np.array(zs) - 1)) < 1e-10


def test_rigid_transmission_limit_is_the_lumped_spring_mass():
    """k → ∞, no delay: Z → (m1+m2)s + b1 + K/s, so k_eff = K − (m1+m2)ω² and the full
    bandwidth is Eq. 1 exactly."""
    p = replace(TABLE2_EM_136209, k=1e13, b=0.0)
    K = 200.0
    w = np.array([3.0, 30.0, 300.0])
    eff = effective_impedance(p, K, w)
    m = p.m1 + p.m2
    assert eff.stiffness == pytest.approx(K - m * w**2, rel=1e-6)
    assert eff.damping == pytest.approx(p.b1, rel=1e-6)
    assert float(bandwidth(p, K)) == pytest.approx(float(bandwidth_lumped(p, K)), rel=1e-6)


@pytest.mark.parametrize("p", SETS)
def test_bandwidth_is_a_root_to_better_than_0p1_percent(p):
    K = 300.0
    f = float(bandwidth(p, K))
    w = 2 * np.pi * f * np.array([1 - 1e-3, 1 + 1e-3])
    k_eff = effective_impedance(p, K, w).stiffness
    assert k_eff[0] > 0 > k_eff[1]  # the + → − crossing lies within ±0.1 %
    # and it is the first: k_eff stays positive below it
    below = effective_impedance(p, K, 2 * np.pi * np.linspace(0.01, 0.999, 400) * f).stiffness
    assert np.all(below > 0)


def test_effective_impedance_limits():
    p = TABLE2_MR
    eff = effective_impedance(p, 250.0, np.array([1e-2, 2 * np.pi * 1e5]))
    assert eff.stiffness[0] == pytest.approx(250.0, rel=1e-3)  # the virtual spring at DC
    assert eff.mass[1] == pytest.approx(p.m2, rel=2e-2)  # the lever alone at high frequency
    assert eff.mass == pytest.approx(-eff.stiffness / np.array([1e-2, 2 * np.pi * 1e5]) ** 2)


def test_resonance_closed_form_undamped():
    p = HapticParams(m1=0.02, b1=1e-9, k=6000.0, b=0.0, m2=0.014)
    wr = math.sqrt(p.k * (p.m1 + p.m2) / (p.m1 * p.m2))  # two masses on a spring
    assert resonance(p) == pytest.approx(wr / (2 * math.pi), rel=1e-6)
    # and it is where |Z_p| is smallest (a zero of Eq. 2)
    f = np.linspace(0.9, 1.1, 2001) * resonance(p)
    assert f[np.argmin(np.abs(passive_impedance(p, 2 * np.pi * f)))] == pytest.approx(
        resonance(p), rel=2e-4
    )
    assert math.isnan(resonance(replace(p, b=200.0)))  # overdamped: none


def test_vectorised_equals_design_by_design():
    rng = np.random.default_rng(3)
    n = 50
    p = HapticParams(
        m1=rng.uniform(1e-3, 0.04, n),
        b1=rng.uniform(0.1, 2, n),
        k=rng.uniform(2e3, 8e3, n),
        b=rng.uniform(1, 25, n),
        m2=0.014,
        delay=rng.uniform(0, 2e-3, n),
    )
    K = rng.uniform(50, 800, n)
    batch = metrics_batch(p, K, limits=False)
    for i in range(0, n, 7):
        q = p.item(i)
        assert batch["bandwidth_hz"][i] == pytest.approx(float(bandwidth(q, K[i])), rel=1e-7)
        assert batch["rendering_area_dB_decade"][i] == pytest.approx(rendering_area(q, K[i]))
        assert batch["resonance_hz"][i] == pytest.approx(resonance(q), nan_ok=True)
    # designs × frequencies in one call
    w = np.logspace(0, 4, 30)
    Z = closed_loop_impedance(
        replace(
            p,
            **{
                f: np.asarray(getattr(p, f))[..., None] if np.ndim(getattr(p, f)) else getattr(p, f)
                for f in ("m1", "b1", "k", "b", "delay")
            },
        ),
        K[:, None],
        w,
    )
    assert Z.shape == (n, 30)
    assert Z[4] == pytest.approx(closed_loop_impedance(p.item(4), K[4], w))


def test_rendering_area_definition():
    p = TABLE2_EM_136206
    assert rendering_area(p, 0.0) == 0.0
    # converges with the grid: 25 points per decade within 0.02 dB·decade of 20000
    ref = rendering_area(p, 300.0, points_per_decade=20000)
    assert abs(rendering_area(p, 300.0) - ref) < 0.02
    # well below the bandwidth the closed loop is K/ω against b1: the area over a band
    # f_lo…f_hi ≪ f_bw is ∫ 20 log10(K/(ω b1)) d(log10 f), a closed form
    band = (1e-3, 1e-2)
    u = np.log10(band)
    expected = 20 * (
        math.log10(300.0 / (2 * math.pi * p.b1)) * (u[1] - u[0]) - (u[1] ** 2 - u[0] ** 2) / 2
    )
    assert rendering_area(p, 300.0, band=band) == pytest.approx(expected, rel=1e-3)


def test_passivity_limit_closed_form_and_dense_check():
    """At ω → 0, Re Z_cl → b1 − K(τ + b1/k): for the MR set that is the binding limit,
    K_p = b1/(τ + b1/k) = 800 N/m."""
    p = TABLE2_MR
    kp = max_passive_stiffness(p)
    assert kp == pytest.approx(p.b1 / (p.delay + p.b1 / p.k), rel=1e-6)
    w = 2 * np.pi * np.logspace(-4, 5, 20000)
    assert np.all(closed_loop_impedance(p, 0.99 * kp, w).real >= 0)
    assert np.min(closed_loop_impedance(p, 1.01 * kp, w).real) < 0
    assert is_passive(p, 0.99 * kp) and not is_passive(p, 1.01 * kp)
    # every Table 2 set: the dense grid agrees with the limit
    for q in SETS[1:]:
        kq = max_passive_stiffness(q)
        assert np.min(closed_loop_impedance(q, 1.001 * kq, w).real) < 0
        assert np.all(closed_loop_impedance(q, 0.999 * kq, w).real >= 0)


def _routh_limit(p):
    """Delay-free: χ = s Num + K(bs + k) is a quartic; bisect K on the largest real root."""
    a3, a2, a1, a0 = (
        p.m1 * p.m2,
        p.m2 * p.b1 + p.m1 * p.b + p.m2 * p.b,
        p.b1 * p.b + (p.m1 + p.m2) * p.k,
        p.b1 * p.k,
    )

    def unstable(K):
        return np.max(np.roots([a3, a2, a1, a0 + K * p.b, K * p.k]).real) > 0

    lo, hi = 1.0, 1.0
    while not unstable(hi):
        hi *= 2
    for _ in range(80):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return lo


@pytest.mark.parametrize("p", SETS)
def test_delay_free_stability_limit_agrees_with_polynomial_roots(p):
    q = replace(p, delay=0.0)
    assert max_stable_stiffness(q) == pytest.approx(_routh_limit(q), rel=1e-6)


def test_delay_destabilises_and_the_tool_says_so():
    K = 1000.0
    assert not is_stable(TABLE2_MR, K)  # 1 ms delay: above its 894 N/m limit
    assert is_stable(replace(TABLE2_MR, delay=0.0), K)  # delay-free: stable
    assert metrics(TABLE2_MR, K)["max_stable_K_N_per_m"] < K
    assert is_stable(TABLE2_MR, 0.0) and is_stable(TABLE2_MR, 500.0)


def _simulate_growth(p, K, t_end=1.0, steps_per_delay=50):
    """Growth rate [1/s] of the free delayed loop: exact discretisation of the 2-DOF
    equations with the delayed force linearly interpolated (first-order hold)."""
    from scipy.linalg import expm

    A = np.array(
        [
            [0, 1, 0, 0],
            [-p.k / p.m1, -(p.b1 + p.b) / p.m1, p.k / p.m1, p.b / p.m1],
            [0, 0, 0, 1],
            [p.k / p.m2, p.b / p.m2, -p.k / p.m2, -p.b / p.m2],
        ]
    )
    B = np.array([0, 1 / p.m1, 0, 0])
    h = p.delay / steps_per_delay
    M = np.zeros((6, 6))  # [franklin-powell-workman]: FOH discretisation by one expm
    M[:4, :4], M[:4, 4], M[4, 5] = A * h, B * h, 1.0
    E = expm(M)
    Phi, G1, G2 = E[:4, :4], E[:4, 4], E[:4, 5]
    n = int(t_end / h)
    x = np.array([0.0, 0.0, 1e-3, 0.0])
    x2 = np.zeros(n + 1)
    x2[0] = x[2]
    hist0 = x[2]  # x2 = x2(0) for t < 0 (held before start)
    for i in range(n):
        u0 = -K * (x2[i - steps_per_delay] if i >= steps_per_delay else hist0)
        j = i + 1 - steps_per_delay
        u1 = -K * (x2[j] if j >= 0 else hist0)
        x = Phi @ x + G1 * u0 + G2 * (u1 - u0)
        x2[i + 1] = x[2]
    t = np.arange(n + 1) * h
    # slope of log(window max |x2|) over the second half
    win = n // 20
    tail = np.abs(x2[n // 2 :])
    tt = t[n // 2 :]
    peaks = [tail[k : k + win].max() for k in range(0, tail.size - win, win)]
    tp = [tt[k] for k in range(0, tail.size - win, win)]
    return np.polyfit(tp, np.log(peaks), 1)[0]


def test_largest_stable_K_matches_time_domain_within_5_percent():
    p = TABLE2_MR
    ks = max_stable_stiffness(p)
    k1, k2 = 0.95 * ks, 1.05 * ks
    s1, s2 = _simulate_growth(p, k1), _simulate_growth(p, k2)
    assert s1 < 0 < s2
    k_td = k1 + (k2 - k1) * (-s1) / (s2 - s1)
    assert k_td == pytest.approx(ks, rel=0.05)


def test_metrics_keys_and_defaults():
    m = metrics(TABLE2_EM_136206)
    assert tuple(m) == METRIC_KEYS
    assert m["K_N_per_m"] == pytest.approx(TABLE2_EM_136206.k_max)
    assert m["passive"] is True
    assert m["bandwidth_hz"] > 0 and m["rendering_area_dB_decade"] > 0


def test_metrics_batch_limits_match_scalar():
    p = HapticParams(
        m1=np.array([1.5e-3, 22e-3, 38e-3]),
        b1=np.array([1.0, 0.6, 1.1]),
        k=4000.0,
        b=20.0,
        m2=0.014,
        delay=np.array([1e-3, 0.0, 5e-4]),
    )
    K = np.array([300.0, 900.0, 2000.0])
    b = metrics_batch(p, K)
    for i in range(3):
        m = metrics(p.item(i), K[i])
        for key in METRIC_KEYS:
            assert b[key][i] == pytest.approx(m[key], rel=1e-9, nan_ok=True)
