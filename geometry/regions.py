"""The region table: the clutch's r–z cross-section as one declarative table of rectangles.

Every rectangle of the clutch — solid, coil or fluid — is a row of ``table(n)``: its name,
part, material, and its four edges as *stations*. A station is a named position (``rho3``,
``zone_A1``, ``coil_out`` …) computed once, by ``stations``, from the DrumClutch fields.
The table depends only on the drum count ``n`` (the topology); the stations are plain
arithmetic on the fields, so the same code evaluates one design (floats) or S designs at
once (arrays of shape S). There is no scalar twin: ``geometry.section.build_section`` is
this table for one design, and every consumer — CAD, mass and inertia, the magnetic
circuit, the FEM, the viscous drag — reads the rectangles and their roles from here.

Layout (z = 0 at the outer face of the front cap; the output shaft sticks out to z < 0)::

    r:  axis | core | gap0 | out1 | gap1 | in1 | gap2 | out2 | … | outN | gap(2N−1) | pole
        … | sleeve | coil | back iron (outer)
    z:  shaft_tip < front < cap_front < hub_front < hub_back < zone_A0 < zone_A1
        < zone_B0 < zone_B1 < cap_back < back

The radial stack between the core and the pole faces is a sequence of 4N − 1 layers
(gap, output drum, gap, input drum, …, output drum, gap) whose interfaces are the stations
``rho0`` (core radius) … ``rho{4N−1}`` (pole radius). Because edges are station names, two
rectangles touch exactly when they share a station: adjacency (which steel walls a gap
lies between, which films are sheared) is read from the table symbolically, once per
topology, and the numbers follow as arrays.

Fluid films carry a role: ``film="cylinder"`` for the sheared cylindrical gaps between an
output and an input wall (``walls`` names them), ``film="face"`` for the axial films
between an output face and an input face (disk shear). The rest of the fluid fills the
cavity; the regions never overlap and exactly cover the cavity (tests/geometry).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry.materials import (
    COIL,
    DEFAULT_CHOICE,
    DENSITY,
    SLOTS,
    MaterialChoice,
    coil_density,
)

Fields = Mapping[str, Any]  # DrumClutch field name -> float or array (SI)

PARTS: tuple[str, ...] = ("rotor", "shaft", "input", "housing", "coil", "fluid")
#: Parts that turn with the output (what the haptic device feels as rotor inertia).
OUTPUT_PARTS: tuple[str, ...] = ("rotor", "shaft")
#: The two active zones: (name, first station, last station).
ZONES: tuple[tuple[str, str, str], ...] = (("A", "zone_A0", "zone_A1"), ("B", "zone_B0", "zone_B1"))


# ---- the layers of the radial stack -------------------------------------------------------
def n_layers(n: int) -> int:
    """Layers between core and pole: 2n gaps, n output and n − 1 input drums."""
    return 4 * n - 1


def layer(j: int) -> tuple[str, int]:
    """Layer ``j`` of the radial stack: ("gap", k) 0-based, or ("out"|"in", i) 1-based."""
    if j % 2 == 0:
        return "gap", j // 2
    m = (j - 1) // 2
    return ("out", m // 2 + 1) if m % 2 == 0 else ("in", (m + 1) // 2)


def rho(j: int) -> str:
    """Station name of the j-th radial interface of the stack (rho0 = core radius)."""
    return f"rho{j}"


# ---- stations: every position where an edge lies -------------------------------------------
def stations(p: Fields, n: int) -> dict[str, Any]:
    """Every r and z station of a clutch with ``n`` output drums (floats or arrays)."""
    g = p["gap"]
    thickness = {"gap": g, "out": p["drum_thickness"], "in": p["input_drum_thickness"]}
    st: dict[str, Any] = {}
    r = p["drum_inner_diameter"] / 2 - g  # the innermost output drum's bore less one gap
    st["axis"] = 0.0 * r
    st[rho(0)] = r
    for j in range(n_layers(n)):
        r = r + thickness[layer(j)[0]]
        st[rho(j + 1)] = r
    st["shaft"] = p["shaft_radius"]
    st["bore"] = p["shaft_radius"] + p["shaft_bore_clearance"]
    st["coil_in"] = r + p["sleeve_thickness"]
    st["coil_out"] = st["coil_in"] + p["coil_depth"]
    st["outer"] = st["coil_out"] + p["shell_thickness"]

    t, cl = p["end_cap_thickness"], p["end_clearance"]
    z = 0.0 * r
    st["shaft_tip"] = z - p["shaft_length"]
    for name, dz in (
        ("front", 0.0),
        ("cap_front", t),
        ("hub_front", cl),
        ("hub_back", p["hub_thickness"]),
        ("zone_A0", cl),
        ("zone_A1", p["zone_length"]),
        ("zone_B0", p["band_length"]),
        ("zone_B1", p["zone_length"]),
        ("cap_back", cl),
        ("back", t),
    ):
        z = z + dz
        st[name] = z
    return st


# ---- the table ------------------------------------------------------------------------------
@dataclass(frozen=True)
class RegionSpec:
    """One row of the region table: a rectangle whose edges are station names."""

    name: str
    part: str
    material: str
    r0: str
    r1: str
    z0: str
    z1: str
    film: str = ""  # "cylinder" | "face" | "" (not a sheared film)
    walls: tuple[str, str] = ("", "")  # cylinder films: (inner, outer) wall names
    #: what the region is to the models, whatever its material: "steel" (magnetic),
    #: "nonmagnetic", "coil" or "fluid"; ``slot`` is the part whose material it takes
    #: (``geometry.materials.SLOTS``; "coil" for the coil)
    role: str = ""
    slot: str = ""


_ROLE = {**SLOTS, "coil": "coil"}  # a part's role is the kind its material must be


@functools.lru_cache(maxsize=256)
def table(n: int, materials: MaterialChoice = DEFAULT_CHOICE) -> tuple[RegionSpec, ...]:
    """Every rectangle of a clutch with ``n`` output drums (see the module docstring), each
    made of the material ``materials`` chooses for its part."""
    if int(n) != n or n < 1:
        raise ValueError(f"n_drums = {n!r}: the table needs an integer >= 1")
    choice = materials.as_dict()
    choice["coil"] = COIL

    def R(name: str, part: str, slot: str, *rest: Any) -> RegionSpec:
        return RegionSpec(name, part, choice[slot], *rest, role=_ROLE[slot], slot=slot)

    last = 2 * n - 1  # the outermost gap, between output drum n and the shell's poles
    hub_r, pole = rho(4 * n - 2), rho(4 * n - 1)
    rows: list[RegionSpec] = [
        R("shaft", "shaft", "hub", "axis", "shaft", "shaft_tip", "hub_back"),
        R("hub", "rotor", "hub", "shaft", hub_r, "hub_front", "hub_back"),
    ]
    drums: dict[str, list[tuple[int, int]]] = {"out": [], "in": []}
    for j in range(n_layers(n)):
        kind, i = layer(j)
        if kind != "gap":
            drums[kind].append((i, j))
    # Output drums (rotor) hang from the hub; input drums from the back cap. Steel in the
    # zones, stainless over the band so the flux cannot short-circuit along the drums.
    for kind, part, z_first, z_last in (("out", "rotor", "hub_back", "zone_B1"),
                                        ("in", "input", "zone_A0", "cap_back")):  # fmt: skip
        for i, j in drums[kind]:
            for seg, mat, z0, z1 in (
                ("A", "drums", z_first, "zone_A1"),
                ("band", "bands", "zone_A1", "zone_B0"),
                ("B", "drums", "zone_B0", z_last),
            ):
                rows.append(R(f"{kind}{i}_{seg}", part, mat, rho(j), rho(j + 1), z0, z1))
    # Housing: the steel core and shell (poles + back iron over the coil) with the coil
    # between them, joined by stainless end caps.
    rows += [
        R("core", "housing", "core", "axis", rho(0), "zone_A0", "cap_back"),
        R("shell_A", "housing", "shell", pole, "outer", "cap_front", "zone_A1"),
        R("shell_back", "housing", "shell", "coil_out", "outer", "zone_A1", "zone_B0"),
        R("shell_B", "housing", "shell", pole, "outer", "zone_B0", "cap_back"),
        R("sleeve", "housing", "housing", pole, "coil_in", "zone_A1", "zone_B0"),
        R("cap_front", "housing", "housing", "bore", "outer", "front", "cap_front"),
        R("cap_back", "housing", "housing", "axis", "outer", "cap_back", "back"),
        R("coil", "coil", "coil", "coil_in", "coil_out", "zone_A1", "zone_B0"),
    ]
    # Sheared cylindrical gaps: wetted where both walls face each other.
    for k in range(2 * n):
        inner = "core" if k == 0 else (f"out{(k + 1) // 2}" if k % 2 else f"in{k // 2}")
        outer = "shell" if k == last else (f"in{(k + 1) // 2}" if k % 2 else f"out{k // 2 + 1}")
        z0 = "hub_back" if k == last else "zone_A0"
        rows.append(R(f"gap{k}", "fluid", "fluid", rho(2 * k), rho(2 * k + 1), z0, "zone_B1",
                      "cylinder", (inner, outer)))  # fmt: skip
    # Axial films between an output face and an input face (disk shear), end clearance high.
    rows.append(
        R("film_hub_front", "fluid", "fluid", "bore", hub_r, "cap_front", "hub_front", "face")
    )
    rows.append(R("film_hub_core", "fluid", "fluid", "axis", rho(0), "hub_back", "zone_A0", "face"))
    for i, j in drums["in"]:
        rows.append(R(f"film_in{i}_tip", "fluid", "fluid", rho(j), rho(j + 1), "hub_back",
                      "zone_A0", "face"))  # fmt: skip
    for i, j in drums["out"]:
        rows.append(R(f"film_out{i}_tip", "fluid", "fluid", rho(j), rho(j + 1), "zone_B1",
                      "cap_back", "face"))  # fmt: skip
    # The rest of the cavity (r < pole, cap_front < z < cap_back) is unsheared fluid.
    rows.append(R("fluid_bore", "fluid", "fluid", "shaft", "bore", "cap_front", "hub_front"))
    rows.append(R("fluid_rim", "fluid", "fluid", hub_r, pole, "cap_front", "hub_back"))
    for k in range(2 * n):
        if k != last:
            rows.append(R(f"fluid_gap{k}_front", "fluid", "fluid", rho(2 * k), rho(2 * k + 1),
                          "hub_back", "zone_A0"))  # fmt: skip
        rows.append(R(f"fluid_gap{k}_back", "fluid", "fluid", rho(2 * k), rho(2 * k + 1), "zone_B1",
                      "cap_back"))  # fmt: skip
    return tuple(rows)


# ---- the table evaluated on one design or many ------------------------------------------------
@dataclass(frozen=True)
class Regions:
    """The region table of ``n``-drum clutches evaluated at S designs (or one, as floats).

    ``at`` maps every station to its value (float, or array of shape S); a region's edges
    are ``at[spec.r0]`` … — no region array is ever copied.
    """

    n: int
    specs: tuple[RegionSpec, ...]
    at: Mapping[str, Any]
    fields: Fields
    #: the material of each part (its names are the ones on ``specs``)
    materials: MaterialChoice = DEFAULT_CHOICE

    def __iter__(self) -> Iterator[RegionSpec]:
        return iter(self.specs)

    def bounds(self, spec: RegionSpec) -> tuple[Any, Any, Any, Any]:
        """(r0, r1, z0, z1) of a region."""
        a = self.at
        return a[spec.r0], a[spec.r1], a[spec.z0], a[spec.z1]

    def spec(self, name: str) -> RegionSpec:
        for s in self.specs:
            if s.name == name:
                return s
        raise KeyError(name)

    def films(self, kind: str) -> tuple[RegionSpec, ...]:
        return tuple(s for s in self.specs if s.film == kind)

    def density(self, material: str) -> Any:
        """kg/m³ of ``material`` in these designs (the coil's depends on its fill)."""
        if material == COIL:
            p = self.fields
            window = p["coil_depth"] * p["band_length"]
            return coil_density(p["coil_turns"], p["wire_diameter"], window)
        return DENSITY[material]

    # named stations people ask for
    @property
    def core_radius(self) -> Any:
        return self.at[rho(0)]

    @property
    def pole_radius(self) -> Any:
        return self.at[rho(4 * self.n - 1)]

    @property
    def hub_outer_radius(self) -> Any:
        return self.at[rho(4 * self.n - 2)]

    @property
    def outer_radius(self) -> Any:
        return self.at["outer"]

    @property
    def length(self) -> Any:
        """Envelope length, shaft stick-out included."""
        return self.at["back"] - self.at["shaft_tip"]


def evaluate(p: Fields, n: int, materials: MaterialChoice = DEFAULT_CHOICE) -> Regions:
    """The region table of ``n``-drum clutches at the designs ``p`` (floats or arrays), made
    of ``materials``."""
    return Regions(n, table(n, materials), stations(p, n), p, materials)


# ---- arrays of designs of several drum counts: one batch per topology ----------------------------
def by_drum_count(n_drums: np.ndarray, ok: np.ndarray | None = None) -> dict[int, np.ndarray]:
    """Row indices of each drum count (rows not ``ok`` left out): one batch per topology."""
    n = np.asarray(n_drums)
    keep = np.ones(n.shape, bool) if ok is None else np.asarray(ok, bool)
    # the distinct counts, sorted: what np.unique does, without the numpy.ma it imports
    # (~30 ms of an interactive command, issue 40)
    s = np.sort(n[keep], axis=None)
    first = np.ones(s.shape, bool)
    np.not_equal(s[1:], s[:-1], out=first[1:])
    return {int(v): np.flatnonzero(keep & (n == v)) for v in s[first]}


def by_topology(
    n_drums: np.ndarray,
    ok: np.ndarray | None = None,
    materials: MaterialChoice | np.ndarray = DEFAULT_CHOICE,
) -> dict[tuple[int, MaterialChoice], np.ndarray]:
    """Row indices of each (drum count, material choice): one batch per region table.
    ``materials``: one choice for every row, or an object array of S choices."""
    if isinstance(materials, MaterialChoice):
        return {(n, materials): rows for n, rows in by_drum_count(n_drums, ok).items()}
    mats = np.asarray(materials, dtype=object)
    out: dict[tuple[int, MaterialChoice], np.ndarray] = {}
    for choice in dict.fromkeys(mats.tolist()):  # first-seen order
        sel = mats == choice
        keep = sel if ok is None else sel & np.asarray(ok, bool)
        for n, rows in by_drum_count(n_drums, keep).items():
            out[(n, choice)] = rows
    return out


def per_topology(
    p: Mapping[str, np.ndarray],
    ok: np.ndarray,
    fn: Callable[[Regions, np.ndarray], Mapping[str, Any]],
    materials: MaterialChoice | np.ndarray = DEFAULT_CHOICE,
) -> dict[str, np.ndarray]:
    """``fn(regions, rows)`` on the region table of every drum count (and material choice:
    ``materials``, one for all rows or an object array of S) in ``p`` (1-D arrays of S
    designs; ``rows`` are the group's row indices), its outputs (arrays of the group's
    size, or (size, …)) scattered back to S rows; rows not ``ok`` are NaN."""
    size = np.asarray(p["n_drums"]).size
    out: dict[str, np.ndarray] = {}
    groups = by_topology(p["n_drums"], ok, materials)
    if not groups:  # no valid design: one empty batch still names the outputs
        first = materials if isinstance(materials, MaterialChoice) else DEFAULT_CHOICE
        groups = {(1, first): np.zeros(0, dtype=np.intp)}
    for (n, choice), rows in groups.items():
        sub = {k: v[rows] for k, v in p.items()}
        for key, val in fn(evaluate(sub, n, choice), rows).items():
            val = np.broadcast_to(np.asarray(val, dtype=float), (rows.size, *np.shape(val)[1:]))
            if key not in out:
                out[key] = np.full((size, *val.shape[1:]), np.nan)
            out[key][rows] = val
    return out
