"""What the workshop can hold: the process limits a design file states under ``[process]``.

Two numbers of the drum stack depend on how the clutch is made, not on its physics:

* the **smallest gap**. A film of nominal thickness g between an input and an output drum
  is thinner on one side by the two rotors' eccentricities and the diameters' tolerances.
  Each rotor's drum surface runs out by its total indicated runout R (TIR), an
  eccentricity of R/2, so the two rotors together can bring the surfaces R closer; each
  diameter's tolerance band T moves its surface by up to T/2, the two facing surfaces
  by T. The film's thinnest point is then g − (R + T). The rule kept here bounds the
  eccentricity ratio ε = (R + T)/g to ``MAX_ECCENTRICITY`` = 1/4: the mean of the drag's
  1/h over an eccentric film is 1/(g √(1 − ε²)) (∫ dθ/(1 + ε cos θ) = 2π/√(1 − ε²)
  [abramowitz-stegun]), so at ε = 1/4 the drag rises by 3.3 % and the thinnest film is
  3/4 of the nominal one. Hence ``min_gap = (R + T)/MAX_ECCENTRICITY``;
* the **smallest drum wall**, a number of the shop (how thin a steel sleeve can be turned
  or drawn and stay round).

Defaults and their sources (docs/optimize.md): runout 0.03 mm TIR, the assembled radial
runout of two deep-groove bearings of ISO 492's normal class at this size (inner ring
K_ia 10 µm, outer ring K_ea 15 µm) plus a drum turned in the same setting as its seat
[iso492]; tolerance 0.02 mm, ISO 286's grade IT7 on 18–30 mm diameters (21 µm), what a
lathe holds without grinding [iso286]; smallest wall 0.25 mm, the thinnest drum of the
paper's built clutch (its input drums, `geometry.params`'s paper preset) [lebel]. With
these the smallest gap is 0.2 mm, the lower edge of the optimiser's default range.
"""

from __future__ import annotations

from dataclasses import dataclass

from geometry.validation import check_range

#: Largest eccentricity ratio of a film that the rule accepts (module docstring).
MAX_ECCENTRICITY = 0.25


@dataclass(frozen=True)
class Process:
    """Process limits (SI, m): the drums' runout (TIR), the diameters' tolerance band and
    the thinnest wall the shop makes."""

    runout: float = 0.03e-3  # m TIR: two ISO 492 normal-class bearings + turning [iso492]
    tolerance: float = 0.02e-3  # m: IT7 on 18–30 mm [iso286]
    min_wall: float = 0.25e-3  # m: the paper clutch's input drums [lebel]

    def __post_init__(self) -> None:
        check_range("runout", self.runout, 0.0, 1e-3, " m")
        check_range("tolerance", self.tolerance, 0.0, 1e-3, " m")
        check_range("min_wall", self.min_wall, 0.0, 5e-3, " m")

    @property
    def min_gap(self) -> float:
        """m: the smallest film whose eccentricity ratio stays at MAX_ECCENTRICITY."""
        return (self.runout + self.tolerance) / MAX_ECCENTRICITY

    def lower_bounds(self) -> dict[str, float]:
        """The DrumClutch lengths this process bounds from below (m)."""
        return {"gap": self.min_gap, "drum_thickness": self.min_wall,
                "input_drum_thickness": self.min_wall}  # fmt: skip


#: ``[process]`` keys of a design file → (field, SI factor).
PROCESS_KEYS = {
    "runout_mm": ("runout", 1e-3),
    "tolerance_mm": ("tolerance", 1e-3),
    "min_wall_mm": ("min_wall", 1e-3),
}
