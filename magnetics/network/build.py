"""Building the reluctance network: the ladder of the drum clutch, read from its region
table (issue 12).

Why not one loop: the drum walls are steel in the active zones and stainless over the band,
so each drum is a flux conductor from zone A to zone B in parallel with the core. Flux that
crosses the outer gaps of zone A can return through a drum's band (stainless and the fluid
beside it) to zone B without crossing the inner gaps: the outer gaps carry more flux than
the inner ones (the FEM shows 10× on a 6-drum, 1 mm-gap design), which a single loop — the
same flux through every gap — cannot represent.

The network is a ladder read from the table. In each active zone the steel regions the
sheared films lie between (``RegionSpec.walls``: the core, the drum walls, the shell's pole)
are its nodes, in radial order; the films are its series elements (one per film and zone,
the exact cylindrical reluctance ln(r1/r0)/(2πμL) [roters1941] ch. 5, L where both walls'
steel face each other inside the zone), and each wall's zone-A node is joined to its zone-B
node by a rung:

- the core: its steel, axially (the flux builds up linearly along each zone);
- each drum: its steel in each zone, axially (same build-up), in series with its band: the
  regions that span the band radially on the drum's own stations (its stainless band, μA/l)
  in parallel with half of each neighbouring film's fluid over the band, on the fluid's
  own B–H (``_band``);
- beside the core's and each drum's steel, in each zone (and beside the core over the
  band), half of each neighbouring film's fluid carries flux axially too: a fluid sheath
  in parallel with the steel section, on its own B–H (``_pair``). A thin or saturated wall
  hands its flux to the fluid beside it; without the sheaths the network was −29 % at 7 A
  on 0.1 mm walls with a 6 mm bore (now −17 %);
- the shell: pole A radially, the back iron axially, pole B — with the coil's ampere-turns
  N·I; in parallel with it the coil window (sleeve and coil, linear, in parallel with the
  outer film's half over the band, non-linear), whose MMF from the distributed winding
  falls linearly across the coil (the window element's permeance is weighted accordingly,
  [roters1941] ch. 5, leakage of a uniformly wound coil), and, beside the back iron, the
  air outside the shell (``magnetics.outer_air``: a solved exterior field problem, stored
  as a table in the shell's proportions).

Past each zone's far end an end leak runs from the pole to the core through the regions
in front of the walls (``_end_leak``), in parallel with the zone's stack: film k carries
x_k − e_z in zone z. Each film's fringing reaches into the fluid pockets on its radii; the
torque reads its field in the film through the laminate beside it (``_fringe_decay``).

"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from geometry.materials import MRF, STEEL
from geometry.regions import ZONES, Regions, RegionSpec
from geometry.validation import ParameterError
from magnetics import outer_air
from magnetics.materials import MATERIALS, MU0, Magnetic, magnetic

FloatArray = NDArray[np.float64]
_POLE_POINTS = 3  # Gauss points in ln r across the thick pole rings


@dataclass(frozen=True)
class Network:
    """The ladder of S designs of one drum count; m films (loops), arrays with leading S.

    Kernels: an element's MMF is Σ_j w_j·H(k_j·Φ) over its Gauss points (k = B/Φ, 1/m²;
    w in m), a zero weight pads unused points. Build-up kernels (``rung_*``, ``sheath_*``:
    the core and the drum walls along a zone, and their fluid sheaths, where the axial flux
    grows linearly from 0 at the zone's far end to Φ at the band) read w·H̄(k·Φ), the exact
    mean H̄(B) = (1/B)·∫0^B H of the material's piecewise-linear H(B)
    (``BHCurve.h_mean_dh``), k the full section's 1/A and w the zone's length.
    """

    turns: FloatArray  # (S,)
    film_name: tuple[str, ...]  # m
    gap_r0: FloatArray  # (S, m)
    gap_r1: FloatArray  # (S, m)
    gap_len: FloatArray  # (S, m, 2) length carrying flux in zone A, B
    gap_eff: FloatArray  # (S, m, 2) the same plus the fringing length at its ends
    fringe_h: FloatArray  # (S, m, 2, 2) the film's own fluid past the overlap's two ends
    fringe_c: FloatArray  # (S, m, 2, 2) each fringe's decay, H(s) = H_e·g/(g + cπs)
    fluid_k: FloatArray  # (S, m, 2)
    fluid_w: FloatArray
    wall_k: FloatArray  # (S, m, 2) steel wall inside film k, radially, zones A and B
    wall_w: FloatArray
    rung_k: FloatArray  # (S, m, 2, 1) wall j's steel axially in zone A and B (rungs 0..m-1)
    rung_w: FloatArray
    sheath_k: FloatArray  # (S, m, 2, 1) the fluid beside wall j axially in zone A and B
    sheath_w: FloatArray
    rung_perm: FloatArray  # (S, m + 1) each rung's band: linear permeance (stainless), H
    rung_fluid: FloatArray  # (S, m + 1) and the area of the fluid beside it, m²
    core_k: FloatArray  # (S, 1): the core over the band
    core_w: FloatArray
    core_sheath_k: FloatArray  # (S, 1): the fluid beside the core over the band
    core_sheath_w: FloatArray
    shell_k: FloatArray  # (S, 2·_POLE_POINTS): the poles, radially
    shell_w: FloatArray
    back_k: FloatArray  # (S, 1): the back iron, axially
    back_w: FloatArray
    window_perm: FloatArray  # (S,) the coil window: linear permeance (sleeve, coil), H
    window_fluid: FloatArray  # (S,) and the area of the outer film's half over the band, m²
    band_len: FloatArray  # (S,) the band's length, m
    outer_air: FloatArray  # (S,) reluctance of the air outside the shell, 1/H
    end_leak: FloatArray  # (S, 2) reluctance from the pole to the core past each zone's end
    steel: str = STEEL  # the drums' steel
    fluid: str = MRF
    core_steel: str = STEEL
    shell_steel: str = STEEL  # the poles and the back iron

    @property
    def m(self) -> int:
        return len(self.film_name)

    @property
    def unknowns(self) -> int:
        """The loop fluxes per design and current: m films, the window, the outer air, the
        two end leaks (``leaks``) and the 2m + 1 sheaths (``sheaths``)."""
        return 3 * self.m + 5

    @property
    def leaks(self) -> slice:
        return slice(self.m + 2, self.m + 4)

    @property
    def sheaths(self) -> slice:
        return slice(self.m + 4, None)


def _overlap(a0, a1, b0, b1):  # type: ignore[no-untyped-def]
    return np.maximum(np.minimum(a1, b1) - np.maximum(a0, b0), 0.0)


def network_from_regions(
    rg: Regions, materials: Mapping[str, Magnetic] | None = None, fringing: bool = True
) -> Network:
    """The ladder of the designs of one region table (the module docstring);
    ``fringing=False`` leaves out the films' fringing at the ends of the walls' overlap."""
    mats = MATERIALS if materials is None else materials
    size = np.size(rg.at["outer"])
    at = {k: np.broadcast_to(np.asarray(v, dtype=float), (size,)) for k, v in rg.at.items()}

    def box(sp: RegionSpec):  # type: ignore[no-untyped-def]
        return at[sp.r0], at[sp.r1], at[sp.z0], at[sp.z1]

    steel = {sp.name: sp for sp in rg if sp.role == "steel"}
    films = rg.films("cylinder")
    m = len(films)
    zones = [(name, at[a], at[b]) for name, a, b in ZONES]
    (_, za0, za1), (_, zb0, zb1) = zones
    band = zb0 - za1

    def wall(name: str, zone: str) -> RegionSpec:
        """The steel region of wall ``name`` in ``zone`` (a drum's zone segment, the core,
        the shell's pole)."""
        for cand in (f"{name}_{zone}", name):
            if cand in steel:
                return steel[cand]
        raise ParameterError(f"network: no steel region for wall {name!r} in zone {zone}")

    zeros = lambda *shape: np.zeros((size, *shape))  # noqa: E731
    gap_len, gap_eff, fluid_k, fluid_w = zeros(m, 2), zeros(m, 2), zeros(m, 2), zeros(m, 2)
    fringe_h, fringe_c = zeros(m, 2, 2), np.ones((size, m, 2, 2))
    mu = {sp.material: magnetic(sp.material, mats).mu_initial for sp in rg}  # initial μ
    wall_k, wall_w = zeros(m, 2), zeros(m, 2)
    rung_k, rung_w = zeros(m, 2, 1), zeros(m, 2, 1)
    rung_perm, rung_fluid = zeros(m + 1), zeros(m + 1)
    gap_r0 = np.stack([at[f.r0] for f in films], axis=1)
    gap_r1 = np.stack([at[f.r1] for f in films], axis=1)
    radii = _stacked_radii(at, rg)  # every region's r0, r1 once: (specs, (R, S), (R, S))
    for k, f in enumerate(films):
        inner, outer = f.walls
        r0, r1, g0, g1 = box(f)
        # the fluid pockets on the film's radii just past its region (a gap's front and
        # back pockets, "fluid_gapK_front"): fringing tubes run into them too, though they
        # are not part of the sheared film (the FEM's torque leaves them out as well)
        e0, e1 = g0, g1
        for sp in rg:
            if sp is not f and sp.material == f.material and (sp.r0, sp.r1) == (f.r0, f.r1):
                q0, q1 = at[sp.z0], at[sp.z1]
                e0 = np.where(np.abs(q1 - e0) < 1e-12, np.minimum(e0, q0), e0)
                e1 = np.where(np.abs(q0 - e1) < 1e-12, np.maximum(e1, q1), e1)
        # what the fringes' legs may run through
        near = _window_layers(at, f, _window_regions(at, f, radii), r1 - r0, mu)
        for z, (zname, z0, z1) in enumerate(zones):
            a, b = wall(inner, zname), wall(outer, zname)
            lo = np.maximum(np.maximum(at[a.z0], at[b.z0]), g0)
            hi = np.minimum(np.minimum(at[a.z1], at[b.z1]), g1)
            length = np.where(_overlap(lo, hi, z0, z1) > 0, np.maximum(hi - lo, 0.0), 0.0)
            gap_len[:, k, z] = length
            # Fringing past each end of the walls' overlap, into the fluid on the film's
            # radii there (up to the plane midway to the other zone, pockets included): two
            # flush edges a gap g apart, a depth h beyond them, add the permeance of the
            # tubes μ·(2πr)·ln(1 + πh/g)/π ([roters1941] ch. 5, fringing at flush pole
            # edges), i.e. a length δ = (g/π)·ln(1 + πh/g) per end: a tube at depth s
            # crosses the film (g) and runs πs round the walls' ends. The torque reads the
            # field the tubes leave in the film's own fluid (``fringe_h``), H_e·g/(g + cπs):
            # their legs round the ends run through the laminate beside the film (a gap's
            # width of it on each side: stainless bands, the next film's fluid, the sleeve
            # and the coil), which takes a share of the MMF that the fluid then does not
            # see, or along a wall that goes on (the core): c from ``_fringe_decay``
            # (``fringe_c``; 1 in fluid, 1.23 between 0.6 mm bands at a 1 mm gap, 1.74 at
            # 0.2 mm, 1.54 at the outer film beside the sleeve and the coil, 0.5–0.9
            # beside the core). The permeance keeps Roters' homogeneous tubes: with δ
            # shortened to (g/cπ)·ln(1 + cπh/g) as well, the reference map's share within
            # ±5 % fell from 92.7 to 90.1 % (random 98.5 to 96.7 %; docs/magnetics.md,
            # "The fringe's field").
            gap = r1 - r0
            mid = 0.5 * (zb0 + za1)
            h_lo = np.maximum(lo - np.maximum(g0, mid if z else g0), 0.0)
            h_hi = np.maximum(np.minimum(g1, mid if not z else g1) - hi, 0.0)
            x_lo = np.maximum(lo - np.maximum(e0, mid if z else e0), 0.0)
            x_hi = np.maximum(np.minimum(e1, mid if not z else e1) - hi, 0.0)
            c = np.stack([_fringe_decay(f, near, lo, gap, mu, -1),
                          _fringe_decay(f, near, hi, gap, mu, 1)], axis=-1)  # fmt: skip
            fringe = (gap / np.pi) * (np.log1p(np.pi * x_lo / gap) + np.log1p(np.pi * x_hi / gap))
            eff = length + (fringe if fringing else 0.0)
            if fringing:
                ok = (length > 0)[:, None]
                fringe_h[:, k, z] = np.where(ok, np.stack([h_lo, h_hi], axis=-1), 0.0)
                fringe_c[:, k, z] = c
            gap_eff[:, k, z] = np.where(length > 0, eff, 0.0)
            # 1 Gauss point in ln r: exact for a linear material ([roters1941] ch. 5)
            rg_ = np.sqrt(r0 * r1)
            ok = length > 0
            fluid_k[:, k, z] = np.where(ok, 1 / (2 * np.pi * rg_ * np.where(ok, eff, 1)), 0)
            fluid_w[:, k, z] = np.where(ok, rg_ * np.log(r1 / r0), 0.0)
            if k > 0:  # the drum wall inside film k, radially over its zone overlap
                w0, w1, c0, c1 = box(a)
                lw = _overlap(c0, c1, z0, z1)
                rw = np.sqrt(w0 * w1)
                okw = lw > 0
                wall_k[:, k, z] = np.where(okw, 1 / (2 * np.pi * rw * np.where(okw, lw, 1)), 0)
                wall_w[:, k, z] = np.where(okw, rw * np.log(w1 / w0), 0.0)
                # the same wall axially: flux builds up linearly over the zone, so
                # ∫0^L H(Φ z/(L A)) dz = L·H̄(Φ/A), the exact mean (a build-up kernel)
                area = np.pi * (w1**2 - w0**2)
                rung_k[:, k, z, 0] = np.where(okw, 1.0 / area, 0.0)
                rung_w[:, k, z, 0] = lw
    # Rungs' band: regions spanning the band on a wall's stations (linear, μA/l), in
    # parallel with half of each neighbouring film's fluid (its own B–H: the band's axial
    # field reaches ~10⁵ A/m at 7 A, where the fluid's secant μ is 0.7 of its initial μ).
    spans = [sp for sp in rg if sp.role != "steel"]
    for k in range(1, m):
        w = wall(films[k].walls[0], "A")
        for sp in spans:
            if sp.r0 == w.r0 and sp.r1 == w.r1:
                share = 1.0
            elif sp.film == "cylinder" and (sp.r1 == w.r0 or sp.r0 == w.r1):
                share = 0.5
            else:
                continue
            r0, r1, c0, c1 = box(sp)
            across = (c0 <= za1) & (c1 >= zb0)
            area = np.pi * (r1**2 - r0**2)
            part = np.where(across, share * area, 0.0)
            if sp.role == "fluid":
                rung_fluid[:, k] += part
            else:
                rung_perm[:, k] += mu[sp.material] * part / band
    core = box(steel["core"])
    core_area = np.pi * core[1] ** 2
    core_k, core_w = (1 / core_area)[:, None], band[:, None]  # the core over the band
    for z, length in enumerate((za1 - za0, zb1 - zb0)):  # and in each zone (rung 0)
        rung_k[:, 0, z, 0] = 1 / core_area
        rung_w[:, 0, z, 0] = length
    # Fluid sheaths: the films carry axial flux too (the FEM's band plane on 1 drum at 0.1
    # mm and 7 A: 22 µWb in the two films' fluid against 26 in the core, 0.25 in the drum).
    # Each wall's steel in a zone is in parallel with half of each neighbouring film's
    # fluid beside it, axially, its flux building up over the zone as the wall's does
    # (the radial and the axial branch of the same region, as in a 2-D permeance mesh,
    # [ostovic1989]); the core over the band with half of film 0 beside it (the
    # drums' band elements hold the rest of the fluid over the band, the window the outer
    # film's outer half).
    half = 0.5 * np.pi * (gap_r1**2 - gap_r0**2)  # (S, m)
    sheath = half.copy()
    sheath[:, 1:] += half[:, :-1]  # wall j: films j − 1 and j
    steel_w = rung_w.sum(-1)  # (S, m, 2): each wall's length in each zone
    has = steel_w > 0
    sheath_k = np.where(has, 1.0 / sheath[..., None], 0.0)[..., None]  # a build-up kernel
    sheath_w = np.where(has, steel_w, 0.0)[..., None]
    f0 = box(films[0])
    across0 = (f0[2] <= za1) & (f0[3] >= zb0)
    core_sheath_k = np.where(across0, 1.0 / half[:, 0], 0.0)[:, None]
    core_sheath_w = np.where(across0, band, 0.0)[:, None]
    pa, pb, back = box(steel["shell_A"]), box(steel["shell_B"]), box(steel["shell_back"])
    x, wt = np.polynomial.legendre.leggauss(_POLE_POINTS)
    sk, sw = [], []
    for p in (pa, pb):
        u0, u1 = np.log(p[0]), np.log(back[0])
        r = np.exp(0.5 * (u0 + u1)[:, None] + 0.5 * (u1 - u0)[:, None] * x)
        sk.append(1 / (2 * np.pi * r * (p[3] - p[2])[:, None]))
        sw.append(0.5 * wt * (u1 - u0)[:, None] * r)
    back_k = (1 / (np.pi * (back[1] ** 2 - back[0] ** 2)))[:, None]
    back_w = (0.5 * (zb0 + zb1) - 0.5 * (za0 + za1))[:, None]
    # Coil window: sleeve and coil between the pole radius and the back iron, half the
    # outer film over the band. In the coil the band's MMF falls linearly from the inner to
    # the outer winding radius, so a ring at r carries μ·(ro − r)/d of the sleeve's field.
    perm_w, fluid_w_area = np.zeros(size), np.zeros(size)
    for sp in spans:
        r0, r1, c0, c1 = box(sp)
        across = (c0 <= za1) & (c1 >= zb0)
        if sp.film == "cylinder" and sp.r1 == films[-1].r1:
            area = 0.5 * np.pi * (r1**2 - r0**2)
        elif sp.part == "coil":  # ∫ 2πr·(r1 − r)/d dr over the coil = π·d·(r1 + 2 r0)/3
            area = np.pi * (r1 - r0) * (r1 + 2 * r0) / 3
        elif sp.r0 == films[-1].r1:  # the sleeve, on the pole radius over the band
            area = np.pi * (r1**2 - r0**2)
        else:
            continue
        if sp.role == "fluid":
            fluid_w_area += np.where(across, area, 0.0)
        else:
            perm_w += np.where(across, mu[sp.material] * area / band, 0.0)
    return Network(
        turns=np.broadcast_to(np.asarray(rg.fields["coil_turns"], dtype=float), (size,)).copy(),
        film_name=tuple(f.name for f in films), gap_eff=gap_eff, fringe_h=fringe_h,
        fringe_c=fringe_c,
        gap_r0=gap_r0, gap_r1=gap_r1, gap_len=gap_len, fluid_k=fluid_k, fluid_w=fluid_w,
        wall_k=wall_k, wall_w=wall_w, rung_k=rung_k, rung_w=rung_w,
        rung_perm=rung_perm, rung_fluid=rung_fluid, band_len=band,
        core_k=core_k, core_w=core_w, core_sheath_k=core_sheath_k, core_sheath_w=core_sheath_w,
        sheath_k=sheath_k, sheath_w=sheath_w,
        shell_k=np.concatenate(sk, axis=1), shell_w=np.concatenate(sw, axis=1),
        back_k=back_k, back_w=back_w, window_perm=perm_w,
        window_fluid=fluid_w_area,
        outer_air=1.0 / outer_air.permeance(at["outer"], band, za1 - pa[2], pb[3] - zb0,
                                            0.5 * (pa[0] + pb[0])),
        end_leak=_end_leak(rg, at, mats, [wall(films[k].walls[0], z) for k in range(m)
                                          for z in ("A", "B")]),
        steel=rg.materials.drums, fluid=rg.materials.fluid, core_steel=rg.materials.core,
        shell_steel=rg.materials.shell,
    )  # fmt: skip


def _stacked_radii(
    at: Mapping[str, FloatArray], rg: Regions
) -> tuple[list[RegionSpec], FloatArray, FloatArray]:
    """Every region of ``rg`` with its inner and outer radii stacked (R, S), once per
    build: ``_window_regions`` asks per film, and a Python loop over the regions per film
    was half of a 20-drum design's evaluate."""
    specs = list(rg)
    return specs, np.stack([at[sp.r0] for sp in specs]), np.stack([at[sp.r1] for sp in specs])


def _window_regions(
    at: Mapping[str, FloatArray],
    f: RegionSpec,
    radii: tuple[list[RegionSpec], FloatArray, FloatArray],
) -> tuple[list[RegionSpec], list[RegionSpec]]:
    """The regions that reach, in some design, within one gap's width inside and outside
    film ``f``'s radii (``_fringe_decay``'s windows), the film itself left out; ``radii``
    from ``_stacked_radii``."""
    specs, r0, r1 = radii
    gap = at[f.r1] - at[f.r0]
    inside = np.any((r1 > at[f.r0] - gap) & (r0 < at[f.r0]), axis=1)
    outside = np.any((r1 > at[f.r1]) & (r0 < at[f.r1] + gap), axis=1)
    return ([sp for sp, k in zip(specs, inside, strict=True) if k and sp is not f],
            [sp for sp, k in zip(specs, outside, strict=True) if k and sp is not f])  # fmt: skip


#: One side of a film's fringe window (``_window_layers``): per region that can lie in it,
#: its z-extent, its thickness t inside the window, μ·t, and whether it is the film's wall.
_Layer = tuple[FloatArray, FloatArray, FloatArray, FloatArray, bool]


def _window_layers(
    at: Mapping[str, FloatArray],
    f: RegionSpec,
    near: tuple[list[RegionSpec], list[RegionSpec]],
    gap: FloatArray,
    mu: Mapping[str, float],
) -> tuple[list[_Layer], list[_Layer]]:
    """What ``_fringe_decay`` reads of the regions ``near`` film ``f`` (``_window_regions``),
    inner side then outer, once per film: a film's four fringes (two zones, two ends)
    differ only in the plane they probe, not in the layers' radii."""
    out: list[list[_Layer]] = []
    for inner, specs in ((True, near[0]), (False, near[1])):
        r_edge = at[f.r0] if inner else at[f.r1]
        w0, w1 = (r_edge - gap, r_edge) if inner else (r_edge, r_edge + gap)
        side = []
        for sp in specs:
            t = np.maximum(np.minimum(at[sp.r1], w1) - np.maximum(at[sp.r0], w0), 0.0)
            wall = sp.role == "steel" and (sp.r1 == f.r0 if inner else sp.r0 == f.r1)
            side.append((at[sp.z0], at[sp.z1], t, t * mu[sp.material], wall))
        out.append(side)
    return out[0], out[1]


def _fringe_decay(
    f: RegionSpec,
    layers: tuple[list[_Layer], list[_Layer]],
    edge: FloatArray,
    gap: FloatArray,
    mu: Mapping[str, float],
    side: int,
) -> FloatArray:
    """c (S,) of film ``f``'s fringe past ``edge`` (``side`` −1: below it, +1: above), its
    field in the film H(s) = H_e·g/(g + cπs): a tube at depth s runs a leg of (π/2)s round
    each wall's end, c = Σ over the two sides of ½·μf/μ_side. A side whose steel goes on past
    the edge (the core over the band) has no leg. Elsewhere the leg runs through the
    laminate of the film's fluid (g) and what lies within one gap's width g beyond the
    film's radius on that side, just past the edge (a drum's band and the next film's
    fluid, the sleeve and the coil; air where no region is): the tubes whose field matters
    lie at depths s ~ g, whose legs reach about that far. Along its layers a laminate's μ
    is their thickness-weighted mean ([wiener1912]). In fluid only, c = 1: Roters' tubes.
    Steel going on on both sides (no legs): the film goes on at H_e, c → 0, kept at 1e-6 so
    that (g/cπ)·ln(1 + cπh/g) = h to 1e-6 without 0/0. ``layers``: the regions that can lie
    in the inner and the outer window (``_window_layers``)."""
    probe = edge + side * 1e-9  # just past the walls' end, m
    c = np.zeros_like(gap)
    for near in layers:
        num, den = gap * mu[f.material], gap.copy()
        steel = np.zeros(gap.shape, bool)
        for z0, z1, t, tmu, wall in near:
            there = (z0 <= probe) & (probe < z1)
            if wall:
                steel |= there  # the wall itself goes on
            # μ·t and t where the region is (elsewhere + 0: num, den > 0 stay as they are)
            np.add(num, tmu, out=num, where=there)
            np.add(den, t, out=den, where=there)
        air = np.maximum(2 * gap - den, 0.0)  # the window's part no region covers
        c += np.where(steel, 0.0, 0.5 * mu[f.material] * (den + air) / (num + air * MU0))
    return np.maximum(c, 1e-6)


def _end_leak(rg: Regions, at, mats, walls: list[RegionSpec]) -> FloatArray:  # type: ignore[no-untyped-def]
    """Reluctance (S, 2) of the path from each pole to the core past the far end of its
    zone, in front of the drums' and the core's ends: the pole's inner face (radius r_p)
    over its length beyond the walls, radially in to the core's radius r_c through the
    regions there (hub, fluid films, pockets), each slab of regions between consecutive
    z-edges a series of exact cylindrical reluctances ln(r1/r0)/(2πμΔz) ([roters1941]
    ch. 5), the slabs in parallel; air (μ0) where no region lies. The short axial entry
    into the core's face is left out. Where the walls reach the pole's end the path is
    absent (reluctance 1e15 /H). The FEM sends 1.4·10⁻⁵ Wb through the paper preset's
    core face at 7 A this way (docs/magnetics.md)."""
    mats = MATERIALS if mats is None else mats
    size = np.size(at["outer"])
    mu = {sp.material: magnetic(sp.material, mats).mu_initial for sp in rg}
    steel = {sp.name: sp for sp in rg if sp.role == "steel"}
    r_c = at[steel["core"].r1]
    out = np.full((size, 2), 1e15)
    for z, pole in enumerate((steel["shell_A"], steel["shell_B"])):
        r_p = at[pole.r0]
        ends = np.stack([at[w.z0 if z == 0 else w.z1] for w in walls
                         if (w.name.endswith("_A") if z == 0 else w.name.endswith("_B"))
                         or w.name == "core"], axis=1)  # fmt: skip
        lo, hi = (at[pole.z0], ends.min(axis=1)) if z == 0 else (ends.max(axis=1), at[pole.z1])
        # the regions that reach into the box [lo, hi] × [r_c, r_p] in some design
        cand = [sp for sp in rg if np.any((at[sp.z1] > lo) & (at[sp.z0] < hi)
                                          & (at[sp.r1] > r_c) & (at[sp.r0] < r_p))]  # fmt: skip
        if not cand:
            continue
        edges = np.stack([lo, hi, *(at[e] for sp in cand for e in (sp.z0, sp.z1))], axis=1)
        e = np.sort(np.clip(edges, lo[:, None], hi[:, None]), axis=1)
        # each candidate's radial span inside [r_c, r_p] and its ln(r1/r0), the same in
        # every slab
        radial = []
        for sp in cand:
            a0 = np.maximum(at[sp.r0], r_c)
            a1 = np.minimum(at[sp.r1], r_p)
            weight = 0.0 if sp.role == "steel" else 1.0 / mu[sp.material]
            radial.append((at[sp.z0], at[sp.z1], a1 > a0, np.log(np.maximum(a1, a0) / a0),
                           weight))  # fmt: skip
        perm = np.zeros(size)
        for j in range(e.shape[1] - 1):
            z0, z1 = e[:, j], e[:, j + 1]
            dz, zm = z1 - z0, 0.5 * (z0 + z1)
            series = np.zeros(size)  # Σ ln(r1/r0)/μ over the slab's radial path
            covered = np.zeros(size)
            for c0, c1, spans, lnr, weight in radial:
                inside = (c0 <= zm) & (zm < c1) & (dz > 0)
                ln = np.where(inside & spans, lnr, 0.0)
                series += ln * weight
                covered += ln
            series += np.maximum(np.log(r_p / r_c) - covered, 0.0) / MU0  # air
            perm += np.where(dz > 0, 2 * np.pi * dz / np.where(series > 0, series, 1.0), 0.0)
        out[:, z] = np.where(perm > 0, 1.0 / np.where(perm > 0, perm, 1.0), 1e15)
    return out
