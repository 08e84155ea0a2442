"""One design, one answer in the batch stability kernels (issue 40): a design's largest
stable K from ``robust_search.stable_stiffness_batch`` and its worst over a box from
``robust_search.stable_worst_box`` are, bit for bit, what the kernel gives it alone,
whichever designs share its batch (and so its chunk of like grid sizes: 256 rows in
``_crossing_scan``, 32 in ``_scan``) and wherever it sits there; the exact kernel
``limits.max_stable_stiffness`` on many designs is its scalar call on each."""

import math
from dataclasses import replace

import numpy as np
import pytest
from test_robust import _random_boxes

from mrclutch import robust
from mrclutch.haptics import limits
from mrclutch.haptics.actuator import TABLE2_MR, HapticParams
from mrclutch.haptics.limits import max_stable_stiffness
from mrclutch.robust_search import stable_stiffness_batch, stable_worst_box


def _params(box, delay=None):
    """The nominal pair of each design of ``box`` (``delay``: instead of its own)."""
    tau = box.delay[0] if delay is None else delay
    return HapticParams(box.m1[0], box.b1[0], box.k, box.b, box.m2, delay=tau)


def _take(p, idx):
    return HapticParams(*(np.asarray(getattr(p, f))[idx] for f in ("m1", "b1", "k", "b", "m2")),
                        delay=np.asarray(p.delay)[idx])  # fmt: skip


def _join(*ps):
    return HapticParams(*(np.concatenate([np.asarray(getattr(p, f)) for p in ps])
                          for f in ("m1", "b1", "k", "b", "m2")),
                        delay=np.concatenate([np.asarray(p.delay) for p in ps]))  # fmt: skip


def test_stable_stiffness_batch_gives_each_design_its_own_answer():
    """12 designs alone, then in batches of ~600 beside designs whose linear grids are
    shorter (delays ÷ 3–30), longer (× 3–10) or mixed, each design at the start, inside
    and at the end of a 256-row chunk: the same floats (inf included)."""
    rng = np.random.default_rng(40)
    targets = _params(_random_boxes(rng, 12))
    alone = np.array([stable_stiffness_batch(_take(targets, [i]))[0] for i in range(12)])
    others = _random_boxes(rng, 600)
    tau = others.delay[0]
    for delay in (tau, tau / rng.uniform(3, 30, 600), tau * rng.uniform(3, 10, 600)):
        crowd = _params(others, delay)
        for at in (0, 250, 600):
            batch = _join(_take(crowd, slice(0, at)), targets, _take(crowd, slice(at, None)))
            got = stable_stiffness_batch(batch)[at : at + 12]
            assert np.array_equal(got, alone), (at, np.max(np.abs(got / alone - 1)))


def test_stable_worst_box_gives_each_box_its_own_answer():
    """8 boxes alone, then in batches of 70 beside boxes with shorter, longer and mixed
    grids, in different 32-row chunks: the same worst, bit for bit, and the same done."""
    rng = np.random.default_rng(41)
    t = _random_boxes(rng, 8)
    lo = np.stack([t.m1[1], t.b1[1], t.delay[1]], 1)
    hi = np.stack([t.m1[2], t.b1[2], t.delay[2]], 1)
    alone = [stable_worst_box(lo[i : i + 1], hi[i : i + 1], t.k[i], t.b[i], t.m2[i])
             for i in range(8)]  # fmt: skip
    a_worst = np.array([w[0] for w, _ in alone])
    a_done = np.array([d[0] for _, d in alone])
    o = _random_boxes(rng, 70)
    olo = np.stack([o.m1[1], o.b1[1], o.delay[1]], 1)
    ohi = np.stack([o.m1[2], o.b1[2], o.delay[2]], 1)
    for scale in (1.0, 1 / 10, 5.0):
        olo_s, ohi_s = olo.copy(), ohi.copy()
        olo_s[:, 2] *= scale
        ohi_s[:, 2] *= scale
        for at in (0, 30, 70):
            L = np.concatenate([olo_s[:at], lo, olo_s[at:]])
            H = np.concatenate([ohi_s[:at], hi, ohi_s[at:]])
            k, b, m2 = (np.concatenate([x[:at], y, x[at:]]) for x, y in
                        ((o.k, t.k), (o.b, t.b), (o.m2, t.m2)))  # fmt: skip
            worst, done = stable_worst_box(L, H, k, b, m2)
            assert np.array_equal(worst[at : at + 8], a_worst), (scale, at)
            assert np.array_equal(done[at : at + 8], a_done), (scale, at)


def test_max_stable_stiffness_of_many_designs_is_each_scalar_call():
    """The exact kernel on a vectorised set (the scans side by side, ``limits._stable_rows``)
    against its scalar call design by design, bit for bit: 40 random designs, and beside
    them rows the side-by-side scan leaves to the scalar path (a sample-and-hold, no
    delay, no transmission damping) and a row whose scan cannot resolve the loop (NaN)."""
    rng = np.random.default_rng(42)
    p = _params(_random_boxes(rng, 40))
    one = np.array([max_stable_stiffness(p.item(i)) for i in range(40)])
    assert np.array_equal(max_stable_stiffness(p), one)
    # a sample-and-hold, no delay, no transmission damping: left to the scalar path
    f = {x: np.r_[getattr(p, x)[:10], [3e-3, 0.4, 4000.0, 20.0, 14e-3][i] * np.ones(3)]
         for i, x in enumerate(("m1", "b1", "k", "b", "m2"))}  # fmt: skip
    f["b"][12] = 0.0
    both = HapticParams(**f, delay=np.r_[p.delay[:10], 1e-3, 0.0, 1e-3],
                        sample_period=np.r_[np.zeros(10), 1e-3, 0.0, 0.0])  # fmt: skip
    alone = np.array([max_stable_stiffness(both.item(i)) for i in range(13)])
    assert np.array_equal(max_stable_stiffness(both), alone)
    far = HapticParams(np.r_[p.m1[:3], 3e-3], np.r_[p.b1[:3], 0.4], np.r_[p.k[:3], 1e5],
                       np.r_[p.b[:3], 20.0], np.r_[p.m2[:3], 14e-3],
                       delay=np.r_[p.delay[:3], 30.0])  # fmt: skip
    got = max_stable_stiffness(far)
    assert np.isnan(got[3]) and np.array_equal(got[:3], one[:3])


@pytest.mark.parametrize("field", ["b1", "delay"])
def test_stable_threshold_grid_in_one_call_is_the_scalar_calls(monkeypatch, field):
    """The stability threshold's 13-point grid in one vectorised call (robust._VECTORISED)
    gives the value and sense of 13 scalar calls exactly, at a K between its limits."""
    p = replace(TABLE2_MR, delay=2e-3)
    K = 0.7 * float(max_stable_stiffness(p))
    fast = robust.threshold(p, K, "stable", field)
    monkeypatch.setattr(robust, "_VECTORISED", frozenset({"passive"}))
    slow = robust.threshold(p, K, "stable", field)
    assert fast is not None and slow is not None
    assert fast == slow  # value and sense, to the bit


def test_max_stable_stiffness_rows_that_scan_on_in_chunks(monkeypatch):
    """Designs over wide ranges (m1 1 mg–0.1 kg, k 0.1–1000 kN/m, τ 1 µs–30 ms, ...), of
    which some scan on past ω_a in linear chunks: side by side each is its scalar call,
    bit for bit, and so is a row whose chunk passes MAX_GRID (NaN, the others scanning on)."""
    rng = np.random.default_rng(5)

    def lg(a, b):
        return 10 ** rng.uniform(np.log10(a), np.log10(b), 120)

    p = HapticParams(lg(1e-6, 1e-1), lg(1e-3, 30), lg(1e2, 1e6), lg(1e-2, 1e3), lg(1e-4, 1e-1),
                     delay=lg(1e-6, 3e-2))  # fmt: skip
    one = np.array([max_stable_stiffness(p.item(i)) for i in range(120)])
    p = _take(p, ~np.isnan(one))  # MAX_REFINED (NaN) sends a whole set to the scalar path
    one = one[~np.isnan(one)]
    chunks = []
    chunk_grid = limits._chunk_grid
    monkeypatch.setattr(limits, "_chunk_grid", lambda *a: chunks.append(a) or chunk_grid(*a))
    assert np.array_equal(max_stable_stiffness(p), one)
    assert len(chunks) >= 5
    monkeypatch.setattr(limits, "MAX_GRID", 30)
    one = np.array([max_stable_stiffness(p.item(i)) for i in range(one.size)])
    assert 0 < np.isnan(one).sum() < one.size
    assert np.array_equal(max_stable_stiffness(p), one, equal_nan=True)


def _threshold_on_the_whole_grid(p, K, verdict, field):
    """``robust.threshold`` as it was before its search stopped at the nearest crossing:
    every point of the 13-point grid by a scalar call, every cell with a sign change
    root-found (robust.bracket_root, the same root-finder), the root nearest the value in p
    kept (the lowest cell of equal nearness)."""
    limit = robust._LIMITS[verdict]
    x0 = float(getattr(p, field))

    def g(u):
        return math.log(min(float(limit(replace(p, **{field: math.exp(u)}))), 1e12) / K)

    lo, hi = math.log(x0 * 1e-3), math.log(min(x0 * 1e3, 1.0) if field == "delay" else x0 * 1e3)
    us = np.linspace(lo, hi, 13)
    gs = [g(u) for u in us]
    u0, best = math.log(x0), None
    for a, b, ga, gb in zip(us[:-1], us[1:], gs[:-1], gs[1:], strict=True):
        if ga == 0 or ga * gb < 0:
            r = a if ga == 0 else robust.bracket_root(g, a, b, ga, gb)
            if best is None or abs(r - u0) < abs(best[0] - u0):
                best = (r, ga, gb)
    if best is None:
        return None
    r, ga, gb = best
    return {"value": math.exp(r), "sense": "≥" if gb > ga else "≤"}


@pytest.mark.parametrize("verdict", ["stable", "passive"])
@pytest.mark.parametrize("field", ["b1", "delay"])
def test_threshold_searched_outward_is_the_whole_grids(verdict, field):
    """The threshold searched outward from the value in p (grid points evaluated only up to
    the nearest crossing) gives the whole grid's answer exactly, value and sense, or None
    where it does: the paper's pair and a random one, K inside and beyond the limit and far
    outside (a crossing, none)."""
    rng = np.random.default_rng(43)
    pairs = [replace(TABLE2_MR, delay=1e-3), _take(_params(_random_boxes(rng, 1)), [0]).item(0)]
    seen = set()
    for p in pairs:
        lim = float(robust._LIMITS[verdict](p))
        for f in (1e-4, 0.5, 1.1, 1e4):
            K = f * lim
            got = robust.threshold(p, K, verdict, field)
            assert got == _threshold_on_the_whole_grid(p, K, verdict, field), (p, f)
            seen.add(got is None)
    assert seen == {True, False}  # a crossing found, and none


def test_the_box_nominal_zwidth_is_the_evaluations_own_where_the_pair_is_the_same():
    """robust_verdicts' nominal Z-width area is read from the evaluation (its MR pair's,
    computed beside the motor) where the box's nominal pair is that pair field for field:
    on the paper preset it is the area the box's nominal gives alone, to the bit; a pair
    that differs (b1 doubled, a sample-and-hold) gets its own area computed."""
    from mrclutch.design import design_preset
    from mrclutch.haptics.zwidth import zwidth
    from mrclutch.pipeline import evaluate

    def alone(q):
        return float(np.ravel(zwidth(q)["zwidth_area_N2_s_per_m2"])[0])

    ev = evaluate(design_preset("paper"))
    nom = robust.robust_box(ev).box.nominal
    own = ev.zwidth["mr"]["zwidth_area_N2_s_per_m2"]
    assert robust._nominal_zwidth_area(ev, nom) == alone(nom) == own
    for other in (replace(nom, b1=nom.b1 * 2), replace(nom, sample_period=1e-3)):
        assert robust._nominal_zwidth_area(ev, other) == alone(other) != own
