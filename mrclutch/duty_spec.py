"""How a design is used: ``Duty``, its ``[duty]`` table (issue 41).

What the duty does to the clutch (the thermal march, the hot figures, the fluid's life) is
``mrclutch.duty``'s; this module is apart from it so that a design (``mrclutch.design``)
loads without the thermal model and the network those figures need.
"""

from __future__ import annotations

from dataclasses import dataclass

from geometry.validation import check_range

#: The paper's duty rule for rated torque, 25 % [lebel] (docs/haptic.md): the default share
#: of the fluid's life at the duty torque.
ON_FRACTION = 0.25
#: s the current limit is held for the hot peak figures.
PEAK_TIME = 30.0


@dataclass(frozen=True)
class Duty:
    """How a design is used (SI): a torque held for a time, the peak hold, the life's duty."""

    torque: float = 0.0  # N·m held slipping (yield + drag); 0: no duty torque
    time: float = 60.0  # s the torque is held
    peak_time: float = PEAK_TIME  # s the current limit is held (hot peak figures)
    on_fraction: float = ON_FRACTION  # share of the life at the duty torque

    def __post_init__(self) -> None:
        check_range("torque", self.torque, 0.0, 1e3, " N·m")
        check_range("time", self.time, 0.0, 1e7, " s", lo_open=True)
        check_range("peak_time", self.peak_time, 0.0, 1e7, " s", lo_open=True)
        check_range("on_fraction", self.on_fraction, 0.0, 1.0)


#: design-file key → (field, factor to SI)
DUTY_KEYS: dict[str, tuple[str, float]] = {
    "torque_N_m": ("torque", 1.0),
    "time_s": ("time", 1.0),
    "peak_time_s": ("peak_time", 1.0),
    "on_fraction": ("on_fraction", 1.0),
}
