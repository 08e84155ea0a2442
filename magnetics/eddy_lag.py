"""The eddy lag of the clutch's steel parts: 1-D magnetic diffusion per part, combined into
the gap flux's lag (one of the torque response's three lags, ``magnetics.dynamics``).

**Eddy currents** (1-D magnetic diffusion, [stoll1974] ch. 2, [lammeraner-stafl1964]).
In a conducting part of permeability μ (incremental, at the operating flux) and
conductivity σ, ∂²H/∂x² = μσ ∂H/∂t. For a slab of thickness d with the surface field
stepped to H₀ on both faces (x = ±d/2) at t = 0 and H = 0 inside before, separation of
variables gives H/H₀ = 1 − Σ_k (4/π)(−1)^k/(2k+1)·cos((2k+1)πx/d)·e^{−t/τ_k}, and its
mean over the thickness (the flux) is

    Φ(t)/Φ∞ = 1 − Σ_{k≥0} 8/((2k+1)²π²)·exp(−(2k+1)²π² t/(μσd²)),

slowest time constant τ₁ = μσd²/π², mean delay ∫(1 − Φ/Φ∞) dt = μσd²/12 (the same as
the low-frequency expansion of its transfer function tanh(x)/x, x = (d/2)√(sμσ)). A
solid cylinder of radius a driven on its surface gives Φ/Φ∞ = 1 − Σ 4/j_k²·
exp(−j_k² t/(μσa²)) (j_k the zeros of J₀), τ₁ = μσa²/j₁², mean delay μσa²/8.
Boundary conditions per part (in an axisymmetric part the eddy current is azimuthal
and driven by the axial flux it encircles): the **core** is the solid cylinder; the
**back iron** is driven on its coil face only — no flux lies beyond its outer face, so
the current vanishes there, a symmetry plane: the half of a slab of thickness 2t; the
**poles** likewise over their axial length l (the stainless end cap carries no flux):
d = 2l; the thin **drum walls** are slabs of their wall thickness driven on both faces.
A laminated or slotted part (a slot cuts the eddy path) has d = its lamination
thickness, driven on both faces (``Laminations``).
**Combination rule.** Each part's reluctance becomes R_i(s) ≈ R_i·(1 + s T_i) (T_i its
mean delay, the first order of tanh(x)/x in s). The gap flux is N·I/D with
D = R_st + R_sh(1 + P R_st), so to first order in s it is a lag of time constant
τ_eddy = Σ_i (∂D/∂R_i)·R_i·T_i / D: each part's mean delay weighted by its share of the
loop's incremental reluctance. A big, unsaturated part (high μ, so a slow T_i) carries
little of the MMF and lags the flux little; a saturated core (low μ, but most of the
reluctance) dominates. The slowest part alone would overstate the lag by orders of
magnitude (the poles' own τ₁ reaches ~0.1 s at low flux).
Against the time-harmonic FEM (``magnetics.fem.eddy``, docs/dynamics.md) τ_eddy is
within −11 … +23 %, the drums' shorted-turn lag missing and the shell's overstated; its
first-order lag overstates the phase above ~10 Hz 2–3× (``eddy_transfer`` does not).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.materials import STEEL, conductivity
from geometry.validation import check_choice, check_nonnegative
from magnetics.circuit import MagneticPath, _kernels, _mmf, solve_flux
from magnetics.laminations import Laminations
from magnetics.materials import MATERIALS, Magnetic, magnetic

FloatArray = NDArray[np.float64]

#: S/m, AISI 1018 at 20 °C: ρ = 1.59e-7 Ω·m at 0 °C and 2.19e-7 at 100 °C [matweb-1018],
#: linear between them: 1.71e-7 Ω·m → 5.8e6 S/m (the registry's, steel_1018.toml).
STEEL_CONDUCTIVITY = conductivity(STEEL)
#: Zeros of J0 [abramowitz-stegun] Table 9.5; beyond them McMahon's expansion (9.5.12).
_J0_ZEROS = (2.404825557695773, 5.520078110286311, 8.653727912911013, 11.79153443901428,
             14.93091770848779, 18.07106396791092, 21.21163662987926, 24.35247153074930,
             27.49347913204025, 30.63460646843198)  # fmt: skip
_MODES = 200  # terms of the diffusion series kept (the rest is lumped as instantaneous)


def _j0_zeros(n: int) -> FloatArray:
    k = np.arange(1, n + 1, dtype=float)
    b = (k - 0.25) * np.pi
    z = b + 1 / (8 * b) - 124 / (3 * (8 * b) ** 3)  # McMahon [abramowitz-stegun] 9.5.12
    z[: len(_J0_ZEROS)] = _J0_ZEROS[:n]
    return z


SHAPES = ("slab", "cylinder")


def diffusion_modes(shape: str, n: int = _MODES) -> tuple[FloatArray, FloatArray]:
    """(c_k, τ_k/τ₁) of the mean-flux step response 1 − Σ c_k e^{−t/τ_k} (module
    docstring): slab c_k = 8/((2k+1)²π²), τ_k = τ₁/(2k+1)²; cylinder c_k = 4/j_k²,
    τ_k = τ₁ (j₁/j_k)². Σ c_k = 1 over all modes."""
    check_choice("shape", shape, SHAPES)
    if shape == "slab":
        m = 2.0 * np.arange(n) + 1.0
        return 8.0 / (m * np.pi) ** 2, 1.0 / m**2
    j = _j0_zeros(n)
    return 4.0 / j**2, (j[0] / j) ** 2


def diffusion_time_constant(
    shape: str, mu: ArrayLike, sigma: ArrayLike, size: ArrayLike
) -> FloatArray:
    """Slowest time constant τ₁ [s]: slab of thickness ``size`` μσd²/π², cylinder of
    radius ``size`` μσa²/j₁² ([stoll1974] ch. 2)."""
    check_choice("shape", shape, SHAPES)
    c = np.pi**2 if shape == "slab" else _J0_ZEROS[0] ** 2
    return np.asarray(mu, float) * np.asarray(sigma, float) * np.asarray(size, float) ** 2 / c


def diffusion_mean_delay(shape: str, tau1: ArrayLike) -> FloatArray:
    """Mean delay ∫(1 − Φ/Φ∞) dt = Σ c_k τ_k: π²/12·τ₁ (slab, μσd²/12) or j₁²/8·τ₁
    (cylinder, μσa²/8)."""
    check_choice("shape", shape, SHAPES)
    f = np.pi**2 / 12 if shape == "slab" else _J0_ZEROS[0] ** 2 / 8
    return f * np.asarray(tau1, float)


def diffusion_step(shape: str, tau1: ArrayLike, t: ArrayLike, n: int = _MODES) -> FloatArray:
    """Mean flux Φ(t)/Φ∞ after a surface-field step: 1 − Σ c_k exp(−t/τ_k) (broadcasts
    τ₁ against t)."""
    c, r = diffusion_modes(shape, n)
    tt = np.asarray(t, float)[..., None] / np.asarray(tau1, float)[..., None]
    return 1.0 - np.sum(c * np.exp(-tt / r), axis=-1)


def diffusion_response(shape: str, tau1: ArrayLike, s: ArrayLike, n: int = _MODES) -> NDArray:
    """Mean-flux transfer function F(s) = Σ c_k/(1 + s τ_k) + (1 − Σ c_k) (the slab's
    tanh(x)/x, x = (d/2)√(sμσ), as its partial fractions; the cylinder's 2I₁(x)/(xI₀(x)))."""
    c, r = diffusion_modes(shape, n)
    st = np.asarray(s)[..., None] * np.asarray(tau1, float)[..., None] * r
    return np.sum(c / (1.0 + st), axis=-1) + (1.0 - c.sum())


@dataclass(frozen=True)
class EddyPart:
    """One steel part's lag (arrays (S,)): its slowest diffusion time constant τ₁ [s] (at its
    reluctance-weighted incremental μ), mean delay T [s], diffusion length [m], shape, and
    its weight (∂D/∂R_i)·R_i/D in the gap flux's lag; ``contribution`` = weight·T."""

    shape: str
    size: FloatArray
    tau1: FloatArray
    mean_delay: FloatArray
    weight: FloatArray

    @property
    def contribution(self) -> FloatArray:
        return self.weight * self.mean_delay


def eddy_parts(
    path: MagneticPath,
    current: ArrayLike,
    laminations: Laminations | None = None,
    sigma: float | None = None,
    materials: Mapping[str, Magnetic] | None = None,
    flux: ArrayLike | None = None,
) -> dict[str, EddyPart]:
    """Each steel part's eddy lag at the bias ``current`` (S,), or at the gap ``flux``
    (S,) Wb where given (module docstring:
    boundary conditions and combination rule). Parts: ``core``, ``drums`` (all the walls
    in both zones together), ``poles``, ``back_iron``. The gap flux's eddy time constant is
    the sum of the parts' ``contribution``."""
    lam = Laminations() if laminations is None else laminations
    mats = MATERIALS if materials is None else materials
    # each part's own steel and conductivity (the registry's), or ``sigma`` for all
    part_steel = {"core": path.core_steel, "drums": path.steel, "shell": path.shell_steel}
    sig = {k: conductivity(v) if sigma is None else sigma for k, v in part_steel.items()}
    for v in sig.values():
        check_nonnegative("sigma", v, " S/m")
    size = path.turns.size
    kn = _kernels(path)
    if flux is None:
        cur = np.broadcast_to(np.asarray(current, float), (size,))
        phi = np.abs(solve_flux(path, path.turns[:, None] * cur[:, None], mats, kernels=kn))
    else:
        phi = np.abs(np.broadcast_to(np.asarray(flux, float), (size,)))[:, None]
    m = _mmf(path, mats, phi, kn)
    phi_sh = m["phi_shell"]
    r_st, r_sh, p = m["dstack"][:, 0], m["dshell"][:, 0], kn.leak[:, 0]
    d_total = r_st + r_sh * (1.0 + p * r_st)
    dd_st, dd_sh = (1.0 + p * r_sh) / d_total, (1.0 + p * r_st) / d_total  # ∂D/∂R_i / D

    def rows(k: FloatArray, wk: FloatArray, flux: FloatArray,
             which: str) -> tuple[FloatArray, FloatArray]:  # fmt: skip
        """Incremental reluctance (J, S) and incremental μ (J, S) of each kernel row."""
        steel = magnetic(part_steel[which], mats)
        _, dh = steel.h_dh(np.ascontiguousarray(k * flux[None, :, :]))
        return (wk * dh)[:, :, 0], 1.0 / np.maximum(dh[:, :, 0], 1e-30)

    def part(shape: str, diff_len: FloatArray, r: FloatArray, mu: FloatArray,
             dd: FloatArray, sigma: float) -> EddyPart:  # fmt: skip
        rsum = r.sum(0)
        mu_w = np.sum(r * mu, 0) / np.where(rsum > 0, rsum, 1.0)
        tau1 = diffusion_time_constant(shape, mu_w, sigma, diff_len)
        mean = diffusion_mean_delay(shape, tau1)
        return EddyPart(shape, np.asarray(diff_len, float), tau1, mean, dd * rsum)

    r_c, mu_c = rows(kn.core_k, kn.core_wk, phi, "core")
    r_d, mu_d = rows(kn.drum_k, kn.drum_wk, phi, "drums")
    r_s, mu_s = rows(kn.shell_k, kn.shell_wk, phi_sh, "shell")
    out: dict[str, EddyPart] = {}
    radius = np.sqrt(path.core_area / np.pi)
    if lam.core > 0:
        out["core"] = part("slab", np.full(size, lam.core), r_c, mu_c, dd_st, sig["core"])
    else:
        out["core"] = part("cylinder", radius, r_c, mu_c, dd_st, sig["core"])
    # drums: per wall (its own thickness), then one entry with the weighted sums
    t_d = (path.drum_r1 - path.drum_r0).T  # (D, S)
    tau_rows = diffusion_time_constant("slab", mu_d, sig["drums"], t_d)
    mean_rows = diffusion_mean_delay("slab", tau_rows)
    rsum = r_d.sum(0)
    safe = np.where(rsum > 0, rsum, 1.0)
    out["drums"] = EddyPart("slab", np.max(t_d, axis=0, initial=0.0),
                            np.sum(r_d * tau_rows, 0) / safe,
                            np.sum(r_d * mean_rows, 0) / safe, dd_st * rsum)  # fmt: skip
    poles = slice(0, r_s.shape[0] - 1)  # the pole rings' Gauss rows; the last is the back iron
    pole_len = np.repeat(path.pole_len.T, (r_s.shape[0] - 1) // 2, axis=0)  # (J-1, S)
    back_r0 = path.pole_r1[:, 0]
    back_t = np.sqrt(path.back_area / np.pi + back_r0**2) - back_r0
    if lam.shell > 0:
        d_pole = np.full(size, lam.shell)
        d_back = np.full(size, lam.shell)
    else:
        d_pole = 2.0 * np.max(pole_len, axis=0)  # driven on the coil face only: d = 2l
        d_back = 2.0 * back_t  # driven on the coil face only: d = 2t
    out["poles"] = part("slab", d_pole, r_s[poles], mu_s[poles], dd_sh, sig["shell"])
    out["back_iron"] = part("slab", d_back, r_s[-1:], mu_s[-1:], dd_sh, sig["shell"])
    return out


def eddy_transfer(parts: Mapping[str, EddyPart], s: ArrayLike) -> NDArray:
    """The gap flux's eddy response Φ(s)/Φ(0) (S, F) with each part's full diffusion
    response F_i(s) in place of its first order: R_i → R_i/F_i(s) in D, to first order in
    the parts' shares, 1/(1 + Σ_i w_i (1/F_i(s) − 1)) (module docstring, combination rule);
    its low-frequency group delay is τ_eddy. Above 1/τ₁ of the slow parts the phase grows
    like √ω, not like ωτ_eddy (docs/dynamics.md: against the time-harmonic FEM)."""
    ss = np.atleast_1d(np.asarray(s))
    den = 1.0 + sum(p.weight[:, None] * (1.0 / diffusion_response(p.shape, p.tau1[:, None], ss)
                                         - 1.0) for p in parts.values())  # fmt: skip
    return 1.0 / den
