"""One design, one answer in the batch stability kernels (issue 40): a design's largest
stable K from ``robust_search.stable_stiffness_batch`` and its worst over a box from
``robust_search.stable_worst_box`` are, bit for bit, what the kernel gives it alone,
whichever designs share its batch (and so its chunk of like grid sizes: 256 rows in
``_crossing_scan``, 32 in ``_scan``) and wherever it sits there."""

import numpy as np
from test_robust import _random_boxes

from mrclutch.haptics.actuator import HapticParams
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
