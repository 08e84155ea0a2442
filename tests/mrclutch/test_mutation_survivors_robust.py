"""Tests written for the round2 mutation run's survivors in the robust kernels
(mrclutch/robust_search.py, mrclutch/robust.py; benchmarks/mutation_run.py --run round2,
docs/testing.md): each drives a branch the run's tests left unexercised and checks its
answer against a closed form or an independent computation."""

import math
from dataclasses import replace

import numpy as np
import pytest

from mrclutch import robust_search
from mrclutch.design import design_preset
from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.hand import NO_HAND, max_stable_stiffness_coupled
from mrclutch.haptics.model import max_stable_stiffness, rendering_area
from mrclutch.haptics.zwidth import zwidth
from mrclutch.pipeline import evaluate
from mrclutch.robust import robust_box, robust_verdicts, threshold
from mrclutch.robust_search import box_search, stable_stiffness_batch, zero_moduli


def _one(p: HapticParams) -> HapticParams:
    """``p`` as a vectorised set of one design (the batch kernel's input)."""
    return HapticParams(np.array([p.m1]), p.b1, p.k, p.b, p.m2, delay=p.delay)


def test_a_light_lever_with_little_grounded_damping_is_limited_by_its_slow_delayed_mode():
    """The rigid lever (m1 + m2 = M, grounded damping b1, rendered K, delay τ):
    M s² + b1 s + K e^{−sτ} = 0 has a root at jω_c (its real and imaginary parts:
    K cos ω_cτ = Mω_c², K sin ω_cτ = b1ω_c) for K_c = Mω_c²/cos(ω_cτ) when
    b1 = Mω_c tan(ω_cτ). With ω_c = 5 rad/s, τ = 10 ms, M = 0.2001 kg: b1 = 0.050067 N·s/m,
    K_c = 5.008760 N/m. A stiff, strongly damped coupling (k = 10⁶ N/m, b = 50 N·s/m) on a
    light actuator (m1 = 0.1 g) puts Num's largest zero at b/m1 ≈ 4.8e5 rad/s, so 5 rad/s
    lies below 10⁻⁴ ω_a, where the three kernels (exact, batch, coupled without a hand)
    began their scans: they missed this crossing and gave 79002 N/m, a spring the loop
    cannot hold (a Padé(8) model of the delay has roots with Re s > 0 there). The
    coupling's compliance moves the 2-DOF limit from the rigid one by O(K/k) = 5e-6:
    rtol 1e-5."""
    m1, m2, tau, wc = 1e-4, 0.2, 0.01, 5.0
    M = m1 + m2
    b1 = M * wc * math.tan(wc * tau)
    k_c = M * wc**2 / math.cos(wc * tau)
    assert abs(k_c - 5.008760) < 1e-6
    p = HapticParams(m1, b1, 1e6, 50.0, m2, delay=tau)
    assert max_stable_stiffness(p) == pytest.approx(k_c, rel=1e-5)
    assert stable_stiffness_batch(_one(p))[0] == pytest.approx(k_c, rel=1e-5)
    assert max_stable_stiffness_coupled(p, NO_HAND) == pytest.approx(k_c, rel=1e-5)


def test_box_search_without_a_sense_finds_the_smallest():
    """``box_search``'s default (sense −1) is the smallest of fn over the box: for
    f = x + 2y on [0, 1]² that is 0 at (0, 0); the largest, 3 at (1, 1), only when asked
    for (the mutant default sense = +1 gives 3)."""
    lo, hi = np.array([[0.0, 0.0]]), np.array([[1.0, 1.0]])

    def f(x):
        return x[..., 0] + 2.0 * x[..., 1]

    v, arg = box_search(f, lo, hi)
    assert v[0] == 0.0 and arg[0].tolist() == [0.0, 0.0]
    v, arg = box_search(f, lo, hi, sense=1)
    assert v[0] == 3.0 and arg[0].tolist() == [1.0, 1.0]


def test_the_batch_kernel_settles_the_paper_lever_and_stiff_ones_itself():
    """The batch kernel's own scan, not its fallback: the paper's MR lever (Table 2, 1 ms)
    and four stiffer or faster ones (k up to 10⁶ N/m, τ down to 0.1 ms; K_max 894 to
    9907 N/m) have a delay, no hold, a crossing and a linear grid of a few hundred points,
    so none is handed to the exact kernel (the docstring's conditions), and each equals the
    exact kernel called directly (another grid) to 1e-9. A crossing test that rejects the
    refined root (|Im X| ≤ 1e-6/|X| instead of 1e-6·|X|: 1e-10 absolute at 10⁴ N/m) or an
    X evaluated off the axis (s = j/ω) leaves the scan with nothing and hands designs over."""
    designs = [
        TABLE2_MR,
        replace(TABLE2_MR, delay=1e-4),
        replace(TABLE2_MR, k=3e4, delay=2e-4),
        replace(TABLE2_MR, k=1e5, delay=1e-4),
        replace(TABLE2_MR, k=1e6, b=200.0, delay=1e-4),
    ]
    p = HapticParams(
        *(np.array([getattr(d, f) for d in designs]) for f in ("m1", "b1", "k", "b", "m2")),
        delay=np.array([d.delay for d in designs]),
    )
    exact = [max_stable_stiffness(d) for d in designs]
    assert 890 < exact[0] < 900 and max(exact) > 9000

    def no_fallback(q):
        raise AssertionError(f"handed to the exact kernel: {q}")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(robust_search, "max_stable_stiffness", no_fallback)
        got = stable_stiffness_batch(p)
    np.testing.assert_allclose(got, exact, rtol=1e-9)


def test_a_delay_threshold_is_searched_up_to_one_second_and_no_further():
    """``threshold`` on the delay scans up to 1 s (its docstring), whatever 10³ × the
    value in ``p`` (2 ms here: 2 s). The paper's MR lever at 2 ms: K set to its own
    stability limit at τ = 0.95 s gives a threshold of 0.95 s (the limit falls with the
    delay: stable below, "≤"); K set to the limit at τ = 1.05 s gives none, the crossing
    being past the end of the scan (the mutant end 1.1 s finds it)."""
    p = replace(TABLE2_MR, delay=2e-3)
    k95 = max_stable_stiffness(replace(p, delay=0.95))
    t = threshold(p, k95, "stable", "delay")
    assert t is not None
    assert t["value"] == pytest.approx(0.95, rel=1e-8) and t["sense"] == "≤"
    k105 = max_stable_stiffness(replace(p, delay=1.05))
    assert k105 < k95  # the limit falls with the delay
    assert threshold(p, k105, "stable", "delay") is None


def test_the_robust_areas_are_searched_over_the_whole_box_of_m1_b1_and_the_delay():
    """The rendering area at K and the Z-width area, worst and best over the (m1, b1, τ)
    box of the paper preset's robust read-out: the search's first grid holds the box's 8
    corners, so its worst is at most, and its best at least, every corner's value
    (computed here directly). b1 decides both (the Z-width grows with b1, ×10 over the
    box; the rendering area falls from 36.5 to 25.1 dB/decade), so a search box that
    loses b1's low edge (the mutant lo3 = b1's high edge) reads a best area of 25.2 and a
    worst Z-width of 733 instead of 36.5 and 18.4."""
    ev = evaluate(design_preset("paper"))
    rb = robust_box(ev)
    r = robust_verdicts(ev, prepared=rb)
    box, K = rb.box, r["K_N_per_m"]
    edges = [
        np.array([getattr(box, f)[1][0], getattr(box, f)[2][0]]) for f in ("m1", "b1", "delay")
    ]
    m1, b1, tau = (x.ravel()[None] for x in np.meshgrid(*edges, indexing="ij"))
    corners = box.params(m1, b1, tau)
    for key, values in (
        ("rendering_area_dB_decade", rendering_area(corners, K)),
        ("zwidth_area_N2_s_per_m2", zwidth(corners)["zwidth_area_N2_s_per_m2"]),
    ):
        v = np.ravel(values)
        assert r[key]["worst"] <= np.min(v) and r[key]["best"] >= np.max(v), key
        assert np.max(v) > 1.3 * np.min(v), key  # the box matters: b1 moves both


def test_zero_moduli_are_those_of_cubics_with_known_zeros():
    """``zero_moduli`` (the batch kernel's ω_a and the slowest zero behind its scan's
    start, ``limits.quiet_below``) on cubics built from their zeros, leading coefficient
    ≠ 1 so that a coefficient not divided by it shows: 2(s + 1)(s + 2)(s + 3) =
    2s³ + 12s² + 22s + 12 → 1, 2, 3; 4(s + 0.5)(s² + 2s + 100) = 4s³ + 10s² + 404s + 200 →
    0.5, 10, 10 (|−1 ± j√99| = 10). Dropping the companion row's sign gives the zeros of
    s³ − 6s² − 11s − 6 instead (7.56, 0.89, 0.89)."""
    coeffs = tuple(np.array(c, float) for c in ([2, 4], [12, 10], [22, 404], [12, 200]))
    got = np.sort(zero_moduli(coeffs), axis=1)
    np.testing.assert_allclose(got, [[1.0, 2.0, 3.0], [0.5, 10.0, 10.0]], rtol=1e-12)
