"""The robust sweep columns' cheaper worst cases (issue 40 item 4) against what they
replace: the worst largest stable K from the crossings over the box
(``robust_search.stable_worst_box``) against the 3 × 3 × 3 box search with six zooms, and
the worst bandwidth exact over τ and K (``robust_columns.bandwidth_worst_delay_K``)
against dense sampling of τ and K."""

import numpy as np
import pytest
from test_robust import _random_boxes

from mrclutch.hand_box import HandBox
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import bandwidth, max_stable_stiffness
from mrclutch.robust import box_search, robust_limits, stable_stiffness_batch
from mrclutch.robust_columns import bandwidth_worst_delay_K
from mrclutch.robust_search import stable_worst_box


def _box3(box):
    lo = np.stack([box.m1[1], box.b1[1], box.delay[1]], 1)
    hi = np.stack([box.m1[2], box.b1[2], box.delay[2]], 1)
    return lo, hi


def _searched(box, lo, hi):
    """The search the sweep ran before (robust_limits' worst stable K until issue 40)."""
    v, _ = box_search(
        lambda x: stable_stiffness_batch(box.params(x[..., 0], x[..., 1], x[..., 2])),
        lo, hi, sense=-1, points=3, zooms=5,
    )  # fmt: skip
    return v


def _one(m1, b1, tau, k=4000.0, b=20.0, m2=14e-3):
    """A HandBox of one design with these (nominal, low, high) ranges."""
    return HandBox(*(tuple(np.array([float(x)]) for x in t) for t in (m1, b1, tau, (1, 1, 1))),
                   np.array([k]), np.array([b]), np.array([m2]), np.array([True]))  # fmt: skip


def test_stable_worst_never_above_the_box_search_and_never_far_below():
    """200 random designs with random ranges (test_robust's): the worst from the crossings
    is never above the box search's (every point the search tries is inside the box, so
    its value bounds the least from above) by more than the roots' 1e-9, and never more
    than 1e-6 below it: where the search's grid holds the worst point, both find it.
    Design 107 is one whose worst sits on a window of frequency narrower than a grid cell
    (the ray of one end of the delay across an edge of the box): the corners' crossings
    put a point inside it (4.0e-6 above the search without them)."""
    box = _random_boxes(np.random.default_rng(29), 200)
    lo, hi = _box3(box)
    got, done = stable_worst_box(lo, hi, box.k, box.b, box.m2)
    assert done.all()
    ref = _searched(box, lo, hi)
    r = got / ref - 1
    assert np.max(r) <= 1e-9, (np.argmax(r), np.max(r))
    assert np.min(r) >= -1e-6, (np.argmin(r), np.min(r))
    assert abs(r[107]) <= 1e-8


def test_stable_worst_of_a_point_box_is_the_kernel():
    """A box of one point: the worst is stable_stiffness_batch there (its crossings, the
    same grid and refinement), to 1e-9; a box of one (m1, b1) with a delay range: never
    above the kernel at either end of the delay."""
    p = HapticParams(np.array([1.5e-3, 4e-3]), np.array([0.3, 1.2]), 4000.0, 20.0, 14e-3,
                     delay=np.array([1e-3, 3e-3]))  # fmt: skip
    lo = hi = np.stack([p.m1, p.b1, p.delay], 1)
    got, done = stable_worst_box(lo, hi, 4000.0, 20.0, 14e-3)
    assert done.all()
    np.testing.assert_allclose(got, stable_stiffness_batch(p), rtol=1e-9)
    hi2 = hi * np.array([1.0, 1.0, 2.0])
    got2, _ = stable_worst_box(lo, hi2, 4000.0, 20.0, 14e-3)
    ends = stable_stiffness_batch(HapticParams(p.m1, p.b1, 4000.0, 20.0, 14e-3, delay=hi2[:, 2]))
    assert np.all(got2 <= np.minimum(got, ends) * (1 + 1e-9))


def test_stable_worst_without_a_delay_is_searched():
    """τ⁺ = 0 (no delay: the exact kernel's case) leaves the crossings' scan undone; the
    sweep's column then runs the box search: robust_limits gives its value."""
    box = _one((1.5e-3, 1.4e-3, 1.6e-3), (0.3, 0.2, 0.5), (0.0, 0.0, 0.0))
    lo, hi = _box3(box)
    _, done = stable_worst_box(lo, hi, box.k, box.b, box.m2)
    assert not done[0]
    lim = robust_limits(box, cases=("worst",))["max_stable_K_worst"]
    assert lim[0] == _searched(box, lo, hi)[0]


def test_bandwidth_worst_over_delay_and_K_against_dense_sampling():
    """200 random designs at their nominal (m1, b1), τ and K over their ranges: the exact
    least over (τ, K) is never above a 60 × 7 sampling of them (corners included) by
    more than the bandwidth's 1e-8, and never below it: here the least is at a corner."""
    box = _random_boxes(np.random.default_rng(5), 200)
    m1, b1 = box.m1[0][:, None], box.b1[0][:, None]
    got = bandwidth_worst_delay_K(box, m1, b1, box.delay[1:], box.K[1:])[:, 0]
    u, v = np.linspace(0, 1, 60)[None, :, None], np.linspace(0, 1, 7)[None, None, :]
    (_, tl, th), (_, kl, kh) = box.delay, box.K
    tau, K = np.broadcast_arrays(tl[:, None, None] + (th - tl)[:, None, None] * u,
                                 kl[:, None, None] + (kh - kl)[:, None, None] * v)  # fmt: skip
    p = HapticParams(m1[..., None], b1[..., None], box.k[:, None, None], box.b[:, None, None],
                     box.m2[:, None, None], delay=tau)  # fmt: skip
    dense = np.nanmin(bandwidth(p, K).reshape(200, -1), axis=1)
    np.testing.assert_allclose(got, dense, rtol=1e-8)


def test_bandwidth_worst_at_a_delay_inside_its_range():
    """A light transmission (b = 0.25 N·s/m) and a delay range of 2.5–11.7 ms: the first
    crossing comes earliest at a delay inside the range (where K·E e^{−jωτ}/D turns
    negative real), 0.6 % below either end; found exactly (the polynomial's root) and
    matched by 4000 samples of τ to 1e-6."""
    m1, b1, k, b, m2, K = 1e-3, 4.07, 700.0, 0.25, 1.44e-3, 276.0
    box = _one((m1, m1, m1), (b1, b1, b1), (2.5e-3, 2.5e-3, 11.7e-3), k=k, b=b, m2=m2)
    Ks = (np.array([K]), np.array([K]))
    got = bandwidth_worst_delay_K(box, np.array([[m1]]), np.array([[b1]]), box.delay[1:], Ks)
    tau = np.linspace(2.5e-3, 11.7e-3, 4000)
    dense = bandwidth(HapticParams(m1, b1, k, b, m2, delay=tau), K)
    ends = dense[[0, -1]]
    assert got[0, 0] < 0.995 * np.min(ends)
    assert got[0, 0] <= np.nanmin(dense) * (1 + 1e-9)
    assert got[0, 0] == pytest.approx(np.nanmin(dense), rel=1e-6)


def test_bandwidth_worst_over_K_is_at_an_end():
    """test_robust's design whose bandwidth falls as K rises (Eq. 1's √K has it rise):
    over a K range the least is at an end (k_eff is linear in K), here K⁺, not the K⁻
    Eq. 1 would pick; equal to the least of 200 samples."""
    p = HapticParams(1e-3, 1.0, 10**2.5, 1.0, 1e-3, delay=1e-2)
    K0 = 0.5 * max_stable_stiffness(p)
    box = _one((1e-3, 1e-3, 1e-3), (1.0, 1.0, 1.0), (1e-2, 1e-2, 1e-2), k=10**2.5, b=1.0,
               m2=1e-3)  # fmt: skip
    Ks = (np.array([0.01 * K0]), np.array([1.2 * K0]))
    got = bandwidth_worst_delay_K(box, np.array([[1e-3]]), np.array([[1.0]]), box.delay[1:], Ks)
    dense = bandwidth(p, np.linspace(0.01 * K0, 1.2 * K0, 200))
    assert np.argmin(dense) == 199
    assert got[0, 0] == pytest.approx(np.min(dense), rel=1e-9)


def test_stable_worst_at_a_dip_of_the_loop_gain_inside_the_delay_range():
    """A light transmission (b = 0.035 N·s/m): |G(ω)| dips near its resonance, and a delay
    inside 0.094–2.37 ms puts that dip on a crossing: the worst is 2.9 % below the kernel
    at either end of the delay (a corner of (m1, b1) inside the cone, the first family),
    and 4000 samples of the delay find it to 1e-7 (never below it)."""
    m1, b1, k, b, m2, ta, tb = 2.5452e-4, 3.7077, 1155.8, 0.035267, 1.19358e-3, 9.3565e-5, 2.3718e-3
    got, done = stable_worst_box(np.array([[m1, b1, ta]]), np.array([[m1, b1, tb]]), k, b, m2)
    assert done[0]
    tau = np.linspace(ta, tb, 4000)
    dense = stable_stiffness_batch(HapticParams(m1, b1, k, b, m2, delay=tau))
    assert got[0] < 0.975 * min(dense[0], dense[-1])
    assert got[0] <= np.min(dense) * (1 + 1e-9)
    assert got[0] == pytest.approx(np.min(dense), rel=1e-7)


def test_stable_worst_at_an_edges_point_nearest_zero():
    """A box whose worst lies inside an edge (b1 at its low end, m1 = 27.7 g inside
    25.9–103 g) with the delay inside its range (5.06 ms in 1.99–8.37 ms): the edge's
    point nearest 0 (the second family). It is the kernel's limit at that point to 1e-6,
    and 0.027 % below what the 3 × 3 × 3 search with six zooms found."""
    lo = np.array([[0.02585, 4.336, 1.99221e-3]])
    hi = np.array([[0.10278, 15.13, 8.37057e-3]])
    k, b, m2 = 1427.4, 0.014915, 1.60392e-3
    got, done = stable_worst_box(lo, hi, k, b, m2)
    assert done[0]
    at = stable_stiffness_batch(HapticParams(0.027746, 4.336, k, b, m2, delay=5.0568e-3))
    assert got[0] == pytest.approx(float(at), rel=1e-6)
    box = _one((lo[0, 0], lo[0, 0], hi[0, 0]), (lo[0, 1], lo[0, 1], hi[0, 1]),
               (lo[0, 2], lo[0, 2], hi[0, 2]), k=k, b=b, m2=m2)  # fmt: skip
    assert got[0] < (1 - 2e-4) * _searched(box, lo, hi)[0]


def test_bandwidth_worst_searched_on_the_edges_is_below_every_inside_point():
    """The worst bandwidth searches only the edges of (m1, b1) (k_eff is harmonic in D
    there: its least lies on the edges): on 100 random boxes no point of a 9 × 9 grid of
    (m1, b1), inside included, with τ and K over their ranges, is below it."""
    box = _random_boxes(np.random.default_rng(31), 100)
    worst = robust_limits(box, cases=("worst",))["bandwidth_worst"]
    t = np.linspace(0.0, 1.0, 9)
    (_, ml, mh), (_, bl, bh) = box.m1, box.b1
    m1 = (ml[:, None, None] + (mh - ml)[:, None, None] * t[:, None]).repeat(9, 2).reshape(100, -1)
    b1 = (bl[:, None, None] + (bh - bl)[:, None, None] * t[None, :]).repeat(9, 1).reshape(100, -1)
    grid = bandwidth_worst_delay_K(box, m1, b1, box.delay[1:], box.K[1:])
    assert np.all(worst <= np.nanmin(grid, axis=1) * (1 + 1e-9))


def test_stable_worst_finds_the_slow_delayed_mode_below_the_old_start():
    """test_mutation_survivors_robust's rigid lever at a 1 ms delay (a linear grid the
    scan takes itself): a light actuator (0.1 g) on a stiff, damped coupling puts Num's
    largest zero near 4.8e5 rad/s, and the slow delayed mode crosses at 5 rad/s, below
    10⁻⁴ of it. The crossings' scan starts below every point's ``quiet_below`` over the box
    (as stable_stiffness_batch does): a point box and a box around it give that limit,
    M ω_c²/cos(ω_c τ) = 5.00256 N/m to the coupling's O(K/k) (it read 7.9e6 N/m when the
    scan started at 10⁻⁴ ω_a)."""
    m1, m2, tau, wc = 1e-4, 0.2, 1e-3, 5.0
    M = m1 + m2
    b1 = M * wc * np.tan(wc * tau)
    kc = M * wc**2 / np.cos(wc * tau)
    lo = np.array([[m1, b1, tau]])
    got, done = stable_worst_box(lo, lo, 1e6, 50.0, m2)
    assert done[0] and got[0] == pytest.approx(kc, rel=1e-5)
    wide, done = stable_worst_box(lo, lo * np.array([[1.2, 1.5, 1.5]]), 1e6, 50.0, m2)
    assert done[0] and wide[0] <= got[0] * (1 + 1e-9)


def test_bandwidth_of_points_side_by_side_is_each_points_own():
    """``bandwidth_worst_delay_K`` takes the four corners (τ, K) of each (m1, b1) in one
    ``bandwidth`` call: a point's bandwidth there equals its bandwidth in a call of its own
    corner, to the bit (120 random designs x 3 points; the corners' bisection and root-find
    are each point's own), and the worst over them is the least of the four calls."""
    box = _random_boxes(np.random.default_rng(11), 120)
    u = np.random.default_rng(12).random((2, 120, 3))
    m1 = box.m1[1][:, None] + (box.m1[2] - box.m1[1])[:, None] * u[0]
    b1 = box.b1[1][:, None] + (box.b1[2] - box.b1[1])[:, None] * u[1]
    (_, ta, tb), (_, ka, kb) = box.delay, box.K
    one = [
        bandwidth(
            box.params(m1, b1, np.broadcast_to(t[:, None], m1.shape)),
            np.broadcast_to(k[:, None], m1.shape),
        )
        for t in (ta, tb)
        for k in (ka, kb)
    ]
    side = bandwidth(box.params(np.tile(m1, 4), np.tile(b1, 4),
                                np.repeat(np.stack([ta, ta, tb, tb], 1), 3, axis=1)),
                     np.repeat(np.stack([ka, kb, ka, kb], 1), 3, axis=1))  # fmt: skip
    assert np.array_equal(side, np.concatenate(one, axis=1), equal_nan=True)
    corners = np.fmin.reduce(np.stack(one), axis=0)
    got = bandwidth_worst_delay_K(box, m1, b1, (ta, tb), (ka, kb))
    assert np.all((got <= corners) | np.isnan(corners))
    assert np.isfinite(got).sum() > 300
