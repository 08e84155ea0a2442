"""The clutch's materials: their names (keyed once, here) and densities, each with its source.

Every region of the section (``geometry.regions``) names one of these materials; the
magnetic and rheological properties of the same names are in ``magnetics.materials``.
Sources: docs/references.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

STEEL = "steel_1018"  # the magnetic yoke and the drums' active zones
STAINLESS = "stainless_304"  # hub, shaft, end caps, sleeve, the drums' non-magnetic band
COIL = "coil"  # copper wire smeared with its bonding epoxy over the coil window
MRF = "mrf_132dg"  # the MR fluid

#: kg/m³. The coil's density depends on its fill: see ``coil_density``.
DENSITY: Mapping[str, float] = MappingProxyType(
    {
        STEEL: 7870.0,  # AISI 1018, FEMM 4.2 material library [femm-matlib] [materials]
        STAINLESS: 8000.0,  # AISI 304/316 [materials]
        MRF: 3050.0,  # LORD MRF-132DG datasheet, ≈ 3.05 g/cm³ [lord-mrf132dg]
    }
)
#: How a person reads each material's name, and its display colour (RGB 0..1): the STEP
#: assembly, the 3-D view and the section plot share them.
LABEL: Mapping[str, str] = MappingProxyType(
    {STEEL: "steel 1018", STAINLESS: "stainless 304", COIL: "coil (Cu + epoxy)", MRF: "MRF-132DG"}
)
COLOUR: Mapping[str, tuple[float, float, float]] = MappingProxyType(
    {
        STEEL: (0.45, 0.47, 0.52),
        STAINLESS: (0.80, 0.82, 0.85),
        COIL: (0.85, 0.45, 0.15),
        MRF: (0.15, 0.15, 0.18),
    }
)
DENSITY_COPPER = 8960.0  # [materials]
DENSITY_EPOXY = 1200.0  # bonding epoxy of an epoxy-bonded coil (typical 1.1–1.3 g/cm³)


def copper_fraction(turns: Any, wire_diameter: Any, window_area: Any) -> Any:
    """Fraction of the coil window that is copper (floats or arrays)."""
    return turns * (math.pi * wire_diameter**2 / 4) / window_area


def coil_density(turns: Any, wire_diameter: Any, window_area: Any) -> Any:
    """Smeared density of the epoxy-bonded coil: copper fraction of the window, rest epoxy
    (floats or arrays)."""
    frac = copper_fraction(turns, wire_diameter, window_area)
    return frac * DENSITY_COPPER + (1 - frac) * DENSITY_EPOXY
