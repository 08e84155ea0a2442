"""The axisymmetric cross-section of one clutch: the region table for a batch of one.

``build_section`` evaluates ``geometry.regions.table`` at one design and gives each
rectangle as a ``Region`` (floats, metres), with the sheared films as ``Gap``/``FaceGap``
and the active zones as ``Zone``. The CAD revolves these regions, the analytic inertia
integrates them, the magnetic circuit and the FEM read their materials, gaps and zones
from them. Nothing else lays out a dimension (geometry/regions.py).

Coordinates: r ≥ 0 from the axis, z along the axis with z = 0 at the outer face of the
front (output-side) end cap; the output shaft sticks out towards z < 0.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

from geometry import regions as table
from geometry.materials import DEFAULT_CHOICE, MaterialChoice
from geometry.params import DrumClutch
from geometry.regions import OUTPUT_PARTS, PARTS, ZONES, Regions

Part = Literal["rotor", "shaft", "input", "housing", "coil", "fluid"]
__all__ = ["OUTPUT_PARTS", "PARTS", "FaceGap", "Gap", "Region", "Section", "Zone", "build_section"]


@dataclass(frozen=True)
class Region:
    """One r–z rectangle of a single part and material."""

    name: str
    part: str
    material: str
    r0: float
    r1: float
    z0: float
    z1: float
    #: "steel" (magnetic), "nonmagnetic", "coil" or "fluid" (``geometry.regions``)
    role: str = ""

    @property
    def area(self) -> float:
        return (self.r1 - self.r0) * (self.z1 - self.z0)


@dataclass(frozen=True)
class Gap:
    """A sheared cylindrical fluid gap between an output surface and an input surface.

    ``z0..z1`` is the wetted length where both walls face each other; the field-carrying
    part of it is its intersection with the active zones.
    """

    index: int
    r_inner: float
    r_outer: float
    z0: float
    z1: float
    inner_wall: str  # region name of the wall at r_inner
    outer_wall: str

    @property
    def width(self) -> float:
        return self.r_outer - self.r_inner

    @property
    def r_mean(self) -> float:
        return 0.5 * (self.r_inner + self.r_outer)


@dataclass(frozen=True)
class FaceGap:
    """An axial fluid film between an output face and an input face (disk-type shear)."""

    name: str
    r0: float
    r1: float
    height: float


@dataclass(frozen=True)
class Zone:
    """An active zone: the axial band where the coil's flux crosses the stack radially."""

    name: str
    z0: float
    z1: float

    @property
    def length(self) -> float:
        return self.z1 - self.z0


@dataclass(frozen=True)
class Section:
    """The labelled cross-section of one clutch."""

    clutch: DrumClutch
    regions: tuple[Region, ...]
    gaps: tuple[Gap, ...]
    faces: tuple[FaceGap, ...]
    zones: tuple[Zone, ...]
    densities: MappingProxyType  # material -> kg/m³
    #: the evaluated region table this section views (None for a hand-made section)
    table: Regions | None = None

    @property
    def materials(self) -> MaterialChoice:
        """The material of each part (the default for a hand-made section)."""
        return DEFAULT_CHOICE if self.table is None else self.table.materials

    def part(self, name: str) -> tuple[Region, ...]:
        return tuple(r for r in self.regions if r.part == name)

    def region(self, name: str) -> Region:
        for r in self.regions:
            if r.name == name:
                return r
        raise KeyError(name)

    def __iter__(self) -> Iterator[Region]:
        return iter(self.regions)

    @property
    def r_max(self) -> float:
        return max(r.r1 for r in self.regions)

    @property
    def z_min(self) -> float:
        return min(r.z0 for r in self.regions)

    @property
    def z_max(self) -> float:
        return max(r.z1 for r in self.regions)

    @property
    def envelope(self) -> tuple[float, float]:
        """(diameter, length) of the bounding cylinder, metres."""
        return 2 * self.r_max, self.z_max - self.z_min


def build_section(c: DrumClutch, materials: MaterialChoice = DEFAULT_CHOICE) -> Section:
    """The region table (geometry/regions.py) evaluated at one design made of ``materials``."""
    rg = table.evaluate(vars(c), c.n_drums, materials)
    regs = tuple(Region(sp.name, sp.part, sp.material, *rg.bounds(sp), sp.role) for sp in rg)
    gaps = tuple(Gap(int(sp.name[3:]), *rg.bounds(sp), *sp.walls) for sp in rg.films("cylinder"))
    faces = tuple(
        FaceGap(sp.name.removeprefix("film_"), r0, r1, z1 - z0)
        for sp in rg.films("face")
        for r0, r1, z0, z1 in [rg.bounds(sp)]
    )
    zones = tuple(Zone(name, rg.at[a], rg.at[b]) for name, a, b in ZONES)
    densities = {m: float(rg.density(m)) for m in {r.material for r in regs}}
    return Section(c, regs, gaps, faces, zones, MappingProxyType(densities), rg)
