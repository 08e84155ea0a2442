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

from geometry.params import broadcast_fields, preset, valid
from magnetics.error_map import circuit_error, error_bound
from magnetics.network_bound import (
    AMPERE_TURNS,
    DATA_FILE,
    DEFAULT_MATERIALS,
    FEATURE_FLOOR,
    FEATURES,
    load,
    material_key,
    measured_sets,
    network_bound,
    network_features,
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
    assert list(mine["features"]) == list(FEATURES) == list(measured["features"])
    np.testing.assert_allclose(list(mine["features"].values()),
                               list(measured["features"].values()), atol=1e-7)  # fmt: skip
    assert mine["q"] == pytest.approx(measured["q"], rel=1e-5)
    assert mine["check"] == measured["check"]


def test_fresh_designs_lie_inside_the_bound_and_it_is_tight(measured: dict) -> None:  # type: ignore[type-arg]
    """On the 200 fresh random designs (a seed never used to build it), every section
    dimension varied, all inside the ranges: |error| inside the bound on ≥ 95 % of designs
    × currents (measured 96.3 %). Its median is 1.79 × the median |error| (3.33 % against
    1.86 %; on the dimensions alone: 2.02 ×, the constant-q bound before it 2.13 ×): issue
    31 asks ≤ 2, met, asserted at 1.80 so that a regression shows. The scale σ̂ varies over
    the check designs (it is adaptive, not a constant in disguise)."""
    c = measured["check"]
    assert c["designs"] == 200 and c["points"] == 600
    assert c["coverage"] >= 0.95
    assert c["median_bound"] <= 1.80 * c["median_abs_error"]
    lo, hi = c["min_scale"], c["max_scale"]
    assert 0.0 < lo < c["median_scale"] < hi and hi > 2.0 * lo
    assert c["median_bound"] < 0.05 and c["max_abs_error"] < 0.10
    assert c["seed"] != measured["build"]["seed"]


def _features_by_hand(p: dict, current: float) -> dict:  # type: ignore[type-arg]
    """The network's solution features written out from its loop fluxes (the ordering of
    Network.unknowns: films 0..m−1, window, outer air, 2 end leaks, sheaths)."""
    from geometry.params import broadcast_fields
    from geometry.regions import evaluate
    from magnetics.network import network_from_regions, solve_network

    q = broadcast_fields(p)
    net = network_from_regions(evaluate(q, int(p["n_drums"])))
    x = solve_network(net, [[p["coil_turns"] * current]])[0, 0]
    m = net.m
    coil = abs(x[m - 1] + x[m])
    film = [abs(x[k] - x[m + 2]) / (math.pi * (net.gap_r0[0, k] + net.gap_r1[0, k])
                                    * net.gap_eff[0, k, 0]) for k in range(m)]  # fmt: skip
    return {
        "window_share": abs(x[m]) / coil,
        "air_share": abs(x[m + 1]) / coil,
        "leak_share": (abs(x[m + 2]) + abs(x[m + 3])) / coil,
        "sheath_share": sum(abs(v) for v in x[m + 4 :]) / coil,
        "inner_outer": abs(x[0]) / abs(x[m - 1]),
        "b_back": coil * net.back_k[0, 0],
        "b_pole": coil * max(net.shell_k[0]),
        "b_core": abs(x[0]) * net.rung_k[0, 0, 0, 0],
        "b_drum": max(abs(x[j] - x[j - 1]) * net.rung_k[0, j, 0, 0] for j in range(1, m)),
        "b_film_max": max(film),
        "b_film_min": min(film),
    }


def test_the_solution_features_are_the_stated_ones() -> None:
    """Each feature of the network's solution written out by hand from the loop fluxes, on
    a 3-drum design at 5 A (a planted change to any term fails); the coil's flux the
    features share out is λ/N (magnetics.network.flux_linkage, another function)."""
    from geometry.params import broadcast_fields
    from geometry.regions import evaluate
    from magnetics.network import flux_linkage, network_from_regions

    p = {**{k: float(v) for k, v in vars(PAPER).items()}, "n_drums": 3.0}
    got = network_features({k: np.array([v]) for k, v in p.items()}, np.array([5.0 * 140]))
    p["coil_turns"] = 140.0
    want = _features_by_hand(p, 5.0)
    assert set(got) == set(FEATURES) == set(want)
    for k in FEATURES:
        assert got[k][0] == pytest.approx(want[k], rel=1e-9), k
    net = network_from_regions(evaluate(broadcast_fields(p), 3))
    lam, _ = flux_linkage(net, [[700.0]])
    assert want["b_back"] == pytest.approx(lam[0, 0] / 140.0 * net.back_k[0, 0], rel=1e-9)
    assert 0 < want["b_film_min"] < want["b_film_max"] < 2.0 and 0 < want["inner_outer"] < 1


def test_the_runtime_bound_is_the_stated_formula() -> None:
    """ê = c + b·x + xᵀAx, σ̂ = exp(d + g·x) and bound = |ê| + q·σ̂, x the inputs scaled to
    [0, 1] (lengths and N·I on log axes, the drum count linear), then the network's
    solution features, ln(v + FEATURE_FLOOR) over their stored spans clipped to [0, 1],
    written out term by term here (each term: a planted change fails)."""
    m = load()
    assert tuple(m.features) == FEATURES
    assert "n_drums" not in m.log_scaled and "gap" in m.log_scaled
    assert AMPERE_TURNS in m.log_scaled
    rng = np.random.default_rng(7)
    names = [k for k in m.ranges if k != AMPERE_TURNS]
    base = {k: float(v) for k, v in vars(PAPER).items()}
    done = 0
    while done < 5:
        x = rng.uniform(size=len(m.ranges))
        x[0] = 0.4  # n_drums = 3: a node
        p = dict(base)
        for k, t in zip(names, x, strict=False):
            lo, hi = m.ranges[k]
            p[k] = lo + t * (hi - lo) if k == "n_drums" else lo * (hi / lo) ** t
        if not valid(broadcast_fields(p))[0]:  # no network for it: the bound says so
            assert network_bound(p, 1.0)[2] == ("not a valid design",)
            continue
        done += 1
        lo, hi = m.ranges[AMPERE_TURNS]
        current = lo * (hi / lo) ** x[-1] / p["coil_turns"]
        feats = _features_by_hand(p, current)
        for k, (flo, fhi) in m.features.items():
            t = (math.log(feats[k] + FEATURE_FLOOR) - flo) / (fhi - flo)
            x = np.append(x, min(max(t, 0.0), 1.0))
        est = m.c + sum(bi * xi for bi, xi in zip(m.b, x, strict=True))
        est += sum(m.a[i][j] * x[i] * x[j] for i in range(len(x)) for j in range(len(x)))
        sig = math.exp(m.d + sum(gi * xi for gi, xi in zip(m.g, x, strict=True)))
        e, b, why = network_bound(p, current)
        assert why == ()
        assert e == pytest.approx(est, rel=1e-9, abs=1e-12)
        assert b == pytest.approx(abs(est) + m.q * sig, rel=1e-9)
    assert 0.0 < m.q < 10.0 and m.coverage == 0.95
    assert 0.0 < math.exp(m.d) < 0.1 and len(m.g) == len(m.ranges) + len(FEATURES)


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


def test_solution_features_handed_over_are_clipped_to_their_span() -> None:
    """The features a caller hands over are the ones the bound solves for itself (the sweep's
    path), and a feature past its build span reads as the span's end (clipped, not
    extrapolated); a NaN feature (no solution) gives NaN and inf."""
    p = {k: float(v) for k, v in vars(PAPER).items()}
    ni = np.array([5.0 * p["coil_turns"]])
    got = network_features({k: np.array([v]) for k, v in p.items()}, ni)
    own = network_bound(p, 5.0)
    assert network_bound(p, 5.0, features=got)[:2] == pytest.approx(own[:2], rel=1e-12)
    m = load()
    for k, (lo, hi) in m.features.items():
        for end, past in ((hi, 1e3), (lo, -1e3)):
            at = dict(got, **{k: np.array([math.exp(end) - FEATURE_FLOOR])})
            beyond = dict(got, **{k: np.array([math.exp(end + past / 1e3) - FEATURE_FLOOR])})
            assert network_bound(p, 5.0, features=beyond)[1] == pytest.approx(
                network_bound(p, 5.0, features=at)[1], rel=1e-9
            ), k
    e, b, why = network_bound(p, 5.0, features=dict(got, b_core=np.array([math.nan])))
    assert math.isnan(e) and b == math.inf and why == ("not a valid design",)
