"""The limits over a hand box (``robust_limits``: nominal, worst and best of the largest
stable and passive K and of the bandwidth) and the robust sweep columns built on them
(``robust_columns_batch``, ``RobustBatchEvaluator``: ``sweep --with
max_stable_K_worst_N_per_m``)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mrclutch.design import ClutchDesign
from mrclutch.fast_batch import BatchEvaluator
from mrclutch.hand_box import HandBox, hand_box_batch
from mrclutch.haptics.model import (
    bandwidth,
    max_passive_stiffness,
)
from mrclutch.hot_range import resolved_ranges
from mrclutch.robust_search import box_search, stable_stiffness_batch, stable_worst_box
from mrclutch.uncertainty import Uncertainty

# ---- the verdicts over the box ----------------------------------------------------------

#: The keys :func:`robust_columns_batch` returns (``outputs.SWEEP_OPTIONAL`` names them).
ROBUST_COLUMNS: tuple[str, ...] = (
    "max_stable_K_worst_N_per_m",
    "max_passive_K_worst_N_per_m",
    "bandwidth_worst_hz",
)


def robust_limits(
    box: HandBox,
    *,
    points: int = 3,
    zooms: int = 3,
    cases: tuple[str, ...] = ("nominal", "worst", "best"),
) -> dict[str, np.ndarray]:
    """Nominal, worst and best of the largest stable K, the largest passive K [N/m] and the
    bandwidth at the rendered K_max [Hz] over ``box`` (module docstring: corners where the
    verdict is monotone, a bounded search elsewhere). Keys ``<quantity>_<case>`` with
    quantity in (max_stable_K, max_passive_K, bandwidth) and case in ``cases`` (of nominal,
    worst, best); NaN for invalid designs."""
    ok = box.valid
    n = ok.size
    out = {f"{q}_{c}": np.full(n, np.nan) for q in ("max_stable_K", "max_passive_K",
                                                     "bandwidth") for c in cases}  # fmt: skip
    if not ok.any():
        return out
    sub = _rows(box, ok)
    (_, mlo, mhi), (_, blo, bhi), (_, tlo, thi), (k0, klo, khi) = sub.m1, sub.b1, sub.delay, sub.K
    res: dict[str, np.ndarray] = {}
    nom = sub.nominal
    if "nominal" in cases:
        res["max_stable_K_nominal"] = stable_stiffness_batch(nom)
        res["max_passive_K_nominal"] = max_passive_stiffness(nom)
        res["bandwidth_nominal"] = bandwidth(nom, k0)
    # passive K: corners (non-increasing in m1, increasing in b1, decreasing in τ)
    if "worst" in cases:
        res["max_passive_K_worst"] = max_passive_stiffness(sub.params(mhi, blo, thi))
    if "best" in cases:
        res["max_passive_K_best"] = max_passive_stiffness(sub.params(mlo, bhi, tlo))
    # stable K: monotone in none of m1, b1, τ (a transmission resonance makes more b1
    # destabilise: tests). The worst: from the crossings over the box (stable_worst_box),
    # a bounded search where its scan cannot close; the best: a search over all three
    lo3, hi3 = np.stack([mlo, blo, tlo], 1), np.stack([mhi, bhi, thi], 1)

    def stable(s: HandBox) -> Callable[[np.ndarray], np.ndarray]:
        return lambda x: stable_stiffness_batch(s.params(x[..., 0], x[..., 1], x[..., 2]))

    if "worst" in cases:
        worst, done = stable_worst_box(lo3, hi3, sub.k, sub.b, sub.m2)
        if not done.all():
            rest = ~done
            worst[rest], _ = box_search(stable(_rows(sub, rest)), lo3[rest], hi3[rest],
                                        sense=-1, points=points, zooms=zooms + 2)  # fmt: skip
        res["max_stable_K_worst"] = worst
    if "best" in cases:
        res["max_stable_K_best"], _ = box_search(stable(sub), lo3, hi3, sense=1,
                                                 points=points, zooms=zooms)  # fmt: skip
    # bandwidth at the rendered K: not monotone in any input (tests). The worst: exact over
    # τ and K (bandwidth_worst_delay_K), searched over the edges of (m1, b1); the best: a
    # search over all four
    if "worst" in cases:
        res["bandwidth_worst"], _ = box_search(
            lambda x: _on_edges(sub, x, lo3[:, :2], hi3[:, :2], (tlo, thi), (klo, khi)),
            lo3[:, :2], hi3[:, :2], sense=-1, points=points, zooms=zooms + 1)  # fmt: skip
    if "best" in cases:
        res["bandwidth_best"], _ = box_search(
            lambda x: bandwidth(sub.params(x[..., 0], x[..., 1], x[..., 2]), x[..., 3]),
            np.stack([mlo, blo, tlo, klo], 1), np.stack([mhi, bhi, thi, khi], 1),
            sense=1, points=points, zooms=zooms + 1)  # fmt: skip
    for key, v in res.items():
        out[key][ok] = v
    return out


CASES = ("nominal", "worst", "best")


def _on_edges(box: HandBox, x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
              tau: tuple[np.ndarray, np.ndarray], K: tuple[np.ndarray, np.ndarray]
              ) -> np.ndarray:  # fmt: skip
    """``bandwidth_worst_delay_K`` at the points x (S, M, 2) of (m1, b1) on an edge of
    their box [lo, hi] (to 1e-9 of its width); NaN (no value) inside it. At one ω, τ, K
    k_eff = −m2ω² + k + Re(α/D), α = K E e^{−jωτ} − E², is harmonic in D = k − m1ω² +
    j(b1 + b)ω (Im D > 0: D ≠ 0) over the rectangle (m1, b1) spans, so its least there lies
    on the edges ([evans2010] §2.2.3, the maximum principle), and so does the first ω where it
    is ≤ 0: the least bandwidth over the box is its least over the edges."""
    span = (hi - lo)[:, None, :]
    edge = np.any((x - lo[:, None, :] <= 1e-9 * span) | (hi[:, None, :] - x <= 1e-9 * span), 2)
    rr, mm = np.nonzero(edge)
    on = _rows(box, rr)
    out = np.full(x.shape[:2], np.nan)
    out[rr, mm] = bandwidth_worst_delay_K(
        on,
        x[rr, mm, 0][:, None],
        x[rr, mm, 1][:, None],
        (tau[0][rr], tau[1][rr]),
        (K[0][rr], K[1][rr]),
    )[:, 0]
    return out


def bandwidth_worst_delay_K(box: HandBox, m1: np.ndarray, b1: np.ndarray,
                            tau: tuple[np.ndarray, np.ndarray], K: tuple[np.ndarray, np.ndarray]
                            ) -> np.ndarray:  # fmt: skip
    """The least bandwidth [Hz] over τ ∈ [τ⁻, τ⁺] and K ∈ [K⁻, K⁺] at each (m1, b1) (arrays
    (S, M); ``tau``, ``K``: the (S,) ends), exactly: the bandwidth is the first ω where
    k_eff ≤ 0 (``haptics.bandwidth``), so the least over a set is the first ω where the
    least k_eff over it is ≤ 0. k_eff = −m2ω² + k − Re(E²/D) + K Re(E e^{−jωτ}/D), E =
    k + jbω, D = k − m1ω² + j(b1 + b)ω (``_k_eff`` regrouped): linear in K, so its least is
    at K⁻ or K⁺; over τ, −K|E/D| where some τ ∈ [τ⁻, τ⁺] turns E e^{−jωτ}/D negative real,
    else at τ⁻ or τ⁺. So the least bandwidth is that of the four corners (τ, K) or the
    first ω where env(ω) = −m2ω² + k − Re(E²/D) − K⁺|E/D| = 0 with such a τ: env's zeros
    are those of P1 − K⁺|E||D| (P1 = (k − m2ω²)|D|² − Re(E² D̄)), the roots in u = ω² of
    P1² − K⁺²|E|²|D|² (degree 6) with P1 ≥ 0. A first crossing where τ reaches an end is
    that corner's."""
    sh = np.shape(m1)
    col = (-1,) + (1,) * (len(sh) - 1)
    k, b, m2 = (np.broadcast_to(x.reshape(col), sh) for x in (box.k, box.b, box.m2))
    (ta, tb), (ka, kb) = ((np.broadcast_to(x.reshape(col), sh) for x in t) for t in (tau, K))
    # the four corners (τ, K) side by side in one bandwidth call (each point's bandwidth is
    # its own, bit for bit, whatever points share the call), taken in the same order
    corners = [(t, kk) for t in (ta, tb) for kk in (ka, kb)]
    side = [
        np.concatenate([np.broadcast_to(x, sh) for x in xs], axis=-1)
        for xs in ((m1,) * 4, (b1,) * 4, [t for t, _ in corners], [kk for _, kk in corners])
    ]
    bw = np.split(bandwidth(box.params(*side[:3]), side[3]), 4, axis=-1)
    out = np.full(sh, np.inf)
    for one in bw:
        out = np.fmin(out, one)
    # env's roots: polynomials in x = u/s (s = k/(m1 + m2), the rigid lever's ω²), ascending
    s = k / (m1 + m2)
    bb = b1 + b
    dm = [k * k, (bb * bb - 2 * k * m1) * s, m1 * m1 * s * s]  # |D|²
    re = [k**3, (2 * k * b * bb - k * k * m1 - k * b * b) * s, b * b * m1 * s * s]  # Re(E² D̄)
    p1 = [k * dm[0] - re[0], k * dm[1] - m2 * s * dm[0] - re[1],
          k * dm[2] - m2 * s * dm[1] - re[2], -m2 * s * dm[2]]  # fmt: skip
    e2 = [k * k, b * b * s]  # |E|²
    c = [sum(p1[i] * p1[j - i] for i in range(max(0, j - 3), min(j, 3) + 1)) for j in range(7)]
    for i in range(2):
        for j in range(3):
            c[i + j] = c[i + j] - kb * kb * e2[i] * dm[j]
    comp = np.zeros((*sh, 6, 6))
    comp[..., 0, :] = -np.stack(c[5::-1], -1) / c[6][..., None]
    comp[..., np.arange(1, 6), np.arange(5)] = 1.0
    x = np.linalg.eigvals(comp)
    real = (np.abs(x.imag) <= 1e-9 * np.abs(x)) & (x.real > 0)
    x = np.where(real, x.real, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        x, p1w, w, phi = _env_roots(x, c, p1, s, k, b, m1, bb)
    n = np.ceil((w * ta[..., None] - phi) / (2 * np.pi))
    ok = (p1w >= 0) & (phi + 2 * np.pi * n <= w * tb[..., None])
    first = np.min(np.where(ok, w, np.inf), axis=-1) / (2 * np.pi)
    out = np.fmin(out, first)
    return np.where(np.isinf(out), np.nan, out)


def _env_roots(x, c, p1, s, k, b, m1, bb):  # type: ignore[no-untyped-def]
    """``bandwidth_worst_delay_K``'s roots x polished, P1 there, ω and arg(−E/D) mod 2π."""
    for _ in range(3):  # Newton on the degree-6 polynomial: the eigenvalues to full accuracy
        f = sum(ci[..., None] * x**i for i, ci in enumerate(c))
        df = sum(i * ci[..., None] * x ** (i - 1) for i, ci in enumerate(c) if i)
        x = x - f / df
    w = np.sqrt(s[..., None] * x)
    e = k[..., None] + 1j * b[..., None] * w
    d = k[..., None] - m1[..., None] * w * w + 1j * bb[..., None] * w
    p1w = sum(ci[..., None] * x**i for i, ci in enumerate(p1))
    phi = np.mod(np.angle(-e / d), 2 * np.pi)  # ωτ ≡ arg(−E/D): E e^{−jωτ}/D negative
    return x, p1w, w, phi


def _rows(box: HandBox, sel: np.ndarray) -> HandBox:
    """The designs ``sel`` (a mask) of ``box``."""
    return HandBox(*(tuple(x[sel] for x in f) if isinstance(f, tuple) else f[sel]
                     for f in (box.m1, box.b1, box.delay, box.K, box.k, box.b, box.m2,
                               box.valid)))  # fmt: skip


def robust_columns_batch(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign | None = None,
    uncertainty: Uncertainty | None = None,
    *,
    nominal: Mapping[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """robust_columns_batch(fields, base=None, uncertainty=None, *, nominal=None)
    -> dict[str, np.ndarray]

    The worst case, over ``uncertainty`` (an :class:`mrclutch.uncertainty.Uncertainty`;
    None: ``resolved_ranges(base)``, its declared uncertainty or the defaults), of the
    largest stable K and the largest passive K [N/m] and of the bandwidth at the rendered
    K_max [Hz], for S designs at once.
    ``fields``: the DrumClutch field arrays ``fast_batch.evaluate_batch`` takes (missing
    fields from ``base.clutch``); ``base``: the ClutchDesign giving the operating point and
    transmission (None: ``ClutchDesign()``). Returns 1-D arrays of S under
    ``ROBUST_COLUMNS``: ``max_stable_K_worst_N_per_m``, ``max_passive_K_worst_N_per_m``,
    ``bandwidth_worst_hz``; NaN for designs DrumClutch's validation refuses. Never above
    the worst over a dense sampling of the ranges (tests/mrclutch/test_robust.py).
    ``nominal``: ``evaluate_batch(fields, base)``'s rows where already computed (saves one
    fast-path evaluation)."""
    base = base if base is not None else ClutchDesign()
    unc = uncertainty if uncertainty is not None else resolved_ranges(base)
    lim = robust_limits(hand_box_batch(fields, base, unc, nominal), cases=("worst",))
    return {
        "max_stable_K_worst_N_per_m": lim["max_stable_K_worst"],
        "max_passive_K_worst_N_per_m": lim["max_passive_K_worst"],
        "bandwidth_worst_hz": lim["bandwidth_worst"],
    }


@dataclass(frozen=True)
class RobustBatchEvaluator(BatchEvaluator):
    """``fast_batch.BatchEvaluator`` that also computes the robust columns (``ROBUST_COLUMNS``,
    ``outputs.SWEEP_OPTIONAL``) over ``uncertainty`` (None: the base design's resolved ranges):
    what ``sweep --with max_stable_K_worst_N_per_m`` runs. Picklable."""

    uncertainty: Uncertainty | None = None

    def __call__(self, fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        on = set(self.optional)
        plain = tuple(k for k in self.optional if k not in ROBUST_COLUMNS)
        rows = dict(BatchEvaluator(self.base, plain)(fields))
        if on & set(ROBUST_COLUMNS):
            rows.update(robust_columns_batch(fields, self.base, self.uncertainty, nominal=rows))
        return {k: rows[k] for k in self.columns}
