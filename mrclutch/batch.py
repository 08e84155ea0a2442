"""A batch of designs as arrays: the dimensions broadcast to S rows and the material of
each row (the sweep's, the optimiser's and the batch models' one reader of a batch). A leaf
of the application layer: it imports geometry only, so every batch model (mrclutch.feel,
mrclutch.duty, mrclutch.hand_box, mrclutch.fast_batch) can read its batches here."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from geometry.materials import SLOTS, MaterialChoice
from geometry.params import broadcast_fields


def batch_fields(
    fields: Mapping[str, Any], base: Any
) -> tuple[dict[str, np.ndarray], MaterialChoice | np.ndarray]:
    """A batch's dimensions (``base``: the ``ClutchDesign`` it varies) as 1-D arrays of S
    (``broadcast_fields``) and its materials: one MaterialChoice for all rows or S of them
    (``material_rows``: the material columns)."""
    fields, mats = material_rows(fields, base.materials)
    if not isinstance(mats, MaterialChoice):  # the material columns set the batch's shape too
        drums = np.asarray(fields.get("n_drums", base.clutch.n_drums))
        fields = {**fields, "n_drums": np.broadcast_to(drums, np.broadcast_shapes(
            drums.shape, mats.shape))}  # fmt: skip
    p = broadcast_fields(fields, base.clutch)
    if not isinstance(mats, MaterialChoice):
        mats = np.broadcast_to(mats, np.shape(p["n_drums"])).ravel()
    return p, mats


def material_rows(
    fields: Mapping[str, Any], base: MaterialChoice
) -> tuple[dict[str, Any], MaterialChoice | np.ndarray]:
    """Split a batch's material columns (``SLOTS`` names: ``fluid``, ``core`` …, each a
    name or an array of names) from its dimensions: (the dimensions, one MaterialChoice
    for every row or an object array of them, one per row). Names are checked here
    (unknown ones refused with the known list)."""
    cols = {k: v for k, v in fields.items() if k in SLOTS}
    rest = {k: v for k, v in fields.items() if k not in SLOTS}
    if not cols:
        return rest, base
    arrs = {k: np.asarray(v, dtype=object) for k, v in cols.items()}
    shape = np.broadcast_shapes(*(a.shape for a in arrs.values()))
    flat = {k: np.broadcast_to(a, shape).ravel() for k, a in arrs.items()}
    cache: dict[tuple[Any, ...], MaterialChoice] = {}
    out = np.empty(int(np.prod(shape)), dtype=object)
    keys = tuple(flat)
    for i in range(out.size):
        combo = tuple(flat[k][i] for k in keys)
        if combo not in cache:
            cache[combo] = replace(base, **dict(zip(keys, combo, strict=True)))
        out[i] = cache[combo]
    return rest, out.reshape(shape)
