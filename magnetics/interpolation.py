"""Multilinear interpolation on a grid whose first axes must hit a node (the drum count):
the error maps' (magnetics.error_map) and the outer air's table (magnetics.outer_air).
Its own module so that the tables the network is built from do not import the error
maps, which read the network's bound (magnetics.network_bound)."""

from __future__ import annotations

import functools
import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np


def interpolate(
    axes: Mapping[str, tuple[float, ...]], grid: np.ndarray, point: Mapping[str, Any],
    node_axes: int = 1,
) -> Any:  # fmt: skip
    """Multilinear interpolation of ``grid`` (shape = the axes' lengths) at ``point`` (scalars
    or arrays that broadcast). The first ``node_axes`` axes (the maps': the drum count) must
    hit a node exactly. NaN outside the axes or where a corner with non-zero weight is NaN."""
    return _interp(axes, grid, point, node_axes)[0]


@functools.lru_cache(maxsize=8)
def _corners(k: int, node_axes: int = 1) -> np.ndarray:
    """The corners of a cell, 0/1 per axis; the first ``node_axes`` axes fixed at 0."""
    return np.array([(0,) * node_axes + c
                     for c in itertools.product((0, 1), repeat=k - node_axes)])  # fmt: skip


def _interp(
    axes: Mapping[str, tuple[float, ...]], grid: np.ndarray, point: Mapping[str, Any],
    node_axes: int = 1,
) -> tuple[Any, Any, Any]:  # fmt: skip
    """(estimate, worst 4·t(1 − t) over the continuous axes, range of the grid values at the
    corners of the point's cell — its local variation); the first ``node_axes`` axes must
    hit a node (``interpolate``)."""
    names = list(axes)
    vals = np.broadcast_arrays(*(np.asarray(point[n], dtype=float) for n in names))
    shape = vals[0].shape
    vals = [v.ravel() for v in vals]
    inside = np.ones(vals[0].shape, bool)
    lo_idx, frac = [], []
    for k, (name, x) in enumerate(zip(names, vals, strict=True)):
        a = np.asarray(axes[name], dtype=float)
        span = a[-1] - a[0]
        ok = (x >= a[0] - 1e-9 * span) & (x <= a[-1] + 1e-9 * span)
        xc = np.clip(x, a[0], a[-1])
        i = np.clip(np.searchsorted(a, xc, side="right") - 1, 0, a.size - 2)
        t = (xc - a[i]) / (a[i + 1] - a[i])
        t = np.where(np.abs(t) < 1e-9, 0.0, np.where(np.abs(1 - t) < 1e-9, 1.0, t))
        if k < node_axes:  # the drum count: a node, no interpolation and no cell
            ok &= (t == 0.0) | (t == 1.0)
            i, t = i + (t == 1.0), np.zeros_like(t)
        inside &= ok
        lo_idx.append(i)
        frac.append(t)
    # all corners of the cell at once (a node axis has one)
    corners = _corners(len(names), node_axes)
    # per axis j: each corner's index (M, P) and weight factor t or 1 − t (the rows of
    # [1 − t, t] its 0/1 picks); the weights' product over the axes in their order
    idx = tuple(i[None] + corners[:, j, None] for j, i in enumerate(lo_idx))
    w = np.stack([1.0 - frac[0], frac[0]])[corners[:, 0]]  # (M, P)
    for j in range(1, len(names)):
        w *= np.stack([1.0 - frac[j], frac[j]])[corners[:, j]]
    v = grid[idx]  # (M, P)
    est = np.sum(np.where(w > 0, w * v, 0.0), axis=0)  # NaN corners count only with weight
    hi, lo = np.fmax.reduce(v, axis=0), np.fmin.reduce(v, axis=0)
    est = np.where(inside, est, np.nan)
    spread = np.max([4 * t * (1 - t) for t in frac[node_axes:]], axis=0)
    rng = np.where(inside, hi - lo, np.nan)
    if shape == ():
        return float(est[0]), float(spread[0]), float(rng[0])
    return est.reshape(shape), spread.reshape(shape), rng.reshape(shape)
