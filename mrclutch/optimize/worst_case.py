"""The optimiser's worst case: the uncertainty ranges it judges a design over
(``process_uncertainty``) and the haptic verdict over them (``WorstCase``: the rendered K
and its bandwidth, a cheap proxy for every design of a search, the full check for the
members)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from mrclutch.design import ClutchDesign
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import bandwidth, max_passive_stiffness
from mrclutch.hot_range import resolved_ranges
from mrclutch.optimize.limits import ROBUST_COLUMNS
from mrclutch.robust import hand_box_batch, robust_columns_batch
from mrclutch.uncertainty import Uncertainty, default_uncertainty


def process_uncertainty(base: ClutchDesign) -> Uncertainty:
    """The uncertainty ranges the optimiser's worst case takes: the design's declared
    ``[uncertainty]`` if it has one; otherwise ``default_uncertainty`` (viscosity, fluid
    temperature, delay, bench damping, yield-stress and B–H lots; docs/verdicts.md) with the
    manufacturing ranges of its ``[process]``: the runout as the drums' eccentricity and
    the tolerance as the gap's."""
    if base.uncertainty is not None:
        return resolved_ranges(base)  # the declared ranges, "duty" resolved
    pr = base.process
    return replace(default_uncertainty(base), runout=pr.runout, gap_tolerance=pr.tolerance)


@dataclass(frozen=True)
class WorstCase:
    """The haptic verdict over the uncertainty ranges, for ``pareto`` and ``optimize``.

    Over ranges this wide no clutch keeps its K_max = F_max/d passive (docs/optimize.md),
    so a design renders the largest K the worst case allows, K = min(K_max, worst-case
    largest passive K, worst-case largest stable K), and its bandwidth is taken at that K
    (``bandwidth_hz`` of its rows; K_max stays under ``K_max_N_per_m``).

    * ``proxy`` (every design of the search): the worst-case passive K at the corner
      (m1⁺, b1⁻, τ⁺) of the hand box without the geometry's tolerance corners (no extra
      fast-path evaluation; passivity is monotone there: ``mrclutch.robust``);
    * ``full`` (the members): ``robust_columns_batch``, the tolerance corners and the
      bounded search of the stable K included; K is taken again from it, so every member
      holds its K over the ranges by construction."""

    uncertainty: Uncertainty

    def _box(self, fields: Mapping[str, ArrayLike], base: ClutchDesign,
             r: Mapping[str, np.ndarray]) -> Any:  # fmt: skip
        """The hand box without the geometry's tolerance corners (no fast-path run)."""
        unc = replace(self.uncertainty, gap_tolerance=0.0, drum_thickness_tolerance=0.0)
        return hand_box_batch(fields, base, unc, nominal=r)

    @staticmethod
    def _at(box: Any, r: Mapping[str, np.ndarray], k_cap: np.ndarray) -> dict[str, np.ndarray]:
        """K = min(K_max, k_cap) and the nominal bandwidth at it."""
        k_max = np.asarray(r["K_max_N_per_m"] if "K_max_N_per_m" in r else r["K_N_per_m"],
                           dtype=float)  # fmt: skip
        k = np.minimum(k_max, k_cap)  # NaN (no finite worst case) stays NaN: refused
        ok = np.isfinite(k) & (k > 0) & box.valid
        bw = np.full(k.shape, np.nan)
        if ok.any():  # the nominal pair of the valid rows only (an invalid row is NaN)
            sub = HapticParams(box.m1[0][ok], box.b1[0][ok], box.k[ok], box.b[ok], box.m2[ok],
                               delay=box.delay[0][ok])  # fmt: skip
            bw[ok] = bandwidth(sub, k[ok])
        return {"K_max_N_per_m": k_max, "K_N_per_m": k, "bandwidth_hz": bw}

    def proxy(self, fields: Mapping[str, ArrayLike], base: ClutchDesign,
              r: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:  # fmt: skip
        box = self._box(fields, base, r)
        kp = np.full(box.valid.shape, np.nan)
        ok = box.valid
        if ok.any():
            (_, _, mhi), (_, blo, _), (_, _, thi) = box.m1, box.b1, box.delay
            sub = HapticParams(mhi[ok], blo[ok], box.k[ok], box.b[ok], box.m2[ok],
                               delay=thi[ok])  # fmt: skip
            kp[ok] = max_passive_stiffness(sub)
        return self._at(box, r, kp)

    def full(self, fields: Mapping[str, ArrayLike], base: ClutchDesign,
             r: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:  # fmt: skip
        cols = robust_columns_batch(fields, base, self.uncertainty)
        ks, kp = cols["max_stable_K_worst_N_per_m"], cols["max_passive_K_worst_N_per_m"]
        out = self._at(self._box(fields, base, r), r, np.minimum(kp, ks) * (1 - 1e-6))
        return {**out, **{c: cols[c] for c in ROBUST_COLUMNS.values()}}


def robust_verdict(base: ClutchDesign, uncertainty: Uncertainty | None = None) -> WorstCase:
    """The worst case for ``pareto(robust=...)`` and ``optimize(robust=...)`` over
    ``uncertainty`` (None: ``process_uncertainty(base)``)."""
    return WorstCase(uncertainty if uncertainty is not None else process_uncertainty(base))
