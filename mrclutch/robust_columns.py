"""The limits over a hand box (``robust_limits``: nominal, worst and best of the largest
stable and passive K and of the bandwidth) and the robust sweep columns built on them
(``robust_columns_batch``, ``RobustBatchEvaluator``: ``sweep --with
max_stable_K_worst_N_per_m``)."""

from __future__ import annotations

from collections.abc import Mapping
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
from mrclutch.robust_search import box_search, stable_stiffness_batch
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
    sub = HandBox(*(tuple(x[ok] for x in f) if isinstance(f, tuple) else f[ok]
                    for f in (box.m1, box.b1, box.delay, box.K, box.k, box.b, box.m2,
                              box.valid)))  # fmt: skip
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
    # destabilise: tests), a search over all three
    for case, sense, z in (x for x in (("worst", -1, zooms + 2), ("best", 1, zooms))
                           if x[0] in cases):  # fmt: skip
        res[f"max_stable_K_{case}"], _ = box_search(
            lambda x: stable_stiffness_batch(sub.params(x[..., 0], x[..., 1], x[..., 2])),
            np.stack([mlo, blo, tlo], 1), np.stack([mhi, bhi, thi], 1), sense=sense,
            points=points, zooms=z)  # fmt: skip
    # bandwidth at the rendered K: not monotone in any input (tests): a search over all four
    for case, sense in (x for x in (("worst", -1), ("best", 1)) if x[0] in cases):
        res[f"bandwidth_{case}"], _ = box_search(
            lambda x: bandwidth(sub.params(x[..., 0], x[..., 1], x[..., 2]), x[..., 3]),
            np.stack([mlo, blo, tlo, klo], 1), np.stack([mhi, bhi, thi, khi], 1),
            sense=sense, points=points, zooms=zooms + 1)  # fmt: skip
    for key, v in res.items():
        out[key][ok] = v
    return out


CASES = ("nominal", "worst", "best")


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
    None: ``base.ranges``, its declared uncertainty or the defaults), of the largest stable K
    and the largest passive K [N/m] and of the bandwidth at the rendered K_max [Hz], for S
    designs at once.
    ``fields``: the DrumClutch field arrays ``fast_batch.evaluate_batch`` takes (missing
    fields from ``base.clutch``); ``base``: the ClutchDesign giving the operating point and
    transmission (None: ``ClutchDesign()``). Returns 1-D arrays of S under
    ``ROBUST_COLUMNS``: ``max_stable_K_worst_N_per_m``, ``max_passive_K_worst_N_per_m``,
    ``bandwidth_worst_hz``; NaN for designs DrumClutch's validation refuses. Never above
    the worst over a dense sampling of the ranges (tests/mrclutch/test_robust.py).
    ``nominal``: ``evaluate_batch(fields, base)``'s rows where already computed (saves one
    fast-path evaluation)."""
    base = base if base is not None else ClutchDesign()
    unc = uncertainty if uncertainty is not None else base.ranges
    lim = robust_limits(hand_box_batch(fields, base, unc, nominal), cases=("worst",))
    return {
        "max_stable_K_worst_N_per_m": lim["max_stable_K_worst"],
        "max_passive_K_worst_N_per_m": lim["max_passive_K_worst"],
        "bandwidth_worst_hz": lim["bandwidth_worst"],
    }


@dataclass(frozen=True)
class RobustBatchEvaluator(BatchEvaluator):
    """``fast_batch.BatchEvaluator`` that also computes the robust columns (``ROBUST_COLUMNS``,
    ``outputs.SWEEP_OPTIONAL``) over ``uncertainty`` (None: the base design's ``ranges``):
    what ``sweep --with max_stable_K_worst_N_per_m`` runs. Picklable."""

    uncertainty: Uncertainty | None = None

    def __call__(self, fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        on = set(self.optional)
        plain = tuple(k for k in self.optional if k not in ROBUST_COLUMNS)
        rows = dict(BatchEvaluator(self.base, plain)(fields))
        if on & set(ROBUST_COLUMNS):
            rows.update(robust_columns_batch(fields, self.base, self.uncertainty, nominal=rows))
        return {k: rows[k] for k in self.columns}
