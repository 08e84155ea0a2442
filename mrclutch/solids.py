"""The clutch's solids as the commands use them: the chord height a mesh is cut to (checked
against the clutch's size, or the one a view's pixel needs), the STEP + STL export, the
tessellated (half-cut) solids the 3-D view draws, and how a material is drawn (its colour,
its label) and in what order the view's legend lists them.

The CLI (``mrclutch export``, ``inertia``, ``view``; mrclutch/cli/view.py draws with
pyvista) parses, calls these and formats. build123d loads with geometry.cad's functions.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from geometry.cad import MATERIAL_COLOURS, check_tolerance, material_solids, tessellate
from geometry.export import ExportResult, export_clutch
from geometry.materials import LABEL
from geometry.params import DrumClutch
from geometry.section import build_section
from geometry.validation import ParameterError, check_positive
from mrclutch.design import ClutchDesign

#: Angular deflection (rad) of the view's tessellation beside its chord height.
VIEW_ANGLE = 0.3


def chord_height_mm(option: str, value_mm: float, clutch: DrumClutch) -> float:
    """An ``_mm`` chord-height option in metres: > 0, and within the bounds relative to the
    clutch's size (geometry.cad.check_tolerance: memory below, shape above)."""
    tol = check_positive(option, value_mm, " mm") * 1e-3
    return check_tolerance(option, tol, clutch, scale=1e3)


def export_cad(design: ClutchDesign, folder: str | Path, tolerance: float) -> ExportResult:
    """STEP (one solid per material), its materials sidecar and one STL per part, written
    into ``folder`` with the chord height ``tolerance`` (m): geometry.export.export_clutch."""
    return export_clutch(design.clutch, folder, tolerance, materials=design.materials)


def view_tolerance(clutch: DrumClutch, window_size: tuple[int, int]) -> float:
    """Chord height [m] the view needs: one pixel when the whole clutch fills the window
    (its larger envelope side over the window's smaller side). A finer tessellation adds
    triangles no one can see; a coarser one shows facets."""
    if min(window_size) < 1:
        raise ParameterError(f"window_size = {window_size!r}: need positive pixel counts")
    return max(build_section(clutch).envelope) / min(window_size)


def view_triangles(clutch: DrumClutch, tolerance: float,
                   cut: bool = True) -> list[tuple[str, str, Any, Any]]:  # fmt: skip
    """(part, material, vertices in mm, faces) of every solid, half of each if ``cut``,
    tessellated to ``tolerance`` (m); faces in VTK's layout (3, i, j, k per triangle)."""
    check_positive("tolerance", tolerance, " m")
    out = []
    for (part, material), shape in material_solids(
        clutch, angle_deg=180.0 if cut else 360.0
    ).items():
        v, f = tessellate(shape, tolerance * 1e3, VIEW_ANGLE)
        faces = np.hstack([np.full((len(f), 1), 3), f]).ravel()
        out.append((part, material, v, faces))
    return out


def material_colour(material: str) -> tuple[float, float, float]:
    """The RGB colour (0…1) a material is drawn in (geometry.cad.MATERIAL_COLOURS)."""
    return MATERIAL_COLOURS[material]


def material_label(material: str) -> str:
    """A material's name as a legend prints it (geometry.materials.LABEL)."""
    return LABEL[material]


def legend_entries(clutch: DrumClutch) -> list[tuple[str, tuple[float, float, float]]]:
    """(label, colour) of every (part, material) in the view, in the section's order."""
    seen: list[tuple[str, tuple[float, float, float]]] = []
    for reg in build_section(clutch).regions:
        entry = (f"{reg.part} ({reg.material})", MATERIAL_COLOURS[reg.material])
        if entry not in seen:
            seen.append(entry)
    return seen
