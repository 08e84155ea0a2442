"""The optimiser's search box: the ranges it varies (``DEFAULT_BOUNDS``, ``--vary``
through ``parse_bounds``), their lower edges raised to the process's limits
(``search_box``), and the edges a design touches, each with what to do (``range_edges``)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from geometry.params import INTEGER_FIELDS, LENGTH_FIELDS, LENGTH_RANGES
from geometry.validation import ParameterError
from mrclutch.design import ClutchDesign
from mrclutch.process import MAX_ECCENTRICITY

#: Default search box (m): what a drum clutch of the paper's size can vary.
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "gap": (0.2e-3, 1.0e-3),
    "drum_thickness": (0.1e-3, 0.6e-3),
    "drum_inner_diameter": (6e-3, 18e-3),
    "zone_length": (3e-3, 9e-3),
}


def search_box(base: ClutchDesign, bounds: Mapping[str, tuple[float, float]] | None
               ) -> tuple[dict[str, tuple[float, float]], dict[str, str]]:  # fmt: skip
    """The search box (m) and where each lower edge comes from ("range": the bounds given
    or ``DEFAULT_BOUNDS``; "process": raised to ``base.process``'s limit). A process limit
    above a range's upper edge, or above a fixed dimension of the base design, is an
    error naming both."""
    box = dict(DEFAULT_BOUNDS if bounds is None else bounds)
    for name, (lo, hi) in box.items():
        if name not in LENGTH_FIELDS:
            raise ParameterError(f"bounds: {name}: not a DrumClutch length")
        if not 0 < lo < hi:
            raise ParameterError(f"bounds: {name} = [{lo}, {hi}]: need 0 < min < max")
    source = dict.fromkeys(box, "range")
    pr = base.process
    for name, least in pr.lower_bounds().items():
        why = ("the process's smallest gap (runout + tolerance)/" f"{MAX_ECCENTRICITY:g}"
               if name == "gap" else "the process's smallest wall")  # fmt: skip
        if name in box:
            lo, hi = box[name]
            if least >= hi:
                raise ParameterError(f"{name}_mm: {why} is {least * 1e3:.4g} mm, above the "
                                     f"range's upper edge {hi * 1e3:.4g} mm; widen --vary or "
                                     "relax [process]")  # fmt: skip
            if least > lo:
                box[name], source[name] = (least, hi), "process"
        elif getattr(base.clutch, name) < least * (1 - 1e-9):
            raise ParameterError(f"{name}_mm = {getattr(base.clutch, name) * 1e3:.4g} (fixed): "
                                 f"below {why}, {least * 1e3:.4g} mm; vary it or relax "
                                 "[process]")  # fmt: skip
    return box, source


def parse_bounds(specs: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``NAME_mm=LO:HI`` strings (CLI) into SI bounds."""
    out: dict[str, tuple[float, float]] = {}
    for s in specs:
        name, _, rng = s.partition("=")
        lo, _, hi = rng.partition(":")
        if not name.endswith("_mm") or name[:-3] not in LENGTH_FIELDS or name in INTEGER_FIELDS:
            raise ParameterError(f"--vary {s!r}: give NAME_mm=LO:HI with a DrumClutch length")
        try:
            a, b = float(lo), float(hi)
        except ValueError:
            raise ParameterError(f"--vary {s!r}: LO and HI must be numbers (mm)") from None
        if not (math.isfinite(a) and math.isfinite(b) and 0 < a < b):
            raise ParameterError(f"--vary {s!r}: need finite 0 < LO < HI (mm)")
        least, most = next((lo, hi) for f, lo, hi, _ in LENGTH_RANGES if f == name[:-3])
        if a * 1e-3 < least or b * 1e-3 > most:  # the optimiser would only see invalid rows
            raise ParameterError(f"--vary {s!r}: {name} must stay within [{least * 1e3:g}, "
                                 f"{most * 1e3:g}] mm")  # fmt: skip
        out[name[:-3]] = (a * 1e-3, b * 1e-3)
    return out


#: A member *touches* a search-range edge within this fraction of the range.
EDGE = 0.01


def range_edges(
    design: ClutchDesign,
    box: Mapping[str, tuple[float, float]],
    source: Mapping[str, str],
    drum_counts: Sequence[int],
) -> tuple[str, ...]:
    """The search-range edges a design touches, each with what to do about it."""
    out = []
    for name, (lo, hi) in box.items():
        v, tol = getattr(design.clutch, name), EDGE * (hi - lo)
        if v <= lo + tol:
            if source.get(name) == "process":
                out.append(f"{name} at the process limit ({lo * 1e3:.4g} mm): a finer process "
                           "([process] runout, tolerance or min_wall) allows less")  # fmt: skip
            else:
                out.append(f"{name} at the lower edge of --vary ({lo * 1e3:.4g} mm): widen the "
                           "range or relax the process limit")  # fmt: skip
        elif v >= hi - tol:
            out.append(f"{name} at the upper edge of --vary ({hi * 1e3:.4g} mm): widen the range")
    n = design.clutch.n_drums
    if len(drum_counts) > 1 and n == max(drum_counts):
        out.append(f"n_drums at the largest of --drums ({n}): try more drums")
    return tuple(out)
