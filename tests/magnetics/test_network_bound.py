"""The network's error bound over every section dimension (issue 31): the stored data is
this measurement, it covers fresh designs it was not built from, and every term of its
formula is the one the module states."""

from __future__ import annotations

import json
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from geometry.params import preset
from magnetics.error_map import circuit_error, error_bound
from magnetics.network_bound import (
    AMPERE_TURNS,
    DATA_FILE,
    DEFAULT_MATERIALS,
    load,
    material_key,
    measured_sets,
    network_bound,
)

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"
PAPER = preset("paper")


def _bench(name: str):  # type: ignore[no-untyped-def]
    sys.path.insert(0, str(BENCH))
    try:
        return __import__(name)
    finally:
        sys.path.remove(str(BENCH))


@pytest.fixture(scope="module")
def measured() -> dict:  # type: ignore[type-arg]
    """The bound re-built from the stored FEM design of experiments (network re-solved)."""
    return _bench("measure_network_bound").measure()


def test_the_stored_bound_is_this_measurement(measured: dict) -> None:  # type: ignore[type-arg]
    """magnetics/data/network_bound.json is what measure_network_bound.py builds from the
    stored FEM today: a change to the network fails here until the bound is re-measured."""
    stored = json.loads(DATA_FILE.read_text())
    mine = stored["material_sets"][DEFAULT_MATERIALS]
    assert mine["ranges"] == measured["ranges"]
    np.testing.assert_allclose(mine["estimate"]["b"], measured["estimate"]["b"], atol=1e-7)
    np.testing.assert_allclose(mine["estimate"]["a"], measured["estimate"]["a"], atol=1e-7)
    np.testing.assert_allclose(mine["scale"]["g"], measured["scale"]["g"], atol=1e-7)
    assert mine["scale"]["d"] == pytest.approx(measured["scale"]["d"], abs=1e-7)
    assert mine["log_scaled"] == measured["log_scaled"]
    assert mine["q"] == pytest.approx(measured["q"], rel=1e-5)
    assert mine["check"] == measured["check"]


def test_fresh_designs_lie_inside_the_bound_and_it_is_tight(measured: dict) -> None:  # type: ignore[type-arg]
    """On the 200 fresh random designs (a seed never used to build it), every section
    dimension varied, all inside the ranges: |error| inside the bound on ≥ 95 % of designs
    × currents (measured 96.2 %). Its median is 2.02 × the median |error| (3.77 % against
    1.86 %; the constant-q bound of the previous round: 2.13 ×): issue 31 asks ≤ 2, not
    met, asserted here at 2.05 so that a regression shows. The scale σ̂ varies over the
    check designs (it is adaptive, not a constant in disguise)."""
    c = measured["check"]
    assert c["designs"] == 200 and c["points"] == 600
    assert c["coverage"] >= 0.95
    assert c["median_bound"] <= 2.05 * c["median_abs_error"]
    lo, hi = c["min_scale"], c["max_scale"]
    assert 0.0 < lo < c["median_scale"] < hi and hi > 2.0 * lo
    assert c["median_bound"] < 0.05 and c["max_abs_error"] < 0.10
    assert c["seed"] != measured["build"]["seed"]


def test_the_runtime_bound_is_the_stated_formula() -> None:
    """ê = c + b·x + xᵀAx, σ̂ = exp(d + g·x) and bound = |ê| + q·σ̂, x the inputs scaled to
    [0, 1] (lengths and N·I on log axes, the drum count linear), written out term by term
    here (each term: a planted change fails)."""
    m = load()
    assert "n_drums" not in m.log_scaled and "gap" in m.log_scaled
    assert AMPERE_TURNS in m.log_scaled
    rng = np.random.default_rng(7)
    names = [k for k in m.ranges if k != AMPERE_TURNS]
    base = {k: float(v) for k, v in vars(PAPER).items()}
    for _ in range(5):
        x = rng.uniform(size=len(m.ranges))
        x[0] = 0.4  # n_drums = 3: a node
        p = dict(base)
        for k, t in zip(names, x, strict=False):
            lo, hi = m.ranges[k]
            p[k] = lo + t * (hi - lo) if k == "n_drums" else lo * (hi / lo) ** t
        lo, hi = m.ranges[AMPERE_TURNS]
        current = lo * (hi / lo) ** x[-1] / p["coil_turns"]
        est = m.c + sum(bi * xi for bi, xi in zip(m.b, x, strict=True))
        est += sum(m.a[i][j] * x[i] * x[j] for i in range(len(x)) for j in range(len(x)))
        sig = math.exp(m.d + sum(gi * xi for gi, xi in zip(m.g, x, strict=True)))
        e, b, why = network_bound(p, current)
        assert why == ()
        assert e == pytest.approx(est, rel=1e-9, abs=1e-12)
        assert b == pytest.approx(abs(est) + m.q * sig, rel=1e-9)
    assert 0.0 < m.q < 10.0 and m.coverage == 0.95
    assert 0.0 < math.exp(m.d) < 0.1 and len(m.g) == len(m.ranges)


def test_the_normalised_cross_conformal_bound_covers_and_adapts() -> None:
    """The script's procedure on synthetic data whose noise grows 20-fold along x₀ (a known
    law, fresh draws to judge it): the normalised bound covers ≈ 95 % of fresh points, as
    the constant one does, with a smaller median (it is tight where the noise is small),
    and its scale found the law's direction."""
    mnb = _bench("measure_network_bound")
    rng = np.random.default_rng(3)

    def draw(n: int) -> tuple[np.ndarray, np.ndarray]:
        x = rng.uniform(size=(n, 2))
        return x, 0.05 * x[:, 1] + 0.004 * np.exp(3.0 * x[:, 0]) * rng.standard_normal(n)

    x, e = draw(1500)
    design = np.arange(e.size)
    xf, ef = draw(20000)
    median = {}
    for scaled_ in (False, True):
        q, _, _ = mnb.cross_conformal(x, e, design, scaled_)
        c, b, a, d, g = mnb.fit(x, e, design, scaled_)
        bound = np.abs(mnb.estimate(c, b, a, xf)) + q * np.exp(d + xf @ g)
        assert 0.93 <= np.mean(np.abs(ef) <= bound) <= 0.97
        median[scaled_] = np.median(bound)
        if scaled_:  # slope 3 along x₀ (δ and the ridge pull it lower), 0 along x₁
            assert 1.5 < g[0] < 3.5 and abs(g[1]) < 0.5
    assert median[True] < 0.85 * median[False]


def test_outside_the_ranges_or_the_materials_the_error_is_unknown() -> None:
    """A shell past its range, N·I past its range, or materials never measured: NaN, inf and
    a note that names why; the hub holes (invisible to the FEM) change nothing."""
    i = 7.0
    e = circuit_error(PAPER, "network", i)
    assert math.isfinite(e.bound) and e.bound > abs(e.estimate) and not e.notes
    hi = load().ranges["shell_thickness"][1]
    off = circuit_error(replace(PAPER, shell_thickness=1.01 * hi), "network", i)
    assert math.isnan(off.estimate) and off.bound == math.inf
    assert "shell_thickness" in off.notes[0] and "off the measured error map" in off.notes[0]
    ni_hi = load().ranges[AMPERE_TURNS][1]
    strong = circuit_error(PAPER, "network", 1.01 * ni_hi / PAPER.coil_turns)
    assert strong.bound == math.inf and "N·I" in strong.notes[0]
    holes = circuit_error(preset("paper-holes"), "network", i)
    assert holes.bound == e.bound
    other = material_key("steel_1010", "mrf_140cg")
    assert other not in measured_sets() and DEFAULT_MATERIALS in measured_sets()
    un = circuit_error(PAPER, "network", i, other)
    assert un.bound == math.inf and "unmeasured" in un.notes[0]


def test_a_value_near_the_float_limit_is_off_the_map_without_an_overflow() -> None:
    """Found by hypothesis (test_batch_fuzz): a drum 1.8e304 m thick made v/lo overflow
    (a RuntimeWarning, an error here) before the range check could say off the map."""
    m = load()
    p = {k: np.array([lo]) for k, (lo, _) in m.ranges.items() if k != AMPERE_TURNS}
    p["drum_thickness"] = np.array([1.797693134862316e304])
    _x, inside, why = m.scaled(p, np.array([m.ranges[AMPERE_TURNS][0]]))
    assert not inside[0] and why == ("drum_thickness",)


def test_the_batch_bound_is_the_single_one_and_needs_a_current() -> None:
    gaps = np.array([0.3e-3, 0.7e-3, 1.2e-3])  # the last outside the gap's range
    p = {k: np.full(3, float(v)) for k, v in vars(PAPER).items()}
    p["gap"] = gaps
    est, bound, why = error_bound(p, "network", np.array([7.0, 5.0, 7.0]))
    assert why == ("gap",) and bound[2] == math.inf and np.isnan(est[2])
    for k, i in ((0, 7.0), (1, 5.0)):
        one = circuit_error(replace(PAPER, gap=float(gaps[k])), "network", i)
        assert bound[k] == pytest.approx(one.bound, rel=1e-12)
    with pytest.raises(ValueError, match="current"):
        error_bound(p, "network")


@pytest.mark.slow
def test_a_small_sample_of_the_stored_fem_is_re_measured() -> None:
    """Two of the stored check designs solved again by the FEM: the stored torques are
    what the FEM gives today (the bound rests on them)."""
    doe = _bench("measure_fem_doe")
    data = json.loads(doe.OUT.read_text())
    rows = sorted(data["check"], key=lambda r: r["design"]["n_drums"])[:2]
    for r in rows:
        again = doe.fem(r["design"])
        for conv in ("mid-line", "weakest-layer"):  # both conventions of the stored solve
            np.testing.assert_allclose(again[conv], r["torque"][conv], rtol=1e-6)
