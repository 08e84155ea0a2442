"""Parametric MR drum clutch: dimensions, the axisymmetric cross-section, mass and CAD.

Light to import: CAD (build123d) and meshes (trimesh) are imported inside the functions
that need them, never here.
"""

from geometry.params import PRESETS, DrumClutch, preset
from geometry.section import Region, Section, build_section
from geometry.validation import ParameterError

__all__ = [
    "PRESETS",
    "DrumClutch",
    "ParameterError",
    "Region",
    "Section",
    "build_section",
    "preset",
]
