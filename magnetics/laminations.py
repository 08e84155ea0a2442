"""Laminated or slotted steel: the thickness the eddy currents are confined to in the core
and the shell, a design's input to the eddy lag (``magnetics.eddy_lag``), apart from it so
that a design loads without the circuit.
"""

from __future__ import annotations

from dataclasses import dataclass

from geometry.validation import check_range


@dataclass(frozen=True)
class Laminations:
    """Laminated or slotted steel parts: the thickness [m] the eddy currents are confined
    to (0: solid). ``shell``: poles and back iron; ``core``: the core."""

    core: float = 0.0
    shell: float = 0.0

    def __post_init__(self) -> None:
        for name in ("core", "shell"):
            check_range(name, getattr(self, name), 0.0, 0.1, " m")
