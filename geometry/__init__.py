"""Parametric MR drum clutch: dimensions, the axisymmetric cross-section, mass and CAD.

Light to import: CAD (build123d) and meshes (trimesh) are imported inside the functions
that need them, never here. The names below are re-exported on first use (PEP 562), so
that importing one light module of the package (``geometry.validation``, which every
layer's checks import) does not build the material registry, the region table and the
presets: the catalogue's ``haptic`` and ``compare`` use none of them (issue 40 item 1).
"""

import importlib
from typing import Any

#: Each re-exported name → the module that defines it (tests/test_architecture.py reads
#: this table as imports of this package).
EXPORTS: dict[str, str] = {
    "PRESETS": "geometry.params",
    "DrumClutch": "geometry.params",
    "ParameterError": "geometry.validation",
    "Region": "geometry.section",
    "Section": "geometry.section",
    "build_section": "geometry.section",
    "preset": "geometry.params",
}

__all__ = sorted(EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in EXPORTS:
        raise AttributeError(f"module 'geometry' has no attribute {name!r}")
    return getattr(importlib.import_module(EXPORTS[name]), name)
