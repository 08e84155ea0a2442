"""Mass and inertia about the axis.

Three methods (see README "Speed against accuracy"):

* ``analytic`` — exact integrals over the section's rectangles (revolved annuli):
  V = π (r1² − r0²) Δz,  I_z = ρ π (r1⁴ − r0⁴) Δz / 2  (thick-walled tube, any dynamics
  text, e.g. Meriam & Kraige, Appendix B). Exact for the axisymmetric body; blind to the
  non-axisymmetric hub features, which it reports rather than hides.
* ``mesh`` — trimesh on the tessellated CAD (tolerance-dependent, see geometry/cad.py).
* ``brep`` — OpenCascade volume integrals on the exact B-rep.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

from geometry.section import OUTPUT_PARTS, PARTS, Section


@dataclass(frozen=True)
class PartMass:
    """Mass (kg) and inertia about the clutch axis (kg·m²) of one part."""

    mass: float
    inertia: float


@dataclass(frozen=True)
class MassReport:
    """Per-part masses and inertias by one method, with the totals users ask for."""

    method: str
    parts: MappingProxyType  # part name -> PartMass
    notes: tuple[str, ...] = ()

    @property
    def rotor_inertia(self) -> float:
        """Inertia of the output assembly (rotor + output shaft), kg·m², fluid excluded."""
        return sum(self.parts[p].inertia for p in OUTPUT_PARTS if p in self.parts)

    @property
    def rotor_mass(self) -> float:
        return sum(self.parts[p].mass for p in OUTPUT_PARTS if p in self.parts)

    @property
    def clutch_mass(self) -> float:
        """Whole clutch with fluid and coil, kg."""
        return sum(pm.mass for pm in self.parts.values())


def analytic_mass(section: Section) -> MassReport:
    """Exact mass and inertia of every part of the axisymmetric section."""
    acc = {p: [0.0, 0.0] for p in PARTS}
    for reg in section.regions:
        rho = section.densities[reg.material]
        dz = reg.z1 - reg.z0
        acc[reg.part][0] += rho * math.pi * (reg.r1**2 - reg.r0**2) * dz
        # thick-walled tube about its axis: I = ρ π (r1⁴ − r0⁴) Δz / 2
        acc[reg.part][1] += rho * math.pi * (reg.r1**4 - reg.r0**4) * dz / 2
    notes: tuple[str, ...] = ()
    if section.clutch.hub_holes:
        notes = (
            f"analytic method does not see the {section.clutch.hub_holes} hub holes "
            "(non-axisymmetric); use mesh or brep",
        )
    parts = {p: PartMass(m, i) for p, (m, i) in acc.items()}
    return MassReport("analytic", MappingProxyType(parts), notes)
