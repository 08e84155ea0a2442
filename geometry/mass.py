"""Mass and inertia about the axis.

Three methods (see README "Speed against accuracy"):

* ``analytic`` — exact integrals over the section's rectangles (revolved annuli):
  V = π (r1² − r0²) Δz,  I_z = ρ π (r1⁴ − r0⁴) Δz / 2  (thick-walled tube, any dynamics
  text, e.g. [meriam-kraige] Appendix B). Exact for the axisymmetric body; blind to the
  non-axisymmetric hub features, which it reports rather than hides.
* ``mesh`` — trimesh on the tessellated CAD (tolerance-dependent, see geometry/cad.py),
  guarded: a mesh that is not closed is refused, and the chord-height error is estimated
  by comparing the mesh with one at half the tolerance (Richardson: the error falls
  linearly with the chord height) and the tolerance refined until it is below ``rtol``.
* ``brep`` — OpenCascade volume integrals on the exact B-rep (``BRepGProp``).

``mesh_mass``/``brep_mass`` take a clutch (its hub holes included); ``weigh_shape`` and
``weigh_mesh`` weigh any solid or closed mesh about an axis through the origin.
The analytic method is one function of the region table (``part_sums``): ``analytic_mass``
applies it to one section, ``analytic_batch`` to arrays of designs (sweeps).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.cad import check_tolerance, material_solids, tessellate
from geometry.materials import DEFAULT_CHOICE, MaterialChoice
from geometry.params import DrumClutch, broadcast_fields, valid
from geometry.regions import OUTPUT_PARTS, PARTS
from geometry.section import Section, build_section
from geometry.validation import ParameterError, check_positive

if TYPE_CHECKING:  # pragma: no cover - typing only
    import trimesh

MM = 1e-3  # metres per millimetre: CAD shapes (geometry/cad.py) are in mm
AXES: dict[str, tuple[float, float, float]] = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}


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


def tube(rho: Any, r0: Any, r1: Any, dz: Any) -> tuple[Any, Any]:
    """Mass and axial inertia of a revolved rectangle (thick-walled tube; any dynamics text,
    e.g. [meriam-kraige] Appendix B): ρπ(r1²−r0²)Δz and ρπ(r1⁴−r0⁴)Δz/2."""
    a0, a1 = r0 * r0, r1 * r1
    m = rho * np.pi * (a1 - a0) * dz
    return m, m * (a1 + a0) / 2


def part_sums(
    rects: Iterable[tuple[str, Any, Any, Any, Any, Any]],
) -> dict[str, tuple[Any, Any]]:
    """(mass, inertia) of every part from its rectangles (part, ρ, r0, r1, z0, z1): floats
    for one design or arrays for many — the analytic method, written once."""
    acc: dict[str, list[Any]] = {p: [0.0, 0.0] for p in PARTS}
    for part, rho, r0, r1, z0, z1 in rects:
        m, j = tube(rho, r0, r1, z1 - z0)
        acc[part][0] = acc[part][0] + m
        acc[part][1] = acc[part][1] + j
    return {p: (m, j) for p, (m, j) in acc.items()}


def analytic_mass(section: Section) -> MassReport:
    """Exact mass and inertia of every part of the axisymmetric section."""
    dens = section.densities
    sums = part_sums((r.part, dens[r.material], r.r0, r.r1, r.z0, r.z1) for r in section.regions)
    notes: tuple[str, ...] = ()
    if section.clutch.hub_holes:
        notes = (
            f"analytic method does not see the {section.clutch.hub_holes} hub holes "
            "(non-axisymmetric); use mesh or brep",
        )
    parts = {p: PartMass(float(m), float(i)) for p, (m, i) in sums.items()}
    return MassReport("analytic", MappingProxyType(parts), notes)


def _report(method: str, acc: Mapping[str, list[float]], notes: tuple[str, ...]) -> MassReport:
    parts = {p: PartMass(m, i) for p, (m, i) in acc.items()}
    return MassReport(method, MappingProxyType(parts), notes)


def _hole_note(c: DrumClutch) -> tuple[str, ...]:
    return (f"includes the {c.hub_holes} hub holes",) if c.hub_holes else ()


# ---- B-rep ------------------------------------------------------------------------------
def weigh_shape(shape: Any, density: float, axis: str = "z") -> PartMass:
    """Exact mass (kg) and inertia about ``axis`` through the origin (kg·m²) of a mm solid."""
    from OCP.BRepGProp import BRepGProp
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape.wrapped, props)  # OCC Gauss integration on the B-rep
    j = props.MomentOfInertia(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(*AXES[axis])))
    return PartMass(density * props.Mass() * MM**3, density * j * MM**5)


#: Where ``brep_mass`` takes its result from inside ``brep_mass_from`` (None: computed here).
_BREP_SOURCE: ContextVar[Callable[[DrumClutch, MaterialChoice], MassReport | None] | None] = (
    ContextVar("brep_source", default=None)
)


@contextmanager
def brep_mass_from(
    source: Callable[[DrumClutch, MaterialChoice], MassReport | None],
) -> Iterator[None]:
    """Inside, ``brep_mass(clutch, materials=m)`` (no ``solids``) returns
    ``source(clutch, m)`` when that is a MassReport, and computes it here when None: the
    same ``brep_mass`` run elsewhere, e.g. the design report's CAD process, which imports
    build123d while the report draws (issue 40)."""
    token = _BREP_SOURCE.set(source)
    try:
        yield
    finally:
        _BREP_SOURCE.reset(token)


def brep_mass(
    clutch: DrumClutch,
    solids: Mapping[tuple[str, str], Any] | None = None,
    materials: MaterialChoice = DEFAULT_CHOICE,
) -> MassReport:
    """Mass and inertia of every part from OpenCascade's exact volume integrals (each
    solid at its chosen material's density); inside ``brep_mass_from``, its source's."""
    source = _BREP_SOURCE.get()
    if solids is None and source is not None:
        known = source(clutch, materials)
        if known is not None:
            return known
    s = build_section(clutch, materials)
    solids = solids if solids is not None else material_solids(clutch, s)
    acc = {p: [0.0, 0.0] for p in PARTS}
    for (part, material), shape in solids.items():
        pm = weigh_shape(shape, s.densities[material])
        acc[part][0] += pm.mass
        acc[part][1] += pm.inertia
    return _report("brep", acc, _hole_note(clutch))


# ---- mesh -------------------------------------------------------------------------------
def check_mesh(mesh: trimesh.Trimesh, name: str) -> None:
    """Refuse a mesh whose volume integrals would be wrong: open, inverted or degenerate."""
    if len(mesh.faces) == 0:
        raise ParameterError(f"mesh of {name}: empty tessellation")
    if not mesh.is_watertight:
        raise ParameterError(f"mesh of {name}: not watertight (open edges); cannot weigh it")
    if not mesh.is_winding_consistent:
        raise ParameterError(f"mesh of {name}: inconsistent triangle winding; cannot weigh it")
    if mesh.volume <= 0:
        raise ParameterError(f"mesh of {name}: volume {mesh.volume:.3g} <= 0 (inside out)")


def winding_number(triangles: np.ndarray, points: np.ndarray, block: int = 4096) -> np.ndarray:
    """Generalised winding number of closed triangle soup ``triangles`` (F, 3, 3) at
    ``points`` (P, 3): Σ solid angles / 4π (Van Oosterom & Strackee 1983), 1 inside an
    outward-oriented closed shell, 0 outside, ½ on its surface."""
    out = np.zeros(len(points))
    for k in range(0, len(triangles), block):
        t = triangles[k : k + block]
        a, b, c = (t[None, :, i, :] - points[:, None, :] for i in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        num = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
        dot = lambda x, y: np.einsum("pfi,pfi->pf", x, y)  # noqa: E731
        den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la
        out += 2.0 * np.arctan2(num, den).sum(axis=1)
    return out / (4.0 * np.pi)


def check_shells(mesh: trimesh.Trimesh, name: str, samples: int = 256) -> None:
    """Refuse a mesh whose closed shells overlap (two cubes meshed into one STL): its
    divergence-theorem volume counts the overlap twice. Each outward shell's vertices,
    edge midpoints and face centroids (up to ``samples``) are tested against the other
    shells by their winding number; a cavity (an inward shell, negative volume) is a
    valid solid and is not tested. Overlaps no sample point reaches (two bars crossing
    without a vertex inside the other) pass: a bound of this check."""
    shells = mesh.split(only_watertight=False) if len(mesh.faces) else []
    if len(shells) < 2:
        return
    rng = np.random.default_rng(0)
    for i, sh in enumerate(shells):
        if sh.volume <= 0:
            continue
        others = [o for j, o in enumerate(shells) if j != i]
        tri = np.concatenate([o.triangles for o in others])
        edges = sh.vertices[sh.edges_unique].mean(axis=1)
        pts = np.concatenate([sh.vertices, edges, sh.triangles_center])
        if len(pts) > samples:
            pts = pts[rng.choice(len(pts), samples, replace=False)]
        w = winding_number(tri, pts)
        if np.any(w > 0.75):
            raise ParameterError(
                f"mesh of {name}: self-intersecting: {len(shells)} closed shells and shell "
                f"{i + 1} lies partly inside another, so its volume would count the overlap "
                "twice; merge them into one solid (a boolean union) before weighing"
            )


def weigh_mesh(
    mesh: trimesh.Trimesh, density: float, axis: str = "z", scale: float = MM
) -> PartMass:
    """Mass and inertia about ``axis`` through the origin of a closed mesh (units × scale = m)."""
    props = mesh.mass_properties  # divergence theorem over the triangles [mirtich1996]
    e = np.asarray(AXES[axis], float)
    c = np.asarray(props["center_mass"])
    vol = float(props["volume"])
    # parallel-axis theorem: I_axis = eᵀ I_cm e + V (|c|² − (c·e)²)   (unit density)
    j = float(e @ np.asarray(props["inertia"]) @ e) + vol * (c @ c - (c @ e) ** 2)
    return PartMass(density * vol * scale**3, density * j * scale**5)


def _tri(shape: Any, tol_mm: float, ang: float) -> trimesh.Trimesh:
    import trimesh

    v, f = tessellate(shape, tol_mm, ang)
    return trimesh.Trimesh(v, f, process=True)


def thinnest_feature(clutch: DrumClutch) -> float:
    """Smallest wall, gap or hole dimension of the clutch (m): the mesh must resolve it."""
    s = build_section(clutch)
    t = min(min(r.r1 - r.r0, r.z1 - r.z0) for r in s.regions)
    if clutch.hub_holes:
        t = min(t, clutch.hub_hole_diameter / 2)
    return t


def mesh_mass(
    clutch: DrumClutch,
    tolerance: float = 1e-5,
    *,
    angular_tolerance: float = 0.5,
    rtol: float = 5e-3,
    guard: bool = True,
    max_refinements: int = 8,
    solids: Mapping[tuple[str, str], Any] | None = None,
    materials: MaterialChoice = DEFAULT_CHOICE,
) -> MassReport:
    """Mass and inertia of every part from a triangle mesh of chord height ``tolerance`` (m).

    With ``guard`` (default): the tolerance is first lowered to half the thinnest feature
    (walls thinner than the chord height can be crossed by the facets of the opposite wall);
    every mesh must be closed (``check_mesh``); and each solid is re-meshed at half the
    tolerance until the two inertias differ by less than ``rtol`` (the difference estimates
    the finer mesh's error, since the error falls linearly with the chord height). Every
    refinement is written in the report's notes; a solid that does not converge within
    ``max_refinements`` halvings raises ParameterError. ``guard=False`` returns the raw
    numbers at ``tolerance`` (for benchmarks and to show what goes wrong).
    """
    check_positive("tolerance", tolerance, " m")
    check_tolerance("tolerance", tolerance, clutch)
    check_positive("angular_tolerance", angular_tolerance, " rad")
    s = build_section(clutch, materials)
    solids = solids if solids is not None else material_solids(clutch, s)
    notes = list(_hole_note(clutch))
    tol = tolerance
    if guard:
        t_min = thinnest_feature(clutch)
        if tol > t_min / 2:
            notes.append(
                f"tolerance refined from {tol * 1e3:.4g} mm to {t_min / 2 * 1e3:.4g} mm "
                f"(half the thinnest feature, {t_min * 1e3:.4g} mm)"
            )
            tol = t_min / 2
    acc = {p: [0.0, 0.0] for p in PARTS}
    for (part, material), shape in solids.items():
        name = f"{part}/{material}"
        rho = s.densities[material]
        mesh = _tri(shape, tol / MM, angular_tolerance)
        if guard:
            check_mesh(mesh, name)
        pm = weigh_mesh(mesh, rho)
        if guard:
            pm, used, est = _converge(
                shape, name, rho, mesh, pm, tol, angular_tolerance, rtol, max_refinements
            )
            if used < tol / 2:
                notes.append(
                    f"{name}: refined to {used * 1e3:.4g} mm (estimated inertia error {est:.2g})"
                )
        acc[part][0] += pm.mass
        acc[part][1] += pm.inertia
    return _report("mesh", acc, tuple(notes))


def _converge(
    shape: Any,
    name: str,
    rho: float,
    mesh: trimesh.Trimesh,
    pm: PartMass,
    tol: float,
    ang: float,
    rtol: float,
    max_refinements: int,
) -> tuple[PartMass, float, float]:
    """Halve the chord height until two successive meshes agree to ``rtol``.

    Returns the finer mesh's PartMass, its tolerance (m) and the estimated relative error.
    """
    planar = all(f.geom_type.name == "PLANE" for f in shape.faces())
    n_faces = len(mesh.faces)
    for _ in range(max_refinements):
        tol /= 2
        fine = _tri(shape, tol / MM, ang)
        check_mesh(fine, name)
        pf = weigh_mesh(fine, rho)
        same = len(fine.faces) == n_faces and pf.inertia == pm.inertia
        if same and planar:  # a planar solid is meshed exactly at any tolerance
            return pf, tol, 0.0
        # identical curved meshes (the angular limit governs) say nothing about the error
        est = max(abs(pf.inertia - pm.inertia) / abs(pf.inertia), abs(pf.mass - pm.mass) / pf.mass)
        if not same and est <= rtol:
            return pf, tol, est
        pm, n_faces = pf, len(fine.faces)
    raise ParameterError(
        f"mesh of {name}: inertia not converged to rtol = {rtol:g} after {max_refinements} "
        f"halvings of the tolerance (down to {tol * 1e3:.3g} mm); use the brep method"
    )


# ---- the analytic method on arrays of designs --------------------------------------------------
def analytic_batch(fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
    """``analytic_mass(build_section(DrumClutch(**design)))`` for arrays of designs at once.

    ``fields`` maps DrumClutch field names (SI) to arrays that broadcast together; missing
    fields take the DrumClutch defaults. Returns arrays of shape S: ``rotor_inertia``
    (kg·m²), ``rotor_mass``, ``clutch_mass`` (kg), ``diameter``, ``length`` (m, envelope),
    ``valid`` (passes DrumClutch's validation; the other entries of invalid designs are
    NaN), and ``mass_<part>`` / ``inertia_<part>`` for every part: ``part_sums`` over the
    region table, one batch per drum count.
    """
    p = broadcast_fields(fields)
    size = p["n_drums"].size
    if size <= BATCH_CHUNK:
        return _analytic_chunk(p)
    # Chunks of < 128 kB arrays: glibc recycles such temporaries from its heap, while each
    # larger one is a fresh mmap whose pages fault in on first touch (the dominant cost on
    # 10⁵ designs; measured in benchmarks/bench_geometry.py).
    out: dict[str, np.ndarray] = {}
    for i in range(0, size, BATCH_CHUNK):
        part = _analytic_chunk({k: v[i : i + BATCH_CHUNK] for k, v in p.items()})
        for k, v in part.items():
            if k not in out:
                out[k] = np.empty(size, dtype=v.dtype)
            out[k][i : i + BATCH_CHUNK] = v
    return out


#: Designs per chunk of ``analytic_batch``: 16000 float64 = 125 kB < glibc's 128 kB mmap
#: threshold.
BATCH_CHUNK = 16000


def region_mass(rg: regions.Regions) -> dict[str, Any]:
    """Per-part mass and inertia, totals and envelope of the designs of one region table."""
    sums = part_sums((sp.part, rg.density(sp.material), *rg.bounds(sp)) for sp in rg)
    res: dict[str, Any] = {}
    for part, (m, j) in sums.items():
        res[f"mass_{part}"], res[f"inertia_{part}"] = m, j
    res["rotor_inertia"] = sum(sums[q][1] for q in OUTPUT_PARTS)
    res["rotor_mass"] = sum(sums[q][0] for q in OUTPUT_PARTS)
    res["clutch_mass"] = sum(sums[q][0] for q in PARTS)
    res["diameter"] = 2 * rg.outer_radius
    res["length"] = rg.length
    return res


def _analytic_chunk(p: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    ok = valid(p)
    res = regions.per_topology(p, ok, lambda rg, rows: region_mass(rg))
    res["valid"] = ok
    return res
