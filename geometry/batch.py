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

from geometry import params as rules
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


def core_radius(p: Mapping[str, np.ndarray]) -> FloatArray:
    """Outer radius of the steel core (DrumClutch.core_radius)."""
    return p["drum_inner_diameter"] / 2 - p["gap"]


def drum_radii(p: Mapping[str, np.ndarray], i: int) -> tuple[FloatArray, ...]:
    """(out_r0, out_r1, in_r0, in_r1) of drum pair ``i`` (0-based), 1-D over designs.

    Whether the drum exists is ``i < n_drums`` (output) and ``i < n_drums − 1`` (input).
    """
    g = p["gap"]
    # Radial pitch of one output+input pair: gap, out drum, gap, in drum.
    pitch = 2 * g + p["drum_thickness"] + p["input_drum_thickness"]
    out_r0 = core_radius(p) + g + i * pitch
    out_r1 = out_r0 + p["drum_thickness"]
    in_r0 = out_r1 + g
    return out_r0, out_r1, in_r0, in_r0 + p["input_drum_thickness"]


def axial_positions(p: Mapping[str, np.ndarray]) -> tuple[FloatArray, ...]:
    """(z_hub0, zs0, zA0, zA1, zB0, zB1, zs1); section.py: z = 0 at the front cap's face."""
    t, cl = p["end_cap_thickness"], p["end_clearance"]
    z_hub0 = t + cl
    zs0 = z_hub0 + p["hub_thickness"]
    zA0 = zs0 + cl
    zA1 = zA0 + p["zone_length"]
    zB0 = zA1 + p["band_length"]
    zB1 = zB0 + p["zone_length"]
    zs1 = zB1 + cl
    return z_hub0, zs0, zA0, zA1, zB0, zB1, zs1


def layout(
    values: Mapping[str, ArrayLike], base: DrumClutch | None = None, *, with_gaps: bool = True
) -> LayoutBatch:
    """Vectorised counterpart of ``DrumClutch``'s derived radii and ``build_section``'s z.

    ``with_gaps=False`` skips the S×2N gap arrays (left with 0 columns) for callers that
    need only the solids, e.g. the vectorised mass (``geometry.mass.analytic_batch``).
    """
    p = broadcast_fields(values, base)
    n = p["n_drums"]
    g, t_out, t_in = p["gap"], p["drum_thickness"], p["input_drum_thickness"]
    nmax = int(n.max()) if n.size else 1
    i = np.arange(nmax)[None, :]
    core = core_radius(p)
    # one column per drum index (1-D kernels: an S×K broadcast with K ≈ 2–5 is slow)
    cols = [drum_radii(p, j) for j in range(nmax)]
    out_r0, out_r1, in_r0, in_r1 = (
        np.column_stack([c[m] for c in cols]) if cols else np.zeros((g.size, 0)) for m in range(4)
    )
    out_mask = i < n[:, None]
    in_mask = i < (n - 1)[:, None]
    pole = core + n * (2 * g + t_out) + (n - 1) * t_in

    t = p["end_cap_thickness"]
    z_hub0, zs0, zA0, zA1, zB0, zB1, zs1 = axial_positions(p)

    # Gaps: 2 per output drum; inner wall of gap 2i is core (i=0) or in drum i-1; gap 2i+1
    # lies outside output drum i. Wetted length [zA0, zB1] except the last gap [zs0, zB1].
    k = np.arange(2 * nmax if with_gaps else 0)[None, :]
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


def valid(lay: LayoutBatch) -> NDArray[np.bool_]:
    """Which designs pass DrumClutch's validation: the same rule tables and predicates."""
    p = lay.p
    ok = np.ones(lay.size, dtype=bool)
    for name, ilo, ihi in rules.INT_RANGES:
        ok &= (p[name] >= ilo) & (p[name] <= ihi)
    for name, lo, hi, lo_open in rules.LENGTH_RANGES:
        v = p[name]
        ok &= ((v > lo) if lo_open else (v >= lo)) & (v <= hi)  # NaN fails both
    for name in rules.NONNEGATIVE_FIELDS:
        ok &= np.isfinite(p[name]) & (p[name] >= 0)
    for name in rules.POSITIVE_FIELDS:
        ok &= np.isfinite(p[name]) & (p[name] > 0)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        ok &= lay.core_radius > 0
        ok &= p["shaft_radius"] < hub_outer_radius(lay)
        d_ins = p["wire_diameter"] + 2 * p["wire_insulation"]
        ok &= rules.coil_fits(p["coil_turns"], d_ins, p["coil_depth"], p["band_length"])
        ok &= rules.wire_fits(d_ins, p["coil_depth"], p["band_length"])
        r_h, d_h = p["hub_hole_pitch_radius"], p["hub_hole_diameter"]
        first_r0 = drum_radii(p, 0)[0]
        holes_ok = rules.hub_holes_inside(r_h, d_h, p["shaft_radius"], first_r0)
        holes_ok &= rules.hub_holes_apart(p["hub_holes"], r_h, d_h)
        ok &= (p["hub_holes"] == 0) | holes_ok
    return ok


def hub_outer_radius(lay: LayoutBatch) -> FloatArray:
    """Outer radius of the outermost output drum (= the hub's outer radius), shape S."""
    if lay.out_r1.shape[1] == 0:  # every design has n_drums = 0 (invalid)
        return np.full(lay.size, np.nan)
    last = np.clip(lay.p["n_drums"] - 1, 0, lay.out_r1.shape[1] - 1)
    return lay.out_r1[np.arange(lay.size), last]
