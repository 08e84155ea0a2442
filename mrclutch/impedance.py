"""What a haptic figure draws (``compare --plot``, the report's haptic figure): the closed
loop's and the passive device's impedance magnitude over the rendering band, the rendering
area between them, the full-model bandwidth, and the effective stiffness and damping, all
from mrclutch.haptics.model (the paper's Eq. 1-4). The figure (mrclutch/cli/plots/haptic.py)
draws these arrays.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mrclutch.haptics.model import (
    BAND_HZ,
    bandwidth,
    closed_loop_impedance,
    effective_impedance,
    passive_impedance,
    rendering_area,
)

#: Points of a figure's frequency axis (log-spaced over the band).
POINTS = 1500


def band_frequencies(band: tuple[float, float] | None = None) -> np.ndarray:
    """The figure's frequencies (Hz): POINTS log-spaced over ``band`` (None: BAND_HZ)."""
    band = BAND_HZ if band is None else band
    return np.logspace(np.log10(band[0]), np.log10(band[1]), POINTS)


def impedance_curves(p: Any, K: float, f: np.ndarray,
                     band: tuple[float, float] | None = None) -> dict[str, Any]:  # fmt: skip
    """At the frequencies ``f`` (Hz) of HapticParams ``p`` rendering a spring ``K`` (N/m):
    ``closed`` |Z| of the closed loop and ``passive`` |Z| of the device (Eq. 2), N·s/m;
    ``area`` the rendering area over ``band`` (dB·decade), ``bandwidth`` (Hz, full model),
    ``stiffness`` k_eff = Re(jωZ) (N/m) and ``damping`` b_eff = Re Z (N·s/m)."""
    band = BAND_HZ if band is None else band
    w = 2 * np.pi * f
    eff = effective_impedance(p, K, w)
    return {
        "closed": np.abs(closed_loop_impedance(p, K, w)),
        "passive": np.abs(passive_impedance(p, w)),
        "area": rendering_area(p, K, band),
        "bandwidth": float(bandwidth(p, K)),
        "stiffness": eff.stiffness,
        "damping": eff.damping,
    }
