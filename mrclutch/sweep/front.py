"""The Pareto front of a sweep's rows: the rows no other row beats in every objective
(``sweep --pareto`` and its plot, mrclutch.cli.plots.design)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def pareto_front(objectives: np.ndarray, maximize: Sequence[bool]) -> np.ndarray:
    """Boolean mask of the non-dominated rows of ``objectives`` (n × k); NaN rows excluded.

    A row is dominated when another is at least as good in every objective and better in
    one. Sorted sweep on the first objective, each candidate checked against the front
    (a row equal to an earlier one is left out with it). Two objectives: a row of that
    order is on the front when its second objective beats every earlier row's (one running
    maximum, 10⁵ rows in ~10 ms). More: the rows go in blocks of ``_FRONT_BLOCK``, a block
    checked against the front so far and against itself at once (10⁵ rows: a fraction of a
    second rather than one NumPy call per row, issue 40).
    """
    obj = np.asarray(objectives, dtype=float)
    sign = np.where(np.asarray(maximize), 1.0, -1.0)
    x = obj * sign  # now maximise everything
    ok = np.all(np.isfinite(x), axis=1)
    idx = np.flatnonzero(ok)
    order = idx[np.lexsort(tuple(-x[idx, j] for j in reversed(range(x.shape[1]))))]
    mask = np.zeros(obj.shape[0], dtype=bool)
    if x.shape[1] == 2 and order.size:  # earlier rows are ≥ in the first objective
        second = x[order, 1]
        best_before = np.maximum.accumulate(np.concatenate(([-np.inf], second[:-1])))
        mask[order[second > best_before]] = True
        return mask
    front: list[int] = []
    fx = np.empty((order.size, x.shape[1]))  # the front's rows, the first len(front) used
    below = np.tri(_FRONT_BLOCK, k=-1, dtype=bool)  # [j, i]: i < j
    for lo in range(0, order.size, _FRONT_BLOCK):
        block = order[lo : lo + _FRONT_BLOCK]
        if front:  # weakly dominated by the front so far: out
            block = block[~_covered(fx[: len(front)], x[block])]
        # within the block, a row weakly dominated by an earlier one is out (checking all
        # earlier rows is checking the front: a dominated dominator's own is earlier still)
        xb = x[block]
        earlier = below[: block.size, : block.size]
        covered = ((xb[None, :] >= xb[:, None]).all(-1) & earlier).any(-1)
        keep = block[~covered]
        fx[len(front) : len(front) + keep.size] = x[keep]
        front.extend(keep.tolist())
    mask[front] = True
    return mask


_FRONT_BLOCK = 256  # rows of pareto_front's sweep checked against the front at once


def _covered(front: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Which ``rows`` (B × k) some row of ``front`` (F × k, each ≥ every row in the first
    objective: earlier in the sweep's order) weakly dominates. Up to three objectives by
    the front's staircase in the others (a search per row); more, all pairs."""
    k = rows.shape[1]
    if k == 1:
        return np.ones(rows.shape[0], dtype=bool)
    if k == 2:
        return rows[:, 1] <= front[:, 1].max()
    if k == 3:  # the most of objective 2 over the front rows at or above each objective 1
        o = np.argsort(-front[:, 1], kind="stable")
        best = np.maximum.accumulate(front[o, 2])
        n = np.searchsorted(-front[o, 1], -rows[:, 1], side="right")  # rows with f1 ≥ a
        return (n > 0) & (best[np.maximum(n - 1, 0)] >= rows[:, 2])
    return (front[None] >= rows[:, None]).all(-1).any(-1)
