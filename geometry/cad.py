"""build123d solids from the section: each part revolved from its r–z regions, plus hub holes.

build123d works in millimetres: the section (SI, metres) is converted at this edge only
(``MM_PER_M``) and every shape this module returns is in mm. build123d takes seconds to
import, so it is imported inside the functions, never at module level.

Two granularities are built from the same rectangles of ``geometry.section``:

* ``material_solids`` — one solid per (part, material): what the mass methods weigh
  (a part may mix materials, e.g. the rotor's stainless hub and band with steel drums);
* ``part_solids`` — one fused solid per part: what STEP/STL export and the assembly show.

The non-axisymmetric hub holes (``DrumClutch.hub_holes``) are cut from the rotor hub here;
this is the only place they exist.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from geometry.materials import COIL, COLOUR, DEFAULT_CHOICE, MRF, STAINLESS, STEEL, MaterialChoice
from geometry.section import PARTS, Region, Section, build_section
from geometry.validation import ParameterError, check_finite

if TYPE_CHECKING:  # pragma: no cover - typing only
    from geometry.params import DrumClutch

MM_PER_M = 1000.0

#: Display colours (RGB 0..1) by material, shared by the STEP assembly and the 3-D view.
MATERIAL_COLOURS = COLOUR
#: Colour of a part in the STEP assembly: its dominant material's colour (the defaults;
#: ``part_material`` for a design's own choice).
PART_MATERIAL: dict[str, str] = {
    "rotor": STEEL,
    "shaft": STAINLESS,
    "input": STEEL,
    "housing": STEEL,
    "coil": COIL,
    "fluid": MRF,
}


def part_material(part: str, materials: MaterialChoice = DEFAULT_CHOICE) -> str:
    """The dominant material of a part, whose colour the part takes in the STEP assembly."""
    return {"rotor": materials.drums, "shaft": materials.hub, "input": materials.drums,
            "housing": materials.shell, "coil": COIL, "fluid": materials.fluid}[part]  # fmt: skip


def _profile(regions: Iterable[Region]) -> Any:
    """2-D union (in the XZ plane, mm, x = r) of the regions' rectangles, internal edges removed."""
    from build123d import Face, Vector, Wire

    faces = []
    for reg in regions:
        r0, r1 = reg.r0 * MM_PER_M, reg.r1 * MM_PER_M
        z0, z1 = reg.z0 * MM_PER_M, reg.z1 * MM_PER_M
        pts = [Vector(r0, 0, z0), Vector(r1, 0, z0), Vector(r1, 0, z1), Vector(r0, 0, z1)]
        faces.append(Face(Wire.make_polygon(pts, close=True)))
    if len(faces) == 1:
        return faces[0]
    return faces[0].fuse(*faces[1:]).clean()


def revolve_regions(regions: Iterable[Region], angle_deg: float = 360.0) -> Any:
    """Solid (or compound of solids) swept by the regions about the z axis, mm."""
    from build123d import Axis, Compound, Solid

    profile = _profile(regions)
    solids = [Solid.revolve(f, angle_deg, Axis.Z) for f in profile.faces()]
    return solids[0] if len(solids) == 1 else Compound(solids)


def hub_hole_tool(clutch: DrumClutch) -> Any | None:
    """The hub holes as cylinders through the hub (mm), or None without holes."""
    if not clutch.hub_holes:
        return None
    from build123d import Compound, Plane, Solid

    s = build_section(clutch)
    hub = s.region("hub")
    # a little longer than the hub so the cut leaves no skin on either face
    z0, z1 = hub.z0 * MM_PER_M - 0.1, hub.z1 * MM_PER_M + 0.1
    r_h = clutch.hub_hole_pitch_radius * MM_PER_M
    rad = clutch.hub_hole_diameter * MM_PER_M / 2
    cyls = []
    for k in range(clutch.hub_holes):
        a = 2 * math.pi * (k + 0.5) / clutch.hub_holes  # off the revolve seam at angle 0
        plane = Plane(origin=(r_h * math.cos(a), r_h * math.sin(a), z0), z_dir=(0, 0, 1))
        cyls.append(Solid.make_cylinder(rad, z1 - z0, plane))
    return Compound(cyls)


def material_solids(
    clutch: DrumClutch, section: Section | None = None, angle_deg: float = 360.0
) -> dict[tuple[str, str], Any]:
    """One solid per (part, material), mm, with the hub holes cut from the rotor hub."""
    s = section if section is not None else build_section(clutch)
    groups: dict[tuple[str, str], list[Region]] = {}
    for reg in s.regions:
        groups.setdefault((reg.part, reg.material), []).append(reg)
    tool = hub_hole_tool(clutch)
    hub_key = (s.region("hub").part, s.region("hub").material)
    out: dict[tuple[str, str], Any] = {}
    for key, regs in groups.items():
        shape = revolve_regions(regs, angle_deg)
        if tool is not None and key == hub_key:
            shape = shape - tool
        out[key] = shape
    return out


def part_solids(
    clutch: DrumClutch, section: Section | None = None, angle_deg: float = 360.0
) -> dict[str, Any]:
    """One solid per part (all its materials fused), mm, hub holes cut; order of PARTS."""
    s = section if section is not None else build_section(clutch)
    tool = hub_hole_tool(clutch)
    out: dict[str, Any] = {}
    for part in PARTS:
        regs = s.part(part)
        if not regs:
            continue
        shape = revolve_regions(regs, angle_deg)
        if tool is not None and part == s.region("hub").part:
            shape = shape - tool
        out[part] = shape
    return out


def solid_label(part: str, material: str) -> str:
    """STEP product name of one material's solid inside a part that mixes materials (letters,
    digits and ``_`` only: the STEP writer turns other characters into ``_``)."""
    return f"{part}_{material}"


def assembly(
    clutch: DrumClutch,
    parts: dict[str, Any] | None = None,
    materials: dict[tuple[str, str], Any] | None = None,
    choice: MaterialChoice = DEFAULT_CHOICE,
) -> Any:
    """A build123d Compound whose children are the parts, labelled and coloured.

    With ``materials`` (``material_solids``), a part that mixes materials becomes a
    sub-assembly of one solid per material, labelled ``solid_label(part, material)``, so
    the file says what each solid is made of (``geometry.export`` writes the densities).
    """
    from build123d import Color, Compound

    parts = parts if parts is not None else part_solids(clutch)
    children = []
    for name, shape in parts.items():
        mats = [(m, s) for (p, m), s in (materials or {}).items() if p == name]
        if len(mats) > 1:
            subs = []
            for material, sub in mats:
                sub.label = solid_label(name, material)
                sub.color = Color(*MATERIAL_COLOURS[material])
                subs.append(sub)
            shape = Compound(children=subs)
        shape.label = name
        shape.color = Color(*MATERIAL_COLOURS[part_material(name, choice)])
        children.append(shape)
    return Compound(children=children, label="mr_drum_clutch")


def brep_volume_mm3(shape: Any) -> float:
    """Exact B-rep volume (mm³) by OpenCascade's volume integrals."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape.wrapped, props)
    return float(props.Mass())


#: Finest chord height relative to the clutch's size: 1e-4 already gives ~280 segments per
#: circle and a volume error ~1e-4 (chord error h/R); finer only multiplies the triangles
#: (``--tolerance-mm 1e-6`` on the paper clutch was killed at 24 GB).
MIN_RELATIVE_TOLERANCE = 1e-4
#: Coarsest chord height relative to the clutch's size: up to here the angular tolerance
#: (0.5 rad) bounds the facets and the paper clutch's parts keep their volume to 1 %;
#: far beyond, the facets of one wall cross the opposite one (``--tolerance-mm 100`` lost
#: 36 % of the shaft).
MAX_RELATIVE_TOLERANCE = 0.02


def clutch_size(clutch: DrumClutch) -> float:
    """The clutch's largest extent (m): outer diameter or overall length."""
    return max(2 * clutch.outer_radius, clutch.overall_length)


def check_tolerance(name: str, tolerance: float, clutch: DrumClutch, scale: float = 1.0) -> float:
    """A chord height ``tolerance`` (m) that is finite, > 0 and within MIN_RELATIVE_TOLERANCE
    … MAX_RELATIVE_TOLERANCE × the clutch's size; the message names ``name`` in the caller's
    unit (value × ``scale``: 1e3 for an ``_mm`` option)."""
    unit = " mm" if scale == 1e3 else " m"
    check_finite(name, tolerance * scale, unit)
    size = clutch_size(clutch)
    floor = MIN_RELATIVE_TOLERANCE * size
    ceiling = MAX_RELATIVE_TOLERANCE * size
    if not tolerance >= floor:
        raise ParameterError(
            f"{name} = {tolerance * scale:.6g}{unit}: must be >= {floor * scale:.3g}{unit} "
            f"({MIN_RELATIVE_TOLERANCE:g} × the clutch's size {size * scale:.4g}"
            f"{unit}; a finer mesh only multiplies the triangles and the memory)"
        )
    if not tolerance <= ceiling:
        raise ParameterError(
            f"{name} = {tolerance * scale:.6g}{unit}: must be <= {ceiling * scale:.3g}{unit} "
            f"({MAX_RELATIVE_TOLERANCE:g} × the clutch's size {size * scale:.4g}{unit}; a "
            f"coarser mesh loses the thin walls and the parts' volume)"
        )
    return tolerance


def tessellate(shape: Any, tolerance_mm: float, angular_tolerance: float = 0.5) -> tuple:
    """Triangulate ``shape`` with an ABSOLUTE chord height ``tolerance_mm`` (mm).

    build123d's own ``tessellate``/``export_stl`` pass ``isRelative=True`` to BRepMesh (the
    deflection then scales with each edge's size) and keep a triangulation computed earlier
    at another tolerance; here any old triangulation is cleared first and the deflection is
    absolute, so the chord-height theory applies. Returns (vertices (n, 3) mm, faces (m, 3)).
    """
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    BRepTools.Clean_s(shape.wrapped)
    BRepMesh_IncrementalMesh(shape.wrapped, tolerance_mm, False, angular_tolerance, True)
    verts: list = []
    tris: list = []
    offset = 0
    exp = TopExp_Explorer(shape.wrapped, TopAbs_FACE)
    while exp.More():
        face = TopoDS.Face(exp.Current())
        exp.Next()
        loc = TopLoc_Location()
        poly = BRep_Tool.Triangulation_s(face, loc)
        if poly is None:
            continue
        trsf = loc.Transformation()
        n = poly.NbNodes()
        pts = [poly.Node(i).Transformed(trsf) for i in range(1, n + 1)]
        verts.append(np.array([(p.X(), p.Y(), p.Z()) for p in pts], dtype=float).reshape(-1, 3))
        t = np.array([poly.Triangle(i).Get() for i in range(1, poly.NbTriangles() + 1)], int)
        t = t.reshape(-1, 3) - 1 + offset
        if face.Orientation() == TopAbs_REVERSED:
            t = t[:, [0, 2, 1]]
        tris.append(t)
        offset += n
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=int)
    return np.concatenate(verts), np.concatenate(tris)
