"""Time-harmonic eddy currents in the clutch's section: the reference of the eddy lag.

A sinusoidal coil current I·e^{jωt} about an operating point I_b drives, in the linearised
steel, the axisymmetric A_φ problem ∇×(ν∇×A) + jωσA = J. In the flux function ψ = r·A_φ
of ``magnetics.fem`` (test function v/r, volume 2πr dr dz; [meunier2008] §5.3, with the
eddy term jωσA·(v/r) integrated like the source):

    ∫ ν (1/r) ∇ψ·∇v dr dz + jω ∫ σ (1/r) ψ v dr dz = ∫ J_φ v dr dz,   ψ = 0 on axis and box.

* **Linearisation.** ν is the incremental reluctivity dH/dB of each material at the local
  |B| of the magnetostatic solution at I_b (``incremental``: isotropic, the same μ the 1-D
  diffusion model of ``magnetics.dynamics`` uses), or the exact small-signal tensor (the
  Newton Jacobian of ``magnetics.fem.forms``: dH/dB along B, H/B across it: ``tensor``).
* **Complex arithmetic.** scikit-fem assembles the real matrices K (ν) and M (σ); the
  system K + jωM is formed and factorised in complex arithmetic by scipy (SuperLU).
* **Gap flux.** Φ = the mean over the gaps and both zones of the radial flux through each
  gap's mid-radius: 2π(ψ(r_k, z_mid) − ψ(r_k, z_end)) per zone, z_mid the coil's centre
  plane. The response is Φ(jω)/Φ(0).
* **Equivalent delay.** To first order in ω, ψ = ψ₀ − jω K⁻¹Mψ₀, so Φ/Φ₀ = 1 − jωT with
  T = λᵀMψ₀/Φ₀, λ = K⁻¹Pᵀ (K symmetric; P the gap-flux functional): the group delay
  −dφ/dω at ω → 0, which the 1-D model's Σ weight·mean delay approximates. The integrand
  σψ₀λ/r splits T exactly into each part's share (``EddyFEM.parts``).
* **Laminations** (``magnetics.laminations.Laminations``): a laminated or slotted part carries
  no azimuthal current (σ_φ = 0: the sheets cut the path); the currents inside each sheet
  of thickness d are homogenised as a complex reluctivity ν·x/tanh(x), x = (d/2)√(jωμσ)
  (the slab's tanh(x)/x flux ratio, [stoll1974] ch. 2; a stack homogenised as in the
  paper [gyselinck1999]), whose first order jωσd²/12 is the 1-D model's mean delay μσd²/12.

Conductivities: AISI 1018 from ``magnetics.eddy_lag.STEEL_CONDUCTIVITY`` (one source of
truth); stainless 304 (hub, caps, sleeve, drum bands) is left out by default, like the 1-D
model, and ``STAINLESS_CONDUCTIVITY`` measures what it adds. scikit-fem is imported only
when a solve runs.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.materials import STAINLESS, STEEL
from geometry.materials import conductivity as material_conductivity
from geometry.section import Section
from geometry.validation import ParameterError, check_choice, check_range
from magnetics.circuit import _kernels, _mmf, path_from_section, solve_flux
from magnetics.dynamics import BIAS
from magnetics.eddy_lag import STEEL_CONDUCTIVITY, eddy_parts, eddy_transfer
from magnetics.fem import DEFAULT_SIZE, build_grid, solve_fem
from magnetics.fem.grid import Grid
from magnetics.laminations import Laminations
from magnetics.materials import MATERIALS, Magnetic

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: S/m, AISI 304 at 20 °C: ρ = 72 μΩ·cm [matweb-304].
STAINLESS_CONDUCTIVITY = 1.39e6
#: The default conductor: the magnetic steel only (what the 1-D model sees).
STEEL_ONLY: Mapping[str, float] = {STEEL: STEEL_CONDUCTIVITY}
#: Steel and the stainless parts.
WITH_STAINLESS: Mapping[str, float] = {STEEL: STEEL_CONDUCTIVITY, STAINLESS: STAINLESS_CONDUCTIVITY}
LINEARISATIONS = ("incremental", "tensor")
#: Hz, the frequencies the comparison reports the phase at.
FREQUENCIES: tuple[float, ...] = (50.0, 100.0, 200.0)
#: Part of each steel region (the 1-D model's parts); shell_A/shell_B hold the pole rings
#: and the back iron's corners, counted as poles.
_PART_OF_REGION = {"core": "core", "shell_A": "poles", "shell_B": "poles",
                   "shell_back": "back_iron"}  # fmt: skip
_LAMINATED_BY = {"core": "core", "poles": "shell", "back_iron": "shell"}


# ---- closed forms --------------------------------------------------------------------------


def cylinder_flux_ratio(omega: ArrayLike, mu: float, sigma: float, radius: float) -> ComplexArray:
    """Φ(jω)/Φ(0) of a long solid cylinder in a uniform axial field H₀e^{jωt} at its surface:
    2J₁(ka)/(ka J₀(ka)), k = √(−jωμσ) (H = H₀J₀(kr)/J₀(ka); [stoll1974] ch. 2,
    [lammeraner-stafl1964])."""
    from scipy.special import jv

    ka = np.sqrt(-1j * np.asarray(omega, float) * mu * sigma) * radius
    small = np.abs(ka) < 1e-6
    ka = np.where(small, 1.0, ka)
    return np.where(small, 1.0 + 0j, 2.0 * jv(1, ka) / (ka * jv(0, ka)))


def slab_flux_ratio(omega: ArrayLike, mu: float, sigma: float, thickness: float) -> ComplexArray:
    """Φ(jω)/Φ(0) of a slab of ``thickness`` d driven on both faces: tanh(x)/x,
    x = (d/2)√(jωμσ) ([stoll1974] ch. 2)."""
    x = 0.5 * thickness * np.sqrt(1j * np.asarray(omega, float) * mu * sigma)
    small = np.abs(x) < 1e-6
    x = np.where(small, 1.0, x)
    return np.where(small, 1.0 + 0j, np.tanh(x) / x)


# ---- the linear system ------------------------------------------------------------------------


@dataclass(frozen=True)
class HarmonicSystem:
    """(K + jωM + K_lam(ω))ψ = f on the free dofs, and the flux functional Φ = P·ψ.
    Quadrature-point arrays are (elements, points) of ``basis``."""

    basis: Any  # skfem.CellBasis
    stiffness: Any  # scipy.sparse (N, N): ∫ ν ∇u·∇v / r
    eddy: Any  # scipy.sparse (N, N): ∫ σ u v / r
    load: FloatArray  # (N,)
    probe: FloatArray  # (N,)
    free: NDArray[np.int64]
    sigma: FloatArray  # σ_φ at the points
    lam_nu: FloatArray  # ν where laminated, 0 elsewhere
    lam_sigma_d2: FloatArray  # σd² where laminated, 0 elsewhere

    @property
    def laminated(self) -> bool:
        return bool(np.any(self.lam_sigma_d2 > 0))


@functools.cache
def _forms() -> tuple[Any, Any, Any]:
    import skfem
    from skfem.helpers import dot, grad

    @skfem.BilinearForm
    def stiff(u, v, w):  # type: ignore[no-untyped-def]
        gu, gv = grad(u), grad(v)
        return (w.nu * dot(gu, gv) + w.dnu * dot(w.n, gu) * dot(w.n, gv)) / w.x[0]

    @skfem.BilinearForm
    def mass(u, v, w):  # type: ignore[no-untyped-def]
        return w.sigma * u * v / w.x[0]

    @skfem.BilinearForm
    def lam(u, v, w):  # type: ignore[no-untyped-def]
        return w.c * dot(grad(u), grad(v)) / w.x[0]

    return stiff, mass, lam


def harmonic_system(
    basis: Any,
    nu: FloatArray,
    sigma: FloatArray,
    load: FloatArray,
    fixed: ArrayLike,
    probe: FloatArray,
    *,
    nu_along: FloatArray | None = None,
    direction: FloatArray | None = None,
    lam_sigma_d2: FloatArray | None = None,
) -> HarmonicSystem:
    """Assemble the system on ``basis`` (axisymmetric, x[0] = r) from quadrature-point ν
    (across the flux), σ and optionally ν along the unit ``direction`` (2, E, P) of ∇ψ₀
    (the tensor linearisation), σd² of laminated points; ``load`` and ``probe`` (N,) node
    vectors, ``fixed`` the ψ = 0 dofs."""
    import skfem

    stiff, mass, _ = _forms()
    nu = np.asarray(nu, float)
    if np.any(~np.isfinite(nu)) or np.any(nu <= 0):
        raise ParameterError("nu: the reluctivity must be finite and > 0 at every point")
    if np.any(np.asarray(sigma) < 0):
        raise ParameterError("sigma: conductivities must be ≥ 0 S/m")
    if nu_along is None or direction is None:
        dnu, n = np.zeros_like(nu), np.zeros((2, *nu.shape))
    else:
        dnu, n = np.asarray(nu_along, float) - nu, np.asarray(direction, float)
    k = skfem.asm(stiff, basis, nu=nu, dnu=dnu, n=n).tocsr()
    m = skfem.asm(mass, basis, sigma=np.asarray(sigma, float)).tocsr()
    sd2 = np.zeros_like(nu) if lam_sigma_d2 is None else np.asarray(lam_sigma_d2, float)
    free = np.setdiff1d(np.arange(basis.N), np.asarray(fixed, dtype=np.int64))
    return HarmonicSystem(basis, k, m, np.asarray(load, float), np.asarray(probe, float), free,
                          np.asarray(sigma, float) * np.ones_like(nu), np.where(sd2 > 0, nu, 0.0),
                          sd2)  # fmt: skip


def _lam_matrix(sys: HarmonicSystem, omega: float) -> Any:
    """K_lam(ω) = ∫ ν(x/tanh x − 1) ∇u·∇v / r on the laminated points (complex)."""
    import skfem

    _, _, lam = _forms()
    on = sys.lam_sigma_d2 > 0
    nu = np.where(on, sys.lam_nu, 1.0)
    # x² = (d/2)²·jωμσ = jω σd²/(4ν)  ([stoll1974] ch. 2, the slab's field)
    x = np.sqrt(1j * omega * sys.lam_sigma_d2 / (4.0 * nu))
    xs = np.where(on & (np.abs(x) > 0), x, 1.0)
    c = np.where(on, nu * (xs / np.tanh(xs) - 1.0), 0.0)
    re = skfem.asm(lam, sys.basis, c=c.real)
    im = skfem.asm(lam, sys.basis, c=c.imag)
    return re.tocsr() + 1j * im.tocsr()


def harmonic_ratio(sys: HarmonicSystem, omega: ArrayLike) -> ComplexArray:
    """Φ(jω)/Φ(0) at angular frequencies ``omega`` [rad/s] (one complex factorisation
    each)."""
    from scipy.sparse.linalg import spsolve

    f, ix = sys.load[sys.free], np.ix_(sys.free, sys.free)
    p = sys.probe[sys.free]
    k = sys.stiffness[ix]
    phi0 = p @ spsolve(k.tocsc(), f)
    if phi0 == 0:
        raise ParameterError("the load drives no gap flux (Φ(0) = 0): no response to normalise")
    out = []
    for w in np.atleast_1d(np.asarray(omega, float)):
        if w < 0 or not math.isfinite(w):
            raise ParameterError(f"omega = {w}: must be finite and ≥ 0 rad/s")
        a = k + 1j * w * sys.eddy[ix]
        if sys.laminated and w > 0:
            a = a + _lam_matrix(sys, float(w))[ix]
        out.append(p @ spsolve(a.tocsc(), f.astype(complex)) / phi0)
    return np.array(out, dtype=complex)


def harmonic_delay(sys: HarmonicSystem) -> tuple[float, FloatArray]:
    """(T, per-element share of T) [s]: the low-frequency group delay −dφ/dω|₀ = λᵀMψ₀/Φ₀
    (module docstring), its integrand σψ₀λ/r (+ σd²/12 ∇ψ₀·∇λ/r where laminated) summed
    per element; the shares add up to T."""
    from scipy.sparse.linalg import splu

    ix = np.ix_(sys.free, sys.free)
    lu = splu(sys.stiffness[ix].tocsc())
    psi, lam = np.zeros(sys.basis.N), np.zeros(sys.basis.N)
    psi[sys.free] = lu.solve(sys.load[sys.free])
    lam[sys.free] = lu.solve(sys.probe[sys.free])  # K symmetric: λ = K⁻¹Pᵀ
    phi0 = float(sys.probe @ psi)
    if phi0 == 0:
        raise ParameterError("the load drives no gap flux (Φ(0) = 0): no delay to normalise")
    b = sys.basis
    pi, li = b.interpolate(psi), b.interpolate(lam)
    # the mass form's integrand; dx = quadrature weight × Jacobian, per element and point
    dens = sys.sigma * np.asarray(pi) * np.asarray(li)
    if sys.laminated:
        dens = dens + sys.lam_sigma_d2 / 12.0 * (pi.grad[0] * li.grad[0] + pi.grad[1] * li.grad[1])
    per_el = np.sum(dens / np.asarray(b.global_coordinates())[0] * b.dx, axis=1) / phi0
    return float(per_el.sum()), per_el


# ---- closed-form check: a long solid cylinder ---------------------------------------------------


def solid_cylinder(
    radius: float, mu: float, sigma: float, omega: ArrayLike, elements: int = 32
) -> tuple[ComplexArray, float]:
    """(Φ(jω)/Φ(0), delay T [s]) of a long solid cylinder in a uniform axial AC field by this
    module's solver: ``elements`` bilinear quadrilaterals across the radius, one along z
    (∂ψ/∂z = 0 on both ends: the infinite cylinder), ψ = 0 on the axis, the surface field H₀
    as the natural boundary term ∫H₀ v dz at r = a. Closed forms: ``cylinder_flux_ratio``,
    T = μσa²/8 (``magnetics.eddy_lag.diffusion_mean_delay``)."""
    import skfem

    check_range("radius", radius, 0.0, 10.0, " m", lo_open=True)
    check_range("elements", elements, 1, 100000, "")
    r = np.linspace(0.0, radius, int(elements) + 1)
    h = radius / int(elements)
    mesh = skfem.MeshQuad.init_tensor(r, np.array([0.0, h]))
    basis = skfem.Basis(mesh, skfem.ElementQuad1(), intorder=2)
    x = mesh.p
    surface = np.isclose(x[0], radius)
    load = np.where(surface, 0.5 * h, 0.0)  # ∫ H₀ v dz over the facet, H₀ = 1 A/m
    probe = np.where(surface, np.pi, 0.0)  # Φ = 2π ψ(a), shared by the facet's two nodes
    shape = np.asarray(basis.global_coordinates())[0].shape
    sys = harmonic_system(basis, np.full(shape, 1.0 / mu), np.full(shape, sigma), load,
                          np.flatnonzero(np.isclose(x[0], 0.0)), probe)  # fmt: skip
    return harmonic_ratio(sys, omega), harmonic_delay(sys)[0]


# ---- the clutch ---------------------------------------------------------------------------------


def bias_current(
    section: Section,
    peak_current: float,
    bias: float = BIAS,
    materials: Mapping[str, Magnetic] | None = None,
) -> float:
    """A: the current at which the saturating circuit's gap flux is ``bias`` × its flux at
    ``peak_current`` — the operating point of ``magnetics.dynamics.torque_response``'s eddy
    lag (F(Φ) is explicit in the circuit: i = F(bias·Φ_peak)/N)."""
    check_range("bias", bias, 0.0, 1.0, "")
    check_range("peak_current", peak_current, 0.0, 1e4, " A", lo_open=True)
    mats = MATERIALS if materials is None else materials
    path = path_from_section(section, mats)
    kn = _kernels(path)
    n = path.turns[:, None]
    peak = np.abs(solve_flux(path, n * peak_current, mats, rtol=1e-10, kernels=kn))
    return float((_mmf(path, mats, bias * peak, kn)["total"] / n)[0, 0])


def _element_parts(grid: Grid, sigma_of: Mapping[str, float]) -> NDArray[np.str_]:
    """Part name of every element: core, poles, back_iron, drums (steel drum walls),
    ``other`` (the remaining conductors, e.g. stainless), '' (no conductor)."""
    cen = grid.centre
    out = np.full(cen.shape[1], "", dtype=object)
    for g in grid.section.regions:
        inside = (cen[0] > g.r0) & (cen[0] < g.r1) & (cen[1] > g.z0) & (cen[1] < g.z1)
        if sigma_of.get(g.material, 0.0) <= 0 or not inside.any():
            continue
        if g.role == "steel" or (not g.role and g.material == STEEL):
            part = _PART_OF_REGION.get(g.name, "drums" if g.part in ("rotor", "input") else "other")
        else:
            part = "other"
        out[inside] = part
    return out.astype(str)


@dataclass(frozen=True)
class EddyFEM:
    """The time-harmonic FEM's gap-flux response about ``current`` (SI): Φ(jω)/Φ(0) at
    ``frequencies`` [Hz], the low-frequency group delay [s] and each part's share of it."""

    current: float  # A, the operating point
    size: float  # m, element size inside the clutch (nan: a grid passed in)
    frequencies: FloatArray  # Hz
    ratio: ComplexArray  # Φ(jω)/Φ(0)
    delay: float  # s, −dφ/dω at ω → 0
    parts: Mapping[str, float]  # s, shares of ``delay`` (core, poles, back_iron, drums, other)
    flux: float  # Wb, the static gap flux (mean per gap and zone) at ``current``
    dofs: int
    linearisation: str

    @property
    def phase_deg(self) -> FloatArray:
        return np.degrees(np.angle(self.ratio))


def _operating_point(grid: Grid, psi: FloatArray, linearisation: str):  # type: ignore[no-untyped-def]
    """(ν across, ν along, unit ∇ψ₀) at the quadrature points: the incremental ν = dH/dB
    everywhere (isotropic), or the secant H/B across and dH/dB along (the tensor)."""
    basis = grid.basis
    r = np.asarray(basis.global_coordinates())[0]
    g = basis.interpolate(psi).grad
    gn = np.hypot(g[0], g[1])
    b = gn / r
    nu_inc, nu_sec = np.empty_like(b), np.empty_like(b)
    for k, m in enumerate(grid.materials):
        sel = grid.material_index == k
        if not sel.any():
            continue
        bb = b[sel]
        d = m.dh_db(bb)
        nu_inc[sel] = d
        nu_sec[sel] = np.where(bb > 1e-9, m.h_of_b(bb) / np.where(bb > 1e-9, bb, 1.0), d)
    n = g / np.where(gn > 0, gn, 1.0)
    if linearisation == "incremental":
        return nu_inc, None, None
    return nu_sec, nu_inc, n


def eddy_response(
    section: Section,
    current: float,
    frequencies: Iterable[float] = FREQUENCIES,
    *,
    size: float | None = None,
    laminations: Laminations | None = None,
    conductivity: Mapping[str, float] | None = None,
    linearisation: str = "incremental",
    materials: Mapping[str, Magnetic] | None = None,
    grid: Grid | None = None,
) -> EddyFEM:
    """The gap flux's response to a small sinusoidal coil current about ``current`` [A]
    (module docstring): the magnetostatic FEM at ``current`` (``solve_fem``), linearised,
    then the complex harmonic system at each of ``frequencies`` [Hz] and its low-frequency
    delay. ``conductivity`` maps material → σ [S/m] (default ``STEEL_ONLY``); laminated
    parts (``laminations``: core; shell = poles and back iron) carry no azimuthal current
    and a complex reluctivity. ``grid`` reuses a grid of this section."""
    import skfem

    check_choice("linearisation", linearisation, LINEARISATIONS)
    check_range("current", current, 0.0, 1e4, " A")
    freq = np.asarray(list(frequencies), float)
    if np.any(~np.isfinite(freq)) or np.any(freq < 0):
        raise ParameterError("frequencies: must be finite and ≥ 0 Hz")
    lam = Laminations() if laminations is None else laminations
    if conductivity is None:  # the magnetic steels only, each its registry's σ
        conductivity = {g.material: material_conductivity(g.material)
                        for g in section.regions if g.role == "steel"} or STEEL_ONLY  # fmt: skip
    sig = dict(conductivity)
    for name, s in sig.items():
        if not (math.isfinite(s) and s >= 0):
            raise ParameterError(f"conductivity[{name!r}] = {s}: must be finite and ≥ 0 S/m")
    mats = MATERIALS if materials is None else materials
    g = build_grid(section, size, mats) if grid is None else grid
    psi0 = solve_fem(section, current, mats, grid=g).psi
    if psi0 is None:
        raise ParameterError("the magnetostatic FEM returned no field ψ to linearise about")
    basis = g.basis
    shape = g.r_qp.shape
    nu, nu_along, direction = _operating_point(g, psi0, linearisation)

    parts = _element_parts(g, sig)
    sigma_el = np.array([sig.get(n, 0.0) for n in g.names])[g.material_index]
    sd2_el = np.zeros_like(sigma_el)
    for part, attr in _LAMINATED_BY.items():
        d = getattr(lam, attr)
        if d > 0:
            on = parts == part
            sd2_el[on] = sigma_el[on] * d**2
            sigma_el[on] = 0.0  # the sheets cut the azimuthal path
    ones = np.ones(shape)

    @skfem.LinearForm
    def source(v, w):  # type: ignore[no-untyped-def]
        return w.j * v

    j_el = np.where(g.coil_mask, section.clutch.coil_turns / g.coil_area, 0.0)  # 1 A
    load = skfem.asm(source, basis, j=j_el[:, None] * ones)
    probe = _gap_probe(g)
    sys = harmonic_system(basis, nu, sigma_el[:, None] * ones, load, g.fixed, probe,
                          nu_along=nu_along, direction=direction,
                          lam_sigma_d2=sd2_el[:, None] * ones)  # fmt: skip
    delay, per_el = harmonic_delay(sys)
    shares = {p: float(per_el[parts == p].sum()) for p in ("core", "poles", "back_iron", "drums",
                                                          "other")}  # fmt: skip
    ratio = harmonic_ratio(sys, 2 * np.pi * freq) if freq.size else np.zeros(0, complex)
    h = float(size) if size is not None else (DEFAULT_SIZE if grid is None else math.nan)
    return EddyFEM(float(current), h, freq, ratio, delay, shares, float(probe @ psi0),
                   int(basis.N), linearisation)  # fmt: skip


def _gap_probe(grid: Grid) -> FloatArray:
    """P with P·ψ = the mean radial flux per gap and zone: π/K Σ_k (2ψ(r_k, z_mid) −
    ψ(r_k, z0_k) − ψ(r_k, z1_k)), r_k the gap's mid-radius, z_mid the coil's centre."""
    sec = grid.section
    coil = sec.region("coil")
    zm = 0.5 * (coil.z0 + coil.z1)
    pts, w = [], []
    for gp in sec.gaps:
        rk = 0.5 * (gp.r_inner + gp.r_outer)
        pts += [(rk, zm), (rk, gp.z0), (rk, gp.z1)]
        w += [2.0, -1.0, -1.0]
    if not pts:
        raise ParameterError("section: no cylindrical gap, no gap flux")
    p = grid.basis.probes(np.array(pts).T)
    return np.asarray((np.pi / len(sec.gaps)) * (np.array(w) @ p)).ravel()


@dataclass(frozen=True)
class DiffusionEddy:
    """The 1-D diffusion model at one operating point (SI): τ_eddy, each part's
    contribution, and at ``frequencies`` [Hz] its first-order lag 1/(1 + jωτ_eddy) (what the
    torque response uses) and its full diffusion response (``eddy_lag.eddy_transfer``)."""

    delay: float
    parts: Mapping[str, float]
    frequencies: FloatArray
    lag: ComplexArray
    transfer: ComplexArray


def diffusion_eddy(
    section: Section,
    current: float,
    frequencies: Iterable[float] = FREQUENCIES,
    laminations: Laminations | None = None,
    materials: Mapping[str, Magnetic] | None = None,
) -> DiffusionEddy:
    """The 1-D diffusion model (``magnetics.eddy_lag.eddy_parts``) at the same operating
    ``current`` [A] as ``eddy_response``, for the like-for-like comparison."""
    mats = MATERIALS if materials is None else materials
    path = path_from_section(section, mats)
    parts = eddy_parts(path, [current], laminations, materials=mats)
    shares = {k: float(p.contribution[0]) for k, p in parts.items()}
    tau = sum(shares.values())
    f = np.asarray(list(frequencies), float)
    s = 2j * np.pi * f
    return DiffusionEddy(tau, shares, f, 1.0 / (1.0 + s * tau), eddy_transfer(parts, s)[0])
