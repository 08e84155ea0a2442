"""`DrumClutch`: the dimensions of a two-zone MR drum clutch, in SI units, validated.

Layout (see ``geometry/section.py`` for the exact r–z regions and README for a figure):

* The **housing** is the magnetic yoke: a solid steel core on the axis and a steel shell
  outside the drum stack, joined by non-magnetic (stainless) end caps. It carries the
  coil and is fixed to the **input** drums; the whole input side turns at the motor speed.
* The **rotor** (output) is a stainless hub disk carrying ``n_drums`` thin steel drums; it
  is fixed to the output **shaft**.
* Output and input drums interleave: core | gap | out 1 | gap | in 1 | gap | out 2 | … |
  out N | gap | shell. There are ``2·n_drums`` sheared cylindrical gaps and
  ``n_drums − 1`` input drums.
* Along the axis the stack has two **active zones** of length ``zone_length`` separated by
  a **non-magnetic band** of length ``band_length`` (stainless in every drum). The coil
  sits in the shell over the band, so its flux crosses the stack radially outward in one
  zone and back inward in the other instead of short-circuiting along the drums.

``drum_inner_diameter`` is the *inner diameter of the innermost output drum*; every other
radius follows from it, the gaps and the thicknesses.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry import regions
from geometry.validation import (
    ParameterError,
    check_int,
    check_range,
)

#: Smallest fluid gap we accept. Turned and ground drums of this size hold ~0.02–0.05 mm
#: runout; a gap below 0.1 mm would be closed by runout and particle chains (MR-fluid
#: particles are 3–10 µm, [lebel] §II-A). Exonetik-type drum clutches use 0.2–0.5 mm.
MIN_GAP = 0.1e-3
#: Thinnest drum the geometry accepts (razor-thin drums are allowed so that the methods
#: can be shown failing on them; the CAD tolerance checks catch what the mesh cannot see).
MIN_DRUM_THICKNESS = 0.02e-3
#: Thinnest wall, clearance or feature we accept: ~10 µm is the tolerance a ground part of
#: this size holds (ISO 286 IT6 at 3–30 mm is 6–13 µm); below it a dimension is a numerical
#: artefact (a 1e-18 m end clearance gave 5.7e10 N·m of face-film drag).
MIN_FEATURE = 10e-6
#: Whole-clutch plausibility limits of a *haptic* clutch: haptic MR clutches are 20–100 mm
#: across ([lebel]: 30×30×40 mm); 0.3 m is 3× the largest, beyond which the rotor inertia
#: alone defeats transparency. A larger clutch is a different product: raise these
#: constants (the only place they are written) to model one.
MAX_OUTER_DIAMETER = 0.3
MAX_OVERALL_LENGTH = 0.3
#: Largest single dimension (no field may exceed the envelope it sits in).
MAX_DIMENSION = max(MAX_OUTER_DIAMETER, MAX_OVERALL_LENGTH)
#: Thickest magnet wire we model (AWG 0000 is 11.7 mm; a haptic coil uses < 1 mm) and the
#: thickest insulation (heavy-build film and glass serving stay well below 0.1 mm).
MAX_WIRE_DIAMETER = 10e-3
MAX_WIRE_INSULATION = 1e-3
#: Fraction of the coil window a layer-wound coil can fill with insulated wire cross-
#: sections d_ins² (square packing fills 1.0; winding leads and layer steps lose ~10 %).
COIL_PACKING = 0.9
#: Hub holes keep this much steel to the shaft and to the first drum, and this web
#: between neighbours (machinable with a 0.2 mm web in stainless; our choice).
HUB_HOLE_MARGIN = 0.25e-3
HUB_HOLE_WEB = 0.2e-3

# ---- the validation rules, stated once --------------------------------------------------
# ``DrumClutch.__post_init__`` turns them into ParameterErrors one design at a time;
# ``valid`` evaluates the same tables and functions on arrays of designs.
#: Integer fields: (name, lo, hi), inclusive.
INT_RANGES: tuple[tuple[str, int, int], ...] = (
    ("n_drums", 1, 20),
    ("coil_turns", 1, 100_000),
    ("hub_holes", 0, 200),
)
#: Length fields: (name, lo, hi, lo_open) in metres; every length has a closed physical
#: range (the edge ``from_mm`` states it in mm, ``valid`` applies it to arrays).
LENGTH_RANGES: tuple[tuple[str, float, float, bool], ...] = (
    ("drum_thickness", MIN_DRUM_THICKNESS, 0.02, False),
    ("input_drum_thickness", MIN_DRUM_THICKNESS, 0.02, False),
    ("gap", MIN_GAP, 5e-3, False),
    ("wire_diameter", MIN_FEATURE, MAX_WIRE_DIAMETER, False),
    ("wire_insulation", 0.0, MAX_WIRE_INSULATION, False),  # bare wire is allowed
    *(
        (name, MIN_FEATURE, MAX_DIMENSION, False)
        for name in (
            "drum_inner_diameter",
            "zone_length",
            "band_length",
            "end_clearance",
            "hub_thickness",
            "end_cap_thickness",
            "shell_thickness",
            "sleeve_thickness",
            "coil_depth",
            "shaft_radius",
            "shaft_length",
            "shaft_bore_clearance",
            "hub_hole_diameter",
            "hub_hole_pitch_radius",
        )
    ),
)


def coil_fits(turns: Any, wire_outer_diameter: Any, coil_depth: Any, band_length: Any) -> Any:
    """turns · d_ins² ≤ packing · window area (layer winding, square packing of d_ins)."""
    return turns * wire_outer_diameter**2 <= COIL_PACKING * coil_depth * band_length


def wire_fits(wire_outer_diameter: Any, coil_depth: Any, band_length: Any) -> Any:
    """One insulated wire fits the window in both directions."""
    return (wire_outer_diameter <= coil_depth) & (wire_outer_diameter <= band_length)


def hub_holes_inside(
    pitch_radius: Any, hole_diameter: Any, shaft_radius: Any, first_drum_r0: Any
) -> Any:
    """Holes lie between the shaft + margin and the first drum − margin."""
    lo = shaft_radius + HUB_HOLE_MARGIN
    hi = first_drum_r0 - HUB_HOLE_MARGIN
    return (pitch_radius - hole_diameter / 2 >= lo) & (pitch_radius + hole_diameter / 2 <= hi)


def bore_covered(bore_radius: Any, hub_outer_radius: Any) -> Any:
    """The front cap's bore opens inside the hub's face, so the hub closes the fluid chamber
    (the face film between hub and cap needs a cap face to shear against)."""
    return bore_radius < hub_outer_radius


def envelope_fits(outer_radius: Any, overall_length: Any) -> Any:
    """The whole clutch stays inside the haptic plausibility envelope (MAX_OUTER_DIAMETER,
    MAX_OVERALL_LENGTH)."""
    return (2 * outer_radius <= MAX_OUTER_DIAMETER) & (overall_length <= MAX_OVERALL_LENGTH)


def hub_holes_apart(n_holes: Any, pitch_radius: Any, hole_diameter: Any) -> Any:
    """Neighbouring holes keep the web: chord between centres 2 r sin(π/n) ≥ d + web."""
    chord = 2 * pitch_radius * np.sin(np.pi / np.maximum(n_holes, 1))
    return (n_holes <= 1) | (chord >= hole_diameter + HUB_HOLE_WEB)


@dataclass(frozen=True)
class DrumClutch:
    """Dimensions of a two-zone MR drum clutch (all lengths in metres).

    Hub features (``hub_holes``…) break the axial symmetry: the CAD, mesh and B-rep see
    them, the analytic section does not (and says so).
    """

    n_drums: int = 2
    drum_thickness: float = 0.3e-3
    input_drum_thickness: float = 0.25e-3
    gap: float = 0.7e-3
    drum_inner_diameter: float = 11.5e-3
    zone_length: float = 6.0e-3
    band_length: float = 8.5e-3
    end_clearance: float = 0.5e-3
    hub_thickness: float = 0.8e-3
    end_cap_thickness: float = 0.8e-3
    shell_thickness: float = 1.4e-3
    sleeve_thickness: float = 0.3e-3
    coil_depth: float = 2.5e-3
    coil_turns: int = 140
    wire_diameter: float = 0.321e-3  # 28 AWG, bare [materials]
    wire_insulation: float = 0.02e-3
    shaft_radius: float = 2.0e-3
    shaft_length: float = 5.0e-3
    shaft_bore_clearance: float = 0.2e-3
    hub_holes: int = 0
    hub_hole_diameter: float = 2.0e-3
    hub_hole_pitch_radius: float = 4.5e-3

    def __post_init__(self) -> None:
        for name, ilo, ihi in INT_RANGES:
            check_int(name, getattr(self, name), ilo, ihi)
        for name, lo, hi, lo_open in LENGTH_RANGES:
            check_range(name, getattr(self, name), lo, hi, " m", lo_open=lo_open)

        # Collisions. The core must keep a solid section inside the first gap.
        core_r = self.core_radius
        if core_r <= 0:
            raise ParameterError(
                f"drum_inner_diameter = {self.drum_inner_diameter:.6g} m: must exceed "
                f"2·gap = {2 * self.gap:.6g} m so the core has a radius > 0"
            )
        if self.shaft_radius >= self.hub_outer_radius:
            raise ParameterError(
                f"shaft_radius = {self.shaft_radius:.6g} m: must be < the hub's outer radius "
                f"{self.hub_outer_radius:.6g} m"
            )
        bore = self.shaft_radius + self.shaft_bore_clearance
        if not bore_covered(bore, self.hub_outer_radius):
            raise ParameterError(
                f"shaft_bore_clearance = {self.shaft_bore_clearance:.6g} m: the front cap's bore "
                f"(radius {bore:.6g} m) must stay inside the hub (outer radius "
                f"{self.hub_outer_radius:.6g} m), or the fluid chamber opens; allowed range "
                f"[{MIN_FEATURE:.6g}, {self.hub_outer_radius - self.shaft_radius:.6g}) m"
            )
        # The coil must fit its window (turns · d_ins² ≤ packing · window area).
        have = COIL_PACKING * self.coil_window_area
        if not coil_fits(
            self.coil_turns, self.wire_outer_diameter, self.coil_depth, self.band_length
        ):
            max_turns = math.floor(have / self.wire_outer_diameter**2)
            fix = (
                f"allowed range [1, {max_turns}]"
                if max_turns >= 1
                else "the window holds no turn: enlarge it or use a thinner wire"
            )
            raise ParameterError(
                f"coil_turns = {self.coil_turns}: does not fit the coil window coil_depth = "
                f"{self.coil_depth:.6g} m × band_length = {self.band_length:.6g} m with "
                f"wire_diameter = {self.wire_diameter:.6g} m and wire_insulation = "
                f"{self.wire_insulation:.6g} m; {fix}"
            )
        if not wire_fits(self.wire_outer_diameter, self.coil_depth, self.band_length):
            raise ParameterError(
                f"wire_diameter = {self.wire_diameter:.6g} m: the insulated wire must fit "
                f"the coil window ({self.coil_depth:.6g} × {self.band_length:.6g} m)"
            )
        if self.hub_holes:
            self._check_hub_holes()
        if not envelope_fits(self.outer_radius, self.overall_length):
            raise ParameterError(
                f"the clutch is {2 * self.outer_radius:.6g} m across × "
                f"{self.overall_length:.6g} m long (n_drums = {self.n_drums}, "
                f"drum_inner_diameter = {self.drum_inner_diameter:.6g} m, gap = {self.gap:.6g} m"
                f", …): must fit Ø {MAX_OUTER_DIAMETER:.6g} m × {MAX_OVERALL_LENGTH:.6g} m, the "
                "plausibility envelope of a haptic clutch (geometry.params.MAX_OUTER_DIAMETER, "
                "MAX_OVERALL_LENGTH; raise them there to model a larger one)"
            )

    def _check_hub_holes(self) -> None:
        r_h, d_h = self.hub_hole_pitch_radius, self.hub_hole_diameter
        lo = self.shaft_radius + HUB_HOLE_MARGIN
        first = self.drum_radii_out[0][0]
        hi = first - HUB_HOLE_MARGIN
        if not hub_holes_inside(r_h, d_h, self.shaft_radius, first):
            raise ParameterError(
                f"hub_hole_pitch_radius = {r_h:.6g} m with hub_hole_diameter = {d_h:.6g} m: "
                f"holes must lie between r = {lo:.6g} m (shaft + 0.25 mm) and "
                f"r = {hi:.6g} m (first drum − 0.25 mm)"
            )
        # Neighbouring holes keep a 0.2 mm web: chord between centres ≥ d + 0.2 mm.
        if not hub_holes_apart(self.hub_holes, r_h, d_h):
            sin_half = min(1.0, (d_h + HUB_HOLE_WEB) / (2 * r_h))
            max_n = max(1, math.floor(math.pi / math.asin(sin_half)))
            raise ParameterError(
                f"hub_holes = {self.hub_holes}: holes of {d_h * 1e3:.3g} mm on a "
                f"{r_h * 1e3:.3g} mm pitch radius overlap; allowed range [0, {max_n}]"
            )

    # ---- derived dimensions: the region table's stations (geometry/regions.py) -----------
    @property
    def stations(self) -> dict[str, float]:
        """Every r and z station of the section (``geometry.regions.stations``), metres."""
        return regions.stations(vars(self), self.n_drums)

    @property
    def core_radius(self) -> float:
        """Outer radius of the steel core = inner wall of the first gap."""
        return self.drum_inner_diameter / 2 - self.gap

    def _drum_radii(self, kind: str) -> tuple[tuple[float, float], ...]:
        st = self.stations
        return tuple(
            (st[regions.rho(j)], st[regions.rho(j + 1)])
            for j in range(regions.n_layers(self.n_drums))
            if regions.layer(j)[0] == kind
        )

    @property
    def drum_radii_out(self) -> tuple[tuple[float, float], ...]:
        """(inner, outer) radius of every output drum, innermost first."""
        return self._drum_radii("out")

    @property
    def drum_radii_in(self) -> tuple[tuple[float, float], ...]:
        """(inner, outer) radius of every input drum, innermost first."""
        return self._drum_radii("in")

    @property
    def pole_radius(self) -> float:
        """Inner radius of the shell's pole faces = outer wall of the last gap."""
        return self.stations[regions.rho(4 * self.n_drums - 1)]

    @property
    def hub_outer_radius(self) -> float:
        """The hub reaches the outer face of the outermost output drum."""
        return self.stations[regions.rho(4 * self.n_drums - 2)]

    @property
    def coil_inner_radius(self) -> float:
        return self.stations["coil_in"]

    @property
    def coil_outer_radius(self) -> float:
        return self.stations["coil_out"]

    @property
    def outer_radius(self) -> float:
        return self.stations["outer"]

    @property
    def wire_outer_diameter(self) -> float:
        return self.wire_diameter + 2 * self.wire_insulation

    @property
    def coil_window_area(self) -> float:
        return self.coil_depth * self.band_length

    @property
    def active_length(self) -> float:
        """Total axial length over which the field crosses the stack (both zones)."""
        return 2 * self.zone_length

    @property
    def stack_length(self) -> float:
        """Axial length of the drum stack region (clearance + zone + band + zone + clearance)."""
        st = self.stations
        return st["cap_back"] - st["hub_back"]

    @property
    def body_length(self) -> float:
        """Housing length: front cap + hub + stack + back cap."""
        return self.stations["back"]

    @property
    def overall_length(self) -> float:
        """Envelope length including the output shaft stick-out."""
        st = self.stations
        return st["back"] - st["shaft_tip"]

    # ---- conversion at the edges ----------------------------------------------------------
    def to_mm(self) -> dict[str, float | int]:
        """Dimensions as a design-file mapping (lengths in mm with ``_mm`` keys)."""
        d: dict[str, float | int] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in INTEGER_FIELDS:
                d[f.name] = v
            else:
                d[f"{f.name}_mm"] = round(v * 1000.0, 9)
        return d

    @classmethod
    def from_mm(
        cls, data: Mapping[str, Any], base: DrumClutch | None = None, where: str = ""
    ) -> DrumClutch:
        """Build from a design-file mapping: lengths in mm under ``<name>_mm`` keys.

        Unknown keys, unit-less length keys and wrong types raise a ParameterError naming
        the key. Without ``base`` every key must be given.
        """
        prefix = f"{where}: " if where else ""
        values: dict[str, Any] = {}
        for key, v in data.items():
            if key in INTEGER_FIELDS:
                if isinstance(v, bool) or not isinstance(v, int):
                    raise ParameterError(f"{prefix}{key} = {v!r}: must be an integer")
                values[key] = v
            elif key.endswith("_mm") and key[:-3] in LENGTH_FIELDS:
                values[key[:-3]] = _length_from_mm(prefix, key, v)
            elif key in LENGTH_FIELDS:
                raise ParameterError(
                    f"{prefix}{key}: lengths need their unit in the key; write {key}_mm (mm)"
                )
            else:
                raise ParameterError(
                    f"{prefix}{key}: unknown key; known keys are "
                    + ", ".join(sorted([*INTEGER_FIELDS, *(k + "_mm" for k in LENGTH_FIELDS)]))
                )
        if base is None:
            missing = [f for f in FIELD_NAMES if f not in values]
            if missing:
                m = missing[0]
                key = m if m in INTEGER_FIELDS else f"{m}_mm"
                raise ParameterError(f'{prefix}{key}: missing (or give base = "paper")')
        try:
            return cls(**values) if base is None else replace(base, **values)
        except ParameterError as exc:  # a rule between fields: say it in the file's keys
            raise ParameterError(prefix + _in_mm(str(exc))) from None


FIELD_NAMES = tuple(f.name for f in fields(DrumClutch))
INTEGER_FIELDS = frozenset({"n_drums", "coil_turns", "hub_holes"})
LENGTH_FIELDS = frozenset(n for n in FIELD_NAMES if n not in INTEGER_FIELDS)
_LENGTH_RULE = {name: (lo, hi, lo_open) for name, lo, hi, lo_open in LENGTH_RANGES}


@functools.cache
def _si_length() -> re.Pattern[str]:
    """``NAME = VALUE m`` of any length field in a message: compiled when a file's value is
    first refused, not at import: an alternation of every field, issue 40)."""
    return re.compile(
        r"\b(" + "|".join(sorted(LENGTH_FIELDS)) + r") = ([-+0-9.eE]+|nan|inf|-inf) m\b"
    )


def _length_from_mm(prefix: str, key: str, value: Any) -> float:
    """A design file's ``<name>_mm`` value in metres, checked by LENGTH_RANGES's rule (the
    one DrumClutch applies) and, if outside, reported in the file's key and unit."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{prefix}{key} = {value!r}: must be a number (mm)")
    name = key[:-3]
    lo, hi, lo_open = _LENGTH_RULE[name]
    si = float(value) / 1000.0
    try:
        check_range(name, si, lo, hi, " m", lo_open=lo_open)
    except ParameterError:
        lb = "(" if lo_open else "["
        raise ParameterError(
            f"{prefix}{key} = {float(value):.6g} mm: must be in {lb}{lo * 1e3:.6g}, "
            f"{hi * 1e3:.6g}] mm"
        ) from None
    return si


def _in_mm(message: str) -> str:
    """``gap = 0.0007 m`` in a DrumClutch message → ``gap_mm = 0.7 mm`` (the file's key)."""
    return _si_length().sub(lambda m: f"{m[1]}_mm = {float(m[2]) * 1e3:.6g} mm", message)


# ---- arrays of designs -------------------------------------------------------------------
def broadcast_fields(
    values: Mapping[str, ArrayLike], base: DrumClutch | None = None
) -> dict[str, np.ndarray]:
    """Every DrumClutch field as a 1-D array of a common length S (missing ones from base)."""
    unknown = sorted(set(values) - set(FIELD_NAMES))
    if unknown:
        raise ParameterError(f"{unknown[0]}: unknown DrumClutch field")
    base = base if base is not None else DrumClutch()
    arrays: dict[str, Any] = {}
    for f in fields(DrumClutch):
        v = values[f.name] if f.name in values else getattr(base, f.name)
        arrays[f.name] = np.asarray(v, dtype=float)
    shaped = np.broadcast_arrays(*arrays.values())
    return {k: np.ravel(a) for k, a in zip(arrays, shaped, strict=True)}


def valid(p: Mapping[str, np.ndarray]) -> NDArray[np.bool_]:
    """Which of the designs ``p`` (``broadcast_fields``) pass DrumClutch's validation: the
    same rule tables and predicates, on arrays (integer fields must hold integers)."""
    ok = np.ones(np.asarray(p["n_drums"]).shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        for name, ilo, ihi in INT_RANGES:
            v = p[name]
            ok &= (v >= ilo) & (v <= ihi) & (v == np.round(v))  # NaN fails
    for name, lo, hi, lo_open in LENGTH_RANGES:
        v = p[name]
        ok &= ((v > lo) if lo_open else (v >= lo)) & (v <= hi)  # NaN fails both
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        d_ins = p["wire_diameter"] + 2 * p["wire_insulation"]
        ok &= coil_fits(p["coil_turns"], d_ins, p["coil_depth"], p["band_length"])
        ok &= wire_fits(d_ins, p["coil_depth"], p["band_length"])
        for n, rows in regions.by_drum_count(p["n_drums"], ok).items():
            sub = {k: v[rows] for k, v in p.items()}
            rg = regions.evaluate(sub, n)
            good = rg.core_radius > 0
            good &= sub["shaft_radius"] < rg.hub_outer_radius
            good &= bore_covered(rg.at["bore"], rg.hub_outer_radius)
            r_h, d_h = sub["hub_hole_pitch_radius"], sub["hub_hole_diameter"]
            first_r0 = rg.at[regions.rho(1)]
            holes = hub_holes_inside(r_h, d_h, sub["shaft_radius"], first_r0)
            holes &= hub_holes_apart(sub["hub_holes"], r_h, d_h)
            good &= (sub["hub_holes"] == 0) | holes
            good &= envelope_fits(rg.outer_radius, rg.length)
            ok[rows] = good
    return ok


#: The paper's clutch ([lebel] Table 1: 0.4 N·m, 2.7 g·cm², 85 g, 30×30×40 mm,
#: 140 turns of 28 AWG). The paper gives no drum dimensions; ours are chosen in
#: README "The paper preset" so that the rotor inertia, the mass, the envelope and the
#: torque at 7 A with MRF-132DG match Table 1 and Fig. 2b.
PRESETS: dict[str, DrumClutch] = {
    "paper": DrumClutch(),
    # the paper's clutch with six Ø2 mm lightening holes in the output hub: the case where
    # the analytic (axisymmetric) inertia and the mesh / B-rep inertias differ
    "paper-holes": replace(
        DrumClutch(), hub_holes=6, hub_hole_diameter=2.0e-3, hub_hole_pitch_radius=4.0e-3
    ),
}


def preset(name: str) -> DrumClutch:
    """A named preset; ParameterError lists the names if ``name`` is unknown."""
    try:
        return PRESETS[name]
    except KeyError:
        raise ParameterError(
            f"preset = {name!r}: unknown; known presets are {', '.join(sorted(PRESETS))}"
        ) from None
