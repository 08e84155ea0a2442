import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from magnetics.materials import (
    MATERIALS,
    MRF_132DG,
    MRF_132DG_DATASHEET_TAU,
    MU0,
    STEEL_1018,
)


@pytest.mark.parametrize("mat", [STEEL_1018, MATERIALS["mrf_132dg"]])
def test_table_points_are_reproduced_and_extrapolation_has_slope_mu0(mat):
    b = np.array(mat.b_table)
    np.testing.assert_allclose(mat.h_of_b(b), mat.h_table, rtol=1e-3)
    b_hi = mat.b_table[-1] + np.array([0.1, 1.0])
    dh = np.diff(mat.h_of_b(b_hi))[0]
    assert dh == pytest.approx(0.9 / MU0, rel=1e-9)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-5, 5), min_size=2, max_size=20))
def test_h_of_b_is_odd_monotone_and_inverted_by_b_of_h(bs):
    b = np.sort(np.array(bs))
    h = STEEL_1018.h_of_b(b)
    assert np.all(np.diff(h) >= 0)
    np.testing.assert_allclose(STEEL_1018.h_of_b(-b), -h)
    np.testing.assert_allclose(STEEL_1018.b_of_h(h), b, atol=1e-9)


@pytest.mark.parametrize("mat", [STEEL_1018, MATERIALS["mrf_132dg"]])
def test_mean_h_over_a_linear_build_up_is_the_integral_of_h(mat):
    """h_mean_dh: H̄(B) = (1/B)·∫0^B H against a 10⁵-point midpoint rule on h_of_b (the
    same curve) to 1e-8, on the table, the knee and the μ0 extension; dH̄/dB against a
    central difference; H̄ ≤ H (H increasing); at B → 0 half the table's first slope."""
    b = np.array([1e-6, 0.05, 0.3, 0.9, 1.4, 1.9, 2.2, 2.6, 4.0])
    h, d = mat.h_mean_dh(b.copy())
    u = (np.arange(100_000) + 0.5) / 100_000
    ref = np.array([mat.h_of_b(u * x).mean() for x in b])
    np.testing.assert_allclose(h, ref, rtol=1e-8)
    eps = 1e-7
    fd = (mat.h_mean_dh(b + eps)[0] - mat.h_mean_dh(b - eps)[0]) / (2 * eps)
    np.testing.assert_allclose(d, fd, rtol=1e-5)
    assert np.all(h <= mat.h_of_b(b))
    assert mat.h_mean_dh(np.zeros(1))[0][0] == 0.0
    assert d[0] == pytest.approx(0.5 * mat.h_dh(np.array([1e-6]))[1][0], rel=1e-9)


def test_carlson_yield_stress_against_datasheet():
    """[carlson] closed form vs [lord-mrf132dg]: +17 % at 18 kA/m, within 5 % at 46/80 kA/m."""
    h, tau = np.array(MRF_132DG_DATASHEET_TAU).T
    ratio = MRF_132DG.tau_y(h) / tau
    assert 1.10 < ratio[0] < 1.20
    assert np.all(np.abs(ratio[1:] - 1) < 0.05)
    assert MRF_132DG.tau_y(0.0) == 0.0
    assert MRF_132DG.tau_y(1e7) == pytest.approx(MRF_132DG.tau_y_max)


def test_numpy_pchip_is_scipys_pchip() -> None:
    """The materials' own PCHIP (no scipy at import) equals scipy's on random data,
    monotone or not, values and derivatives."""
    from scipy.interpolate import PchipInterpolator

    from magnetics.materials import pchip

    rng = np.random.default_rng(7)
    for _ in range(100):
        x = np.unique(rng.uniform(0.0, 10.0, rng.integers(3, 12)))
        y = rng.normal(size=x.size)
        q = np.linspace(x[0], x[-1], 301)
        ref = PchipInterpolator(x, y)
        v, d = pchip(x, y, q)
        np.testing.assert_allclose(v, ref(q), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(d, ref.derivative()(q), rtol=1e-10, atol=1e-10)


def test_importing_the_materials_does_not_import_scipy() -> None:
    import subprocess
    import sys

    code = "import sys, magnetics.materials; assert 'scipy' not in sys.modules, 'scipy'"
    subprocess.run([sys.executable, "-c", code], check=True)


def _leggauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """numpy's ``legendre.leggauss(n)`` (its steps: the companion matrix's eigenvalues, one
    Newton step, the weights from the derivative, symmetrised, summing to 2) with the
    eigenvalues from the symmetric tridiagonal solver: O(n²) instead of a dense n × n
    eigvalsh (4.4 s of CPU at n = 2000, against 0.14 s); nodes equal to 1e-16, weights to
    5e-10 relative (the closed form's error against it: 1.4944199e-9 either way)."""
    from numpy.polynomial import legendre as leg
    from scipy.linalg import eigvalsh_tridiagonal

    k = np.arange(1.0, n)
    x = eigvalsh_tridiagonal(np.zeros(n), k / np.sqrt((2 * k - 1) * (2 * k + 1)))
    c = np.zeros(n + 1)
    c[-1] = 1.0
    df = leg.legval(x, leg.legder(c))
    x -= leg.legval(x, c) / df
    fm = leg.legval(x, c[1:])
    w = 1.0 / (fm / np.abs(fm).max() * (df / np.abs(df).max()))
    w, x = (w + w[::-1]) / 2, (x - x[::-1]) / 2
    return x, w * (2.0 / w.sum())


def test_yield_stress_along_a_hyperbolic_decay_in_closed_form() -> None:
    """MRFluid.tau_y_decay, ∫0^W τy(H·e^−v)·e^v dv, against 2000 Gauss–Legendre points of
    τy itself from the weak field to deep saturation (to 1e-8: the table's Hermite
    interpolation, rounding at the smallest W), and its two limits: a·W·τ_max where τy is
    linear in H, (e^W − 1)·τ_max where τy is τ_max along the whole decay."""
    fluid = MRF_132DG
    u, wt = _leggauss(2000)
    h = np.array([1e-3, 1e2, 3e4, 1.6e5, 4e5, 2e6, 3e7, 1e9])[:, None]
    w = np.array([1e-3, 0.3, 1.0, 3.0, 8.0])[None, :]
    v = 0.5 * w[..., None] * (u + 1)
    ref = 0.5 * w * (fluid.tau_y(h[..., None] * np.exp(-v)) * np.exp(v) * wt).sum(-1)
    np.testing.assert_allclose(fluid.tau_y_decay(h, w), ref, rtol=1e-8)
    np.testing.assert_allclose(fluid.tau_y_decay(1e-3, w), 6.33e-9 * w * fluid.tau_y_max,
                               rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose(fluid.tau_y_decay(1e300, w), np.expm1(w) * fluid.tau_y_max,
                               rtol=1e-12)  # fmt: skip
    assert np.all(fluid.tau_y_decay(h, 0.0) == 0.0)
    assert np.all(fluid.tau_y_decay(0.0, w) == 0.0)
    assert np.all(np.isfinite(fluid.tau_y_decay(np.inf, w)))


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 1e9), st.floats(0.0, 1e9), st.floats(0.0, 10.0), st.floats(0.0, 10.0))
def test_yield_stress_along_a_decay_grows_with_the_field_and_the_depth(h0, h1, w0, w1) -> None:
    """More field or a longer decay never lowers the summed yield stress (τy ≥ 0 and
    non-decreasing in |H|), and it stays within its bounds: ≤ (e^W − 1)·τ_max; each to the
    closed form's rounding: 1e-9 relative, and τ_max·1e-11 absolute (the table's Hermite
    error, which e^W·S(ln a − W) − S(ln a) keeps where W is tiny)."""
    (ha, hb), (wa, wb) = sorted((h0, h1)), sorted((w0, w1))
    f, top = MRF_132DG.tau_y_decay, MRF_132DG.tau_y_max
    assert f(ha, wa) <= f(hb, wa) * (1 + 1e-9) + 1e-11 * top
    assert f(ha, wa) <= f(ha, wb) * (1 + 1e-9) + 1e-11 * top
    assert -1e-11 * top <= f(hb, wb) <= np.expm1(wb) * top * (1 + 1e-9) + 1e-11 * top


def test_carrier_viscosity_is_the_walther_line_through_its_points() -> None:
    """ASTM D341 [astm-d341]: W = log10 log10(ν + 0.7) (ν in mm²/s) is linear in log10 T
    (K). Through MRF-132DG's carrier points (40 °C, 19 mm²/s) and (100 °C, 4.1 mm²/s):
    W(19) = log10 log10 19.7 = 0.11210, W(4.1) = log10 log10 4.8 = −0.16670; slope
    −0.27880/log10(373.15/313.15) = −3.6617; at 70 °C W = 0.11210 − 3.6617·log10(343.15/
    313.15) = −0.033377, so ν = 10^(10^W) − 0.7 = 7.735 mm²/s. The plastic viscosity scales
    with it: η(100 °C)/η(40 °C) = 4.1/19."""
    from magnetics.materials import FLUIDS, MRF

    f = FLUIDS[MRF]
    assert f.carrier_viscosity(40.0) == pytest.approx(19.0e-6, rel=1e-9)
    assert f.carrier_viscosity(100.0) == pytest.approx(4.1e-6, rel=1e-9)
    assert f.carrier_viscosity(70.0) == pytest.approx(7.735e-6, rel=1e-3)
    ratio = f.viscosity_at(100.0) / f.viscosity_at(40.0)
    assert ratio == pytest.approx(4.1 / 19.0, rel=1e-9)


@pytest.mark.parametrize("mat", [STEEL_1018, MATERIALS["mrf_132dg"], MATERIALS["air"]])
@pytest.mark.parametrize(
    "shape", [(12, 5000, 2), (12, 700, 16), (12, 3000, 1), (9, 1, 1), (1, 9000, 1)]
)
def test_h_dh_sum_is_the_weighted_sum_of_h_dh_bit_for_bit(mat, shape):
    """h_dh_sum (the circuit's element sums) equals h_dh at B = k·Φ weighted by w, wk and
    summed over the first axis, to the last bit: the blocks of j's of a large (S, C) (the
    first two shapes: two blocks of 6, blocks of 5, 5 and 2), the plain expression of a
    small one (numpy adds J ≥ 8 terms pairwise at S·C = 1) and of a single j. B spans zero,
    the table and the μ0 extension."""
    j, s, c = shape
    rng = np.random.default_rng(sum(shape))
    k = rng.uniform(0.0, 2.0, (j, s, 1))
    k[:, ::7] = 0.0  # masked entries (k = w = 0)
    w = rng.uniform(0.0, 1e-2, (j, s, 1))
    phi = rng.choice([0.0, 0.3, 1.0, 2.5, 30.0], (s, c)) * rng.uniform(0.5, 1.0, (s, c))
    h, dh = mat.h_dh(k * phi)
    h *= w
    dh *= w * k
    got = mat.h_dh_sum(k, phi, w, w * k)
    for a, b in zip(got, (h.sum(0), dh.sum(0)), strict=True):
        assert a.shape == (s, c)
        np.testing.assert_array_equal(a.view(np.int64), b.view(np.int64))
