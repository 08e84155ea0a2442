"""Saturating magnetic circuit of the two-zone drum clutch, vectorised, bracketed solver.

One flux loop: core (axial) → zone A (every gap and steel drum wall radially) → pole A
(radially) → back iron (axial) → pole B → zone B → core. Each element's MMF drop is
``∫ H(B(r)) dr`` with ``B = Φ/(2π r L)`` for radial elements (Gauss–Legendre in ln r:
exact for a linear material, whose reluctance is ln(r1/r0)/(2π μ L) — [roters1941],
ch. 5) and ``H(Φ/A)·l`` for axial ones.

Gap length: a gap carries the zone's flux where its two steel walls face each other (the
overlap of the walls' steel, inside the gap's wetted length). For the outermost gap in
zone A that is the zone plus the end clearance, because the pole and the outer drum both
reach the hub.

Leakage: the flux that leaves pole A and returns to pole B without crossing the zones
(through the sleeve and coil window, μ0, and through the stainless bands and the fluid
between the drums over the band) is a parallel permeance ``P_leak`` across the stack's MMF
``F_stack(Φ)``; it loads the poles and back iron, not the gaps. The loop equation

    N·I = F_stack(Φ) + F_shell(Φ + P_leak·F_stack(Φ))

stays a single equation, strictly increasing in the gap flux Φ (a composition and sum of
increasing functions), so a bracket [0, Φ_hi] with F(Φ_hi) ≥ N·I always exists (every H(B)
grows at least like B/μ0 past saturation) and safeguarded Newton inside it cannot diverge.

Band field (torque only): over the non-magnetic band the magnetic potential between the
core and the pole radius falls linearly from the zone's radial MMF ``F_r`` at the zone's
end to 0 at the band's centre (the coil is a uniform current sheet between the poles, and
the band's centre is the plane of antisymmetry). This is Roters' linear-potential
assumption for the leakage between the pole faces of a distributed winding ([roters1941],
ch. 5 "leakage flux", the field of a uniformly wound coil; also [hanselman] §2.6 for the
same 1-D treatment). Radially the band stack is a series of fluid gaps and stainless drum
walls, so a gap at radius r sees
``B(x) = F_r·(1 − 2x/b)/(r·S_b)`` with ``S_b = Σ ln(ro/ri)/μ`` over the band's layers (fluid
at its initial μ); that field's yield stress adds torque over the band (the FEM shows it is
~10 % of the total). It is not fed back into the loop (its flux is part of the leakage).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.materials import MRF, STEEL
from geometry.params import DrumClutch
from geometry.regions import ZONES, Regions
from geometry.section import Section, build_section
from geometry.validation import ParameterError
from magnetics.materials import MATERIALS, MU0, BHCurve, Magnetic, magnetic

FloatArray = NDArray[np.float64]
FLUID = MRF
_POLE_POINTS = 3  # Gauss points in ln r for the thick pole rings
#: A steel element is reported saturated where its differential μr falls below this.
SATURATION_MU_R = 100.0


@dataclass(frozen=True)
class MagneticPath:
    """The loop's elements for S designs (arrays with leading axis S).

    ``gap_*`` (S, K): the field-carrying part of each sheared gap in each zone (K = both
    zones), radii and length (steel-wall overlap); ``drum_*`` (S, D): steel drum walls
    radially crossed in the zones; ``pole_*`` (S, 2); ``core_*``/``back_*`` (S,): axial area
    and length; ``leak_permeance`` (S,) H; ``turns`` (S,); ``band_len`` (S,) m and
    ``band_reluctance`` (S,) m/H·rad (``S_b`` of the module docstring).
    """

    turns: FloatArray
    gap_r0: FloatArray
    gap_r1: FloatArray
    gap_len: FloatArray
    gap_mask: NDArray[np.bool_]
    gap_label: tuple[str, ...]
    drum_r0: FloatArray
    drum_r1: FloatArray
    drum_len: FloatArray
    drum_mask: NDArray[np.bool_]
    pole_r0: FloatArray
    pole_r1: FloatArray
    pole_len: FloatArray
    core_area: FloatArray
    core_len: FloatArray
    back_area: FloatArray
    back_len: FloatArray
    leak_permeance: FloatArray
    band_len: FloatArray
    band_reluctance: FloatArray
    steel: str = STEEL  # the drums' steel
    fluid: str = FLUID
    core_steel: str = STEEL
    shell_steel: str = STEEL  # the poles and the back iron

    @property
    def gap_r_mid(self) -> FloatArray:
        return 0.5 * (self.gap_r0 + self.gap_r1)


def _leak_permeance(
    mu_fluid: float,
    band: FloatArray,
    fluid_area: FloatArray,
    nonmag_stack: FloatArray,
    window: FloatArray,
) -> FloatArray:
    # Axial permeance μA/l of the band region ([roters1941] ch. 5); fluid and stainless inside the
    # stack at half weight (linear potential drop across the stack), sleeve + coil at full.
    return (0.5 * (mu_fluid * fluid_area + MU0 * nonmag_stack) + MU0 * window) / band


def band_series_reluctance(
    rg: Regions, materials: Mapping[str, Magnetic] | None = None
) -> FloatArray:
    """S_b = Σ ln(ro/ri)/μ (initial μ) over the regions that span the band axially between
    the core and the pole radius: the band's radial series reluctance per radian and metre
    (the band field of the module docstring), shape S."""
    mats = MATERIALS if materials is None else materials
    size = np.size(rg.at["outer"])
    at = {k: np.broadcast_to(np.asarray(v, dtype=float), (size,)) for k, v in rg.at.items()}
    (_, _, za1), (_, zb0, _) = ZONES
    rc, rp = rg.core_radius, rg.pole_radius
    s_band = np.zeros(size)
    for sp in rg:
        r0, r1 = at[sp.r0], at[sp.r1]
        layer = (at[sp.z0] <= at[za1]) & (at[sp.z1] >= at[zb0]) & (r0 >= rc) & (r1 <= rp)
        if not layer.any():
            continue  # adds 0 to every design (most regions: no log to take)
        mu = magnetic(sp.material, mats).mu_initial
        s_band = s_band + np.where(layer, np.log(r1 / np.where(layer, r0, r1)) / mu, 0.0)
    return s_band


def path_from_regions(rg: Regions, materials: Mapping[str, Magnetic] | None = None) -> MagneticPath:
    """The loop of the designs of one region table (S designs of one drum count).

    Read from the table, not laid out again: a gap's walls are the steel regions that share
    its edge stations, the length it carries flux over is where those walls face each
    other inside the gap's wetted length and an active zone; the drum walls are the steel
    regions of the rotor and input parts, crossed over their overlap with each zone; the
    leakage and band reluctance come from the regions that span the band between the core
    and the back iron.
    """
    mats = MATERIALS if materials is None else materials
    size = np.size(rg.at["outer"])
    at = {k: np.broadcast_to(np.asarray(v, dtype=float), (size,)) for k, v in rg.at.items()}
    col = lambda v: np.broadcast_to(np.asarray(v, dtype=float), (size,))  # noqa: E731

    def box(sp):  # type: ignore[no-untyped-def]
        return at[sp.r0], at[sp.r1], at[sp.z0], at[sp.z1]

    steels = [sp for sp in rg if sp.role == "steel"]
    gaps = rg.films("cylinder")
    zones = [(name, at[a], at[b]) for name, a, b in ZONES]
    gap_r0, gap_r1, gap_len, labels = [], [], [], []
    for zname, z0, z1 in zones:
        for g in gaps:
            _, _, g0, g1 = box(g)
            length = np.zeros(size)
            for a in (w for w in steels if w.r1 == g.r0):  # inner walls
                for b in (w for w in steels if w.r0 == g.r1):  # outer walls
                    lo = np.maximum(np.maximum(at[a.z0], at[b.z0]), g0)
                    hi = np.minimum(np.minimum(at[a.z1], at[b.z1]), g1)
                    facing = (hi > lo) & (np.minimum(hi, z1) > np.maximum(lo, z0))
                    length = length + np.where(facing, hi - lo, 0.0)
            if np.any(length > 0):
                gap_r0.append(at[g.r0])
                gap_r1.append(at[g.r1])
                gap_len.append(length)
                labels.append(f"{g.name}_{zname}")
    drum_r0, drum_r1, drum_len = [], [], []
    for _, z0, z1 in zones:
        for sp in steels:
            if sp.part in ("rotor", "input"):
                r0, r1, a0, a1 = box(sp)
                length = np.maximum(np.minimum(a1, z1) - np.maximum(a0, z0), 0.0)
                if np.any(length > 0):
                    drum_r0.append(r0)
                    drum_r1.append(r1)
                    drum_len.append(length)
    core, back = box(rg.spec("core")), box(rg.spec("shell_back"))
    pole_a, pole_b = box(rg.spec("shell_A")), box(rg.spec("shell_B"))
    # Leakage over the band (zone A's end to zone B's start): what lies between the core
    # and the back iron there; the band's radial series reluctance S_b from the core to
    # the pole radius (series layers: Σ ln(ro/ri)/μ).
    (_, za0, za1), (_, zb0, _) = zones
    band = zb0 - za1
    mu_f = magnetic(rg.materials.fluid, mats).mu_initial
    fluid_area = nonmag = window = np.zeros(size)
    rc, rp = core[1], pole_a[0]
    for sp in rg:
        r0, r1, a0, a1 = box(sp)
        spans = (a0 <= za1) & (a1 >= zb0) & (r0 >= rc)
        if not spans.any():
            continue  # adds 0 to every design
        area = np.pi * (r1**2 - r0**2)
        layer = spans & (r1 <= rp)
        if sp.role == "fluid":
            fluid_area = fluid_area + np.where(layer, area, 0.0)
        elif sp.role != "steel":
            nonmag = nonmag + np.where(layer, area, 0.0)
        window = window + np.where(spans & ~layer & (r1 <= back[0]), area, 0.0)
    stack = lambda xs: np.stack(xs, axis=1) if xs else np.zeros((size, 0))  # noqa: E731
    zc = 0.5 * (za0 + za1), 0.5 * (zb0 + zones[1][2])
    glen = stack(gap_len)
    dlen = stack(drum_len)
    return MagneticPath(
        turns=col(rg.fields["coil_turns"]).astype(float),
        gap_r0=stack(gap_r0), gap_r1=stack(gap_r1), gap_len=glen, gap_mask=glen > 0,
        gap_label=tuple(labels),
        drum_r0=stack(drum_r0), drum_r1=stack(drum_r1), drum_len=dlen, drum_mask=dlen > 0,
        pole_r0=stack([pole_a[0], pole_b[0]]), pole_r1=stack([back[0], back[0]]),
        pole_len=stack([pole_a[3] - pole_a[2], pole_b[3] - pole_b[2]]),
        core_area=np.pi * rc**2, core_len=zc[1] - zc[0],
        back_area=np.pi * (back[1] ** 2 - back[0] ** 2), back_len=zc[1] - zc[0],
        leak_permeance=_leak_permeance(mu_f, band, fluid_area, nonmag, window),
        band_len=band, band_reluctance=band_series_reluctance(rg, mats),
        steel=rg.materials.drums, fluid=rg.materials.fluid, core_steel=rg.materials.core,
        shell_steel=rg.materials.shell,
    )  # fmt: skip


def path_from_section(
    section: Section, materials: Mapping[str, Magnetic] | None = None
) -> MagneticPath:
    """The loop of one design (S = 1): ``path_from_regions`` of the section's table."""
    if section.table is None:
        raise ParameterError("section: built by hand, without a region table; no circuit")
    return path_from_regions(section.table, materials)


@dataclass(frozen=True)
class _Kernels:
    """Element MMF = Σ_points w·H(k·Φ) (masked entries have w = k = 0); ``wk`` = w·k.

    Arrays are (J, S), points first, so the sums over points add whole rows (fast).

    ``gap``: fluid at the gap flux; ``drum``: steel drum walls (stack radial MMF);
    ``core``: axial core; ``shell``: poles and back iron at the shell flux.
    """

    gap_k: FloatArray
    gap_w: FloatArray
    gap_wk: FloatArray
    drum_k: FloatArray
    drum_w: FloatArray
    drum_wk: FloatArray
    core_k: FloatArray
    core_w: FloatArray
    core_wk: FloatArray
    shell_k: FloatArray
    shell_w: FloatArray
    shell_wk: FloatArray
    leak: FloatArray

    def rows(self, idx: np.ndarray) -> _Kernels:
        """The kernels of the designs ``idx`` only (the solver drops converged rows)."""
        return _Kernels(*(a[idx] if a.ndim == 2 else a[:, idx] for a in
                          (getattr(self, f.name) for f in dataclasses.fields(self))))  # fmt: skip


@functools.lru_cache(maxsize=8)
def _gauss(n: int) -> tuple[FloatArray, FloatArray]:
    """Gauss–Legendre nodes and weights on [−1, 1], computed once per order."""
    x, wt = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = wt.flags.writeable = False
    return x, wt


def _radial(r0: FloatArray, r1: FloatArray, length: FloatArray, n: int, mask=None):  # type: ignore[no-untyped-def]
    """Gauss–Legendre in u = ln r of ∫ H(Φ/(2π e^u L)) e^u du.

    Returns (k, w) of shape (S, K·n): B = k·Φ at each point, MMF = Σ w·H. Exact for a
    linear material (the integrand is then constant in u).
    """
    x, wt = _gauss(n)
    u0, u1 = np.log(r0), np.log(r1)
    r = np.exp(0.5 * (u0 + u1)[..., None] + 0.5 * (u1 - u0)[..., None] * x)
    k = 1.0 / (2 * np.pi * r * length[..., None])
    w = 0.5 * wt * (u1 - u0)[..., None] * r
    if mask is not None:
        w = np.where(mask[..., None], w, 0.0)
        k = np.where(mask[..., None], k, 0.0)
    flat = (k.shape[0], int(np.prod(k.shape[1:])))  # explicit: -1 is ambiguous for S = 0
    return k.reshape(flat), w.reshape(flat)


def _kernels(path: MagneticPath) -> _Kernels:
    """The path's integration kernels, built once per path (every solve on it reuses them)."""
    cached = path.__dict__.get("_kernels_cache")
    if cached is None:
        cached = _build_kernels(path)
        object.__setattr__(path, "_kernels_cache", cached)
    return cached


def _build_kernels(path: MagneticPath) -> _Kernels:
    gk, gw = _radial(path.gap_r0, path.gap_r1, path.gap_len, 1, path.gap_mask)
    dk, dw = _radial(path.drum_r0, path.drum_r1, path.drum_len, 1, path.drum_mask)
    pk, pw = _radial(path.pole_r0, path.pole_r1, path.pole_len, _POLE_POINTS)
    col = lambda v: np.asarray(v, dtype=float)[:, None]  # noqa: E731
    sk = np.concatenate([pk, col(1 / path.back_area)], axis=1)
    sw = np.concatenate([pw, col(path.back_len)], axis=1)
    ck, cw = col(1 / path.core_area), col(path.core_len)
    t = lambda a: np.ascontiguousarray(a.T)[:, :, None]  # noqa: E731  (J, S, 1)
    return _Kernels(t(gk), t(gw), t(gk * gw), t(dk), t(dw), t(dk * dw), t(ck), t(cw), t(ck * cw),
                    t(sk), t(sw), t(sk * sw), col(path.leak_permeance))  # fmt: skip


def _sum_h(mat: Magnetic, phi: FloatArray, k: FloatArray, w: FloatArray, wk: FloatArray):  # type: ignore[no-untyped-def]
    """Σ_j w_j·H(k_j·Φ) and its Φ-derivative Σ_j w_j·k_j·H'(k_j·Φ); Φ ≥ 0 (S, C), k (J, S, 1)."""
    return mat.h_dh_sum(k, phi, w, wk)


def _mmf(
    path: MagneticPath, mats: Mapping[str, Magnetic], phi: FloatArray, kern: _Kernels | None = None
) -> dict[str, FloatArray]:
    """MMF drops (A) at gap flux ``phi`` ≥ 0 (S, C): radial (gaps + drums, both zones),
    stack, shell flux, total and dF/dΦ; ``dstack`` = dF_stack/dΦ, ``dshell`` = dF_shell/dΦ_shell
    (the incremental reluctances of the two branches, for the inductance)."""
    kn = _kernels(path) if kern is None else kern
    steel, fluid = magnetic(path.steel, mats), magnetic(path.fluid, mats)
    g, dg = _sum_h(fluid, phi, kn.gap_k, kn.gap_w, kn.gap_wk)
    d, dd = _sum_h(steel, phi, kn.drum_k, kn.drum_w, kn.drum_wk)
    c, dc = _sum_h(magnetic(path.core_steel, mats), phi, kn.core_k, kn.core_w, kn.core_wk)
    radial = g + d
    stack = radial + c
    dstack = dg + dd + dc
    shell = phi + kn.leak * stack
    s, ds = _sum_h(magnetic(path.shell_steel, mats), shell, kn.shell_k, kn.shell_w, kn.shell_wk)
    return {"gaps": g, "radial": radial, "stack": stack, "phi_shell": shell,
            "total": stack + s, "dstack": dstack, "dshell": ds,
            "dtotal": dstack + ds * (1.0 + kn.leak * dstack)}  # fmt: skip


def linear_flux(
    path: MagneticPath, ampere_turns: ArrayLike, materials: Mapping[str, Magnetic] | None = None
) -> FloatArray:
    """Gap flux Φ (Wb), (S, C), of the unsaturated circuit (every material on its initial
    slope) at ``ampere_turns`` (S, C): |N·I|/F'(0), ``solve_flux``'s first iterate."""
    mats = MATERIALS if materials is None else materials
    ni = np.abs(np.atleast_2d(np.asarray(ampere_turns, dtype=float)))
    return ni / _mmf(path, mats, np.zeros((path.turns.size, 1)))["dtotal"]


def solve_flux(
    path: MagneticPath,
    ampere_turns: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    rtol: float = 1e-12,
    max_iter: int = 200,
    kernels: _Kernels | None = None,
    start: FloatArray | None = None,
) -> FloatArray:
    """Gap flux Φ (Wb), shape (S, C), solving N·I = F(Φ) for ``ampere_turns`` (S, C);
    ``start`` (S, C), a first guess (e.g. the flux at a nearby current), replaces the
    linear circuit's flux as the first iterate.

    Safeguarded Newton ([numerical-recipes] §9.4 "rtsafe") on the strictly increasing F,
    started at the linear (unsaturated) circuit's flux: the bracket [lo, hi] always
    contains the root and shrinks every step; a Newton step that would leave it is
    replaced by bisection, so it cannot diverge. Negative N·I is solved by symmetry.
    """
    mats = MATERIALS if materials is None else materials
    ni = np.atleast_2d(np.asarray(ampere_turns, dtype=float))
    ni = np.broadcast_to(ni, (path.turns.size, ni.shape[-1]))
    if not np.all(np.isfinite(ni)):
        raise ParameterError("current: must be finite")
    sign, target = np.sign(ni), np.abs(ni)
    kn = _kernels(path) if kernels is None else kernels

    def f(phi: FloatArray) -> tuple[FloatArray, FloatArray]:
        m = _mmf(path, mats, phi, kn)
        return m["total"] - target, m["dtotal"]

    # Linear (unsaturated) circuit: Φ = N·I / F'(0). Exact below the tables' first
    # segment, and the first Newton iterate otherwise.
    if start is None:
        x = target / f(np.zeros((target.shape[0], 1)))[1]
    else:
        x = np.broadcast_to(np.abs(np.asarray(start, dtype=float)), target.shape).copy()
    # |NI| < 1e-100 A (down to subnormals): the linear regime is exact to rounding.
    tiny = target < 1e-100
    out = x.copy()
    rows = np.arange(x.shape[0])  # the designs still iterating; converged ones are dropped
    lo, hi = np.zeros_like(x), np.full_like(x, np.inf)
    for _ in range(max_iter):
        fx, dfx = f(x)
        right = fx >= 0
        lo = np.where(right, lo, x)
        hi = np.where(right, x, hi)
        closed = np.isfinite(hi) & ((hi - lo) <= rtol * hi)
        done = (np.abs(fx) <= rtol * target) | closed | tiny
        if done.all():
            out[rows] = x
            break
        newton = x - fx / np.where(dfx > 0, dfx, np.inf)
        ok = (newton > lo) & (newton < hi) & (dfx > 0)
        # no upper bound yet: double (F grows at least like Φ/μ0, so this brackets)
        fallback = np.where(np.isinf(hi), 2 * x, 0.5 * (lo + hi))
        x = np.where(done, x, np.where(ok, newton, fallback))
        keep = ~done.all(axis=1)
        if keep.sum() < 0.7 * keep.size:  # compact: later iterations cost only what is left
            out[rows[~keep]] = x[~keep]
            rows, x, lo, hi = rows[keep], x[keep], lo[keep], hi[keep]
            target, tiny, kn = target[keep], tiny[keep], kn.rows(np.flatnonzero(keep))
    else:
        raise ParameterError(f"circuit: no convergence in {max_iter} iterations")
    x = out
    return x * sign


@dataclass(frozen=True)
class CircuitResult:
    """Solution of the loop for S designs × C currents (arrays (S, C) or (S, C, K))."""

    current: FloatArray  # (S, C) A
    flux: FloatArray  # gap flux (S, C) Wb
    flux_shell: FloatArray  # back-iron flux incl. leakage (S, C) Wb
    gap_label: tuple[str, ...]
    gap_r_mid: FloatArray  # (S, K) m
    gap_len: FloatArray  # (S, K) m
    gap_b: FloatArray  # (S, C, K) T at mid-radius
    gap_h: FloatArray  # (S, C, K) A/m
    radial_mmf: FloatArray  # (S, C) A, radial MMF across the stack of one zone
    steel_b: Mapping[str, FloatArray]  # element -> |B| (S, C), T (largest along the element)
    saturated: Mapping[str, NDArray[np.bool_]]  # element -> differential μr < 100


def solve(
    clutch: DrumClutch | Section,
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
) -> CircuitResult:
    """Solve the circuit of one design for an array of currents (A)."""
    section = clutch if isinstance(clutch, Section) else build_section(clutch)
    path = path_from_section(section, materials)
    return solve_path(path, np.atleast_1d(np.asarray(currents, dtype=float))[None, :], materials)


def solve_path(
    path: MagneticPath, currents: ArrayLike, materials: Mapping[str, Magnetic] | None = None
) -> CircuitResult:
    """Solve for currents of shape (S, C) (or broadcastable); everything reported."""
    mats = MATERIALS if materials is None else materials
    cur = np.asarray(currents, dtype=float)
    cur = np.broadcast_to(cur.reshape(cur.shape[0] if cur.ndim == 2 else 1, -1),
                          (path.turns.size, cur.shape[-1] if cur.ndim else 1))  # fmt: skip
    kern = _kernels(path)
    phi = solve_flux(path, path.turns[:, None] * cur, mats, kernels=kern)
    parts = _mmf(path, mats, np.abs(phi), kern)
    rmid = path.gap_r_mid
    b = np.abs(phi)[:, :, None] / (2 * np.pi * rmid * path.gap_len)[:, None, :]
    b = np.where(path.gap_mask[:, None, :], b, 0.0)
    h = magnetic(path.fluid, mats).h_of_b(b)
    shell = np.abs(parts["phi_shell"])
    sb = {
        "core": np.abs(phi) / path.core_area[:, None],
        "drums": np.max(np.where(path.drum_mask[:, None, :], np.abs(phi)[:, :, None]
                                 / (2 * np.pi * path.drum_r0 * path.drum_len)[:, None, :], 0.0),
                        axis=-1, initial=0.0),
        "pole_A": shell / (2 * np.pi * path.pole_r0[:, 0] * path.pole_len[:, 0])[:, None],
        "pole_B": shell / (2 * np.pi * path.pole_r0[:, 1] * path.pole_len[:, 1])[:, None],
        "back_iron": shell / path.back_area[:, None],
    }  # fmt: skip
    steel_of = {"core": path.core_steel, "drums": path.steel}
    sat = {}
    for k, v in sb.items():
        mat = magnetic(steel_of.get(k, path.shell_steel), mats)
        sat[k] = (mat.mu_r_differential(v) < SATURATION_MU_R if isinstance(mat, BHCurve)
                  else np.zeros(v.shape, bool))  # fmt: skip
    return CircuitResult(np.array(cur), phi, parts["phi_shell"], path.gap_label, rmid,
                         path.gap_len, b, h, 0.5 * parts["radial"], sb, sat)  # fmt: skip
