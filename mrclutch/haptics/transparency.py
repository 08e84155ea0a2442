"""Transparency in free motion: the force the hand feels when it moves the device with
no virtual environment rendered (K = 0), the backdrive force of the 2-DOF model.

With K = 0 the hand meets the passive device, Z_p = F_h/ẋ2 (Eq. 2, ``model.passive_
impedance``); for a sinusoidal hand motion x2 = X sin ωt the velocity amplitude is ωX, so
the force amplitude is |Z_p(jω)| ω X. Smaller is more transparent.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from geometry.validation import check_positive
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.model import passive_impedance

#: m, Hz: the free hand motion the backdrive force is quoted for: voluntary hand motion
#: lies below 2 Hz for unexpected and 2–5 Hz for periodic commands [brooks1990]; 10 mm is
#: a fifth of the paper's 50 mm workspace, a stroke well inside it.
HAND_AMPLITUDE = 10e-3
HAND_FREQUENCY = 2.0


def backdrive_force(
    p: HapticParams, amplitude: float = HAND_AMPLITUDE, frequency: float = HAND_FREQUENCY
) -> Any:
    """Force amplitude [N] at the hand for a free motion of ``amplitude`` [m] at
    ``frequency`` [Hz]: |Z_p(jω)| ω X (Eq. 2 at K = 0; module docstring). Vectorised over
    the designs of ``p``."""
    check_positive("amplitude", amplitude, " m")
    check_positive("frequency", frequency, " Hz")
    w = 2.0 * math.pi * frequency
    f = np.abs(passive_impedance(p, w)) * w * amplitude
    return f if np.ndim(f) else float(f)
