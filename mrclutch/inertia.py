"""What ``mrclutch inertia`` computes for a design: its rotor inertia and masses by each
method (analytic from the section, mesh from the STLs, B-rep from the CAD solids).

The CLI (mrclutch/cli/commands/inertia.py) parses the options, calls this and formats; a CAD
file is weighed by mrclutch.weigh. build123d and trimesh load with the geometry functions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from geometry.cad import material_solids
from geometry.mass import MassReport, analytic_mass, brep_mass, mesh_mass
from geometry.section import build_section
from mrclutch.design import ClutchDesign

__all__ = ["METHODS", "design_inertia"]

#: A design's methods, cheapest first: analytic (the section), mesh (STL), brep (CAD).
METHODS = ("analytic", "mesh", "brep")


def design_inertia(design: ClutchDesign, methods: Sequence[str], tolerance: float | None,
                   done: Callable[..., Any] | None = None,
                   ) -> tuple[dict[str, MassReport], tuple[float, float]]:  # fmt: skip
    """The mass report of each of ``methods`` (METHODS) and the clutch's envelope (diameter,
    length; m). The CAD solids are built once, only for mesh or brep; ``tolerance`` (m) is
    the mesh's chord height (None where no mesh is asked). ``done(step, message)`` is told
    after the solids (step 1, a message only when built) and after each method."""
    tell = done if done is not None else (lambda *a: None)
    clutch = design.clutch
    s = build_section(clutch, design.materials)
    cad = bool(set(methods) - {"analytic"})
    solids = material_solids(clutch, s) if cad else None
    tell(1, "inertia: CAD solids built" if cad else None)
    reps: dict[str, MassReport] = {}
    for k, m in enumerate(methods, 2):
        if m == "analytic":
            reps[m] = analytic_mass(s)
        elif m == "mesh":
            reps[m] = mesh_mass(clutch, tolerance, solids=solids, materials=design.materials)
        else:
            reps[m] = brep_mass(clutch, solids, materials=design.materials)
        tell(k)
    return reps, s.envelope
