"""Vectorised layout of many drum clutches at once, for sweeps (no section objects).

`layout(fields)` broadcasts arrays of DrumClutch fields and returns the radii and axial
positions that ``geometry/section.py`` lays out one design at a time. The two are
checked against each other design by design (tests/geometry/test_batch.py): the section
stays the single source of truth, this is its vectorised image.

Drum stacks of different drum counts share arrays padded to the largest count; masks say
which entries exist.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.params import FIELD_NAMES, INTEGER_FIELDS, DrumClutch, ParameterError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LayoutBatch:
    """Radii and axial positions of S designs (arrays of shape S, or S×K for drums/gaps).

    Gap k of a design lies between ``gap_r_inner[:, k]`` and ``gap_r_outer[:, k]``; it exists
    where ``gap_mask[:, k]``. Output drum i: ``out_r0/out_r1[:, i]`` where ``out_mask``.
    """

    p: Mapping[str, np.ndarray]  # every DrumClutch field, broadcast to shape S
    core_radius: FloatArray
    pole_radius: FloatArray
    out_r0: FloatArray
    out_r1: FloatArray
    out_mask: NDArray[np.bool_]
    in_r0: FloatArray
    in_r1: FloatArray
    in_mask: NDArray[np.bool_]
    gap_r_inner: FloatArray
    gap_r_outer: FloatArray
    gap_z0: FloatArray
    gap_z1: FloatArray
    gap_mask: NDArray[np.bool_]
    coil_inner_radius: FloatArray
    coil_outer_radius: FloatArray
    outer_radius: FloatArray
    z_hub0: FloatArray
    zs0: FloatArray
    zA0: FloatArray
    zA1: FloatArray
    zB0: FloatArray
    zB1: FloatArray
    zs1: FloatArray
    overall_length: FloatArray

    @property
    def size(self) -> int:
        return int(self.core_radius.size)


def broadcast_fields(
    values: Mapping[str, ArrayLike], base: DrumClutch | None = None
) -> dict[str, np.ndarray]:
    """Every DrumClutch field as a 1-D array of a common length S (missing ones from base)."""
    unknown = sorted(set(values) - set(FIELD_NAMES))
    if unknown:
        raise ParameterError(f"{unknown[0]}: unknown DrumClutch field")
    base = base if base is not None else DrumClutch()
    arrays: dict[str, Any] = {}
    for f in fields(DrumClutch):
        v = values[f.name] if f.name in values else getattr(base, f.name)
        arrays[f.name] = np.asarray(v, dtype=np.int64 if f.name in INTEGER_FIELDS else float)
    shaped = np.broadcast_arrays(*arrays.values())
    return {k: np.ravel(a) for k, a in zip(arrays, shaped, strict=True)}


def layout(values: Mapping[str, ArrayLike], base: DrumClutch | None = None) -> LayoutBatch:
    """Vectorised counterpart of ``DrumClutch``'s derived radii and ``build_section``'s z."""
    p = broadcast_fields(values, base)
    n = p["n_drums"]
    g, t_out, t_in = p["gap"], p["drum_thickness"], p["input_drum_thickness"]
    nmax = int(n.max()) if n.size else 1
    i = np.arange(nmax)[None, :]
    core = p["drum_inner_diameter"] / 2 - g
    # Radial pitch of one output+input pair: gap, out drum, gap, in drum.
    pitch = (2 * g + t_out + t_in)[:, None]
    out_r0 = core[:, None] + g[:, None] + i * pitch
    out_r1 = out_r0 + t_out[:, None]
    in_r0 = out_r1 + g[:, None]
    in_r1 = in_r0 + t_in[:, None]
    out_mask = i < n[:, None]
    in_mask = i < (n - 1)[:, None]
    pole = core + n * (2 * g + t_out) + (n - 1) * t_in

    # Axial positions (section.py: z = 0 at the front cap's outer face).
    t, cl = p["end_cap_thickness"], p["end_clearance"]
    z_hub0 = t + cl
    zs0 = z_hub0 + p["hub_thickness"]
    zA0 = zs0 + cl
    zA1 = zA0 + p["zone_length"]
    zB0 = zA1 + p["band_length"]
    zB1 = zB0 + p["zone_length"]
    zs1 = zB1 + cl

    # Gaps: 2 per output drum; inner wall of gap 2i is core (i=0) or in drum i-1; gap 2i+1
    # lies outside output drum i. Wetted length [zA0, zB1] except the last gap [zs0, zB1].
    k = np.arange(2 * nmax)[None, :]
    drum = k // 2
    inner_side = (k % 2) == 0
    gi = np.where(inner_side, out_r0[:, drum[0]] - g[:, None], out_r1[:, drum[0]])
    go = gi + g[:, None]
    gap_mask = k < (2 * n)[:, None]
    last = k == (2 * n - 1)[:, None]
    gap_z0 = np.where(last, zs0[:, None], zA0[:, None]) + 0 * gi
    gap_z1 = zB1[:, None] + 0 * gi

    coil_in = pole + p["sleeve_thickness"]
    coil_out = coil_in + p["coil_depth"]
    outer = coil_out + p["shell_thickness"]
    overall = zs1 + t + p["shaft_length"]
    return LayoutBatch(
        p, core, pole, out_r0, out_r1, out_mask, in_r0, in_r1, in_mask,
        gi, go, gap_z0, gap_z1, gap_mask, coil_in, coil_out, outer,
        z_hub0, zs0, zA0, zA1, zB0, zB1, zs1, overall,
    )  # fmt: skip
