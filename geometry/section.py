"""The axisymmetric cross-section: labelled r–z rectangles, the single source of truth.

The CAD revolves these regions, the analytic inertia integrates them, the magnetic
circuit and the FEM read their materials, gaps and zones from them. Nothing else lays
out a dimension.

Coordinates: r ≥ 0 from the axis, z along the axis with z = 0 at the outer face of the
front (output-side) end cap; the output shaft sticks out towards z < 0.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

from geometry.params import DrumClutch

Part = Literal["rotor", "shaft", "input", "housing", "coil", "fluid"]
PARTS: tuple[str, ...] = ("rotor", "shaft", "input", "housing", "coil", "fluid")
#: Parts that turn with the output (what the haptic device feels as rotor inertia).
OUTPUT_PARTS: tuple[str, ...] = ("rotor", "shaft")

# Densities (kg/m³), each with its source.
DENSITY_STEEL = 7870.0  # AISI 1018, FEMM 4.2 matlib / shared/reference/materials.md
DENSITY_STAINLESS = 8000.0  # AISI 304/316, shared/reference/materials.md
DENSITY_COPPER = 8960.0  # shared/reference/materials.md
DENSITY_EPOXY = 1200.0  # bonding epoxy of an epoxy-bonded coil (typical 1.1–1.3 g/cm³)
DENSITY_MRF = 3050.0  # LORD MRF-132DG datasheet, ≈ 3.05 g/cm³ (materials.md)


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


def coil_density(c: DrumClutch) -> float:
    """Smeared density of the epoxy-bonded coil: copper fraction of the window, rest epoxy."""
    copper_area = c.coil_turns * 3.141592653589793 * c.wire_diameter**2 / 4
    frac = copper_area / c.coil_window_area
    return frac * DENSITY_COPPER + (1 - frac) * DENSITY_EPOXY


def build_section(c: DrumClutch) -> Section:
    """Lay out every region of ``c`` in the r–z plane (see module docstring)."""
    t, cl, h = c.end_cap_thickness, c.end_clearance, c.hub_thickness
    z_hub0 = t + cl
    zs0 = z_hub0 + h  # hub back face: stack starts
    zA0 = zs0 + cl
    zA1 = zA0 + c.zone_length
    zB0 = zA1 + c.band_length
    zB1 = zB0 + c.zone_length
    zs1 = zB1 + cl  # back cap inner face
    R = c.outer_radius
    rp = c.pole_radius

    steel, stainless = "steel_1018", "stainless_304"
    regs: list[Region] = []

    def add(name: str, part: str, mat: str, r0: float, r1: float, z0: float, z1: float) -> None:
        regs.append(Region(name, part, mat, r0, r1, z0, z1))

    # Output side: shaft, hub, drums (steel in the zones, stainless band between).
    add("shaft", "shaft", stainless, 0.0, c.shaft_radius, -c.shaft_length, zs0)
    add("hub", "rotor", stainless, c.shaft_radius, c.hub_outer_radius, z_hub0, zs0)
    for i, (a, b) in enumerate(c.drum_radii_out, start=1):
        add(f"out{i}_A", "rotor", steel, a, b, zs0, zA1)
        add(f"out{i}_band", "rotor", stainless, a, b, zA1, zB0)
        add(f"out{i}_B", "rotor", steel, a, b, zB0, zB1)
    # Input drums, fixed to the back cap.
    for i, (a, b) in enumerate(c.drum_radii_in, start=1):
        add(f"in{i}_A", "input", steel, a, b, zA0, zA1)
        add(f"in{i}_band", "input", stainless, a, b, zA1, zB0)
        add(f"in{i}_B", "input", steel, a, b, zB0, zs1)
    # Housing: core, shell (poles + back iron over the coil), sleeve, end caps.
    add("core", "housing", steel, 0.0, c.core_radius, zA0, zs1)
    add("shell_A", "housing", steel, rp, R, t, zA1)
    add("shell_back", "housing", steel, c.coil_outer_radius, R, zA1, zB0)
    add("shell_B", "housing", steel, rp, R, zB0, zs1)
    add("sleeve", "housing", stainless, rp, c.coil_inner_radius, zA1, zB0)
    add("cap_front", "housing", stainless, c.shaft_radius + c.shaft_bore_clearance, R, 0.0, t)
    add("cap_back", "housing", stainless, 0.0, R, zs1, zs1 + t)
    add("coil", "coil", "coil", c.coil_inner_radius, c.coil_outer_radius, zA1, zB0)

    # Sheared cylindrical gaps: walls alternate core|out1|in1|out2|…|outN|shell.
    walls: list[tuple[str, float, float, float]] = [("core", c.core_radius, zA0, zs1)]
    for i in range(c.n_drums):
        a, b = c.drum_radii_out[i]
        walls.append((f"out{i + 1}", a, zs0, zB1))
        walls.append((f"out{i + 1}", b, zs0, zB1))
        if i < c.n_drums - 1:
            a, b = c.drum_radii_in[i]
            walls.append((f"in{i + 1}", a, zA0, zs1))
            walls.append((f"in{i + 1}", b, zA0, zs1))
    walls.append(("shell", rp, t, zs1))
    gaps: list[Gap] = []
    for k in range(0, len(walls), 2):
        (n0, r0, a0, a1), (n1, r1, b0, b1) = walls[k], walls[k + 1]
        g = Gap(k // 2, r0, r1, max(a0, b0), min(a1, b1), n0, n1)
        gaps.append(g)
        add(f"gap{g.index}", "fluid", "mrf_132dg", g.r_inner, g.r_outer, g.z0, g.z1)

    # Axial films (disk-type shear) between output faces and input faces.
    faces = [
        FaceGap("hub_front", c.shaft_radius + c.shaft_bore_clearance, c.hub_outer_radius, cl),
        FaceGap("hub_core", 0.0, c.core_radius, cl),
    ]
    faces += [FaceGap(f"in{i + 1}_tip", a, b, cl) for i, (a, b) in enumerate(c.drum_radii_in)]
    faces += [FaceGap(f"out{i + 1}_tip", a, b, cl) for i, (a, b) in enumerate(c.drum_radii_out)]

    # Whatever else of the cavity (r < rp, t < z < zs1) no solid or gap holds is fluid.
    regs += _fill(regs, 0.0, rp, t, zs1, "fluid", "mrf_132dg")

    densities = {
        steel: DENSITY_STEEL,
        stainless: DENSITY_STAINLESS,
        "coil": coil_density(c),
        "mrf_132dg": DENSITY_MRF,
    }
    zones = (Zone("A", zA0, zA1), Zone("B", zB0, zB1))
    return Section(c, tuple(regs), tuple(gaps), tuple(faces), zones, MappingProxyType(densities))


def _fill(
    occupied: list[Region], r0: float, r1: float, z0: float, z1: float, part: str, mat: str
) -> list[Region]:
    """Cover the free part of the rectangle [r0,r1]×[z0,z1] with rectangles (row-merged)."""
    inside = [g for g in occupied if g.r1 > r0 and g.r0 < r1 and g.z1 > z0 and g.z0 < z1]
    rs = sorted(
        {
            r0,
            r1,
            *(min(max(g.r0, r0), r1) for g in inside),
            *(min(max(g.r1, r0), r1) for g in inside),
        }
    )
    zs = sorted(
        {
            z0,
            z1,
            *(min(max(g.z0, z0), z1) for g in inside),
            *(min(max(g.z1, z0), z1) for g in inside),
        }
    )
    out: list[Region] = []
    for j in range(len(zs) - 1):
        za, zb = zs[j], zs[j + 1]
        if zb - za <= 0:
            continue
        zm = 0.5 * (za + zb)
        run_start: float | None = None
        for i in range(len(rs) - 1):
            ra, rb = rs[i], rs[i + 1]
            rm = 0.5 * (ra + rb)
            free = rb > ra and not any(g.r0 < rm < g.r1 and g.z0 < zm < g.z1 for g in inside)
            if free and run_start is None:
                run_start = ra
            if not free and run_start is not None:
                out.append(Region(f"{part}_{len(out)}", part, mat, run_start, ra, za, zb))
                run_start = None
        if run_start is not None:
            out.append(Region(f"{part}_{len(out)}", part, mat, run_start, rs[-1], za, zb))
    return out
