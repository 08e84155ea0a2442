"""Response time from the geometry: coil inductance, amplifier, eddy currents, fluid.

The torque of an MR clutch follows a current command through three lags in series, each
computed here from the design (one design or S designs as arrays, like the circuit):

1. **Electrical.** The coil's flux linkage is λ(I) = N·Φ_shell: the source N·I of the
   circuit (``magnetics.circuit``) sits in series with the shell, so the flux it drives —
   the gap flux plus the leakage across the stack, Φ_shell = Φ + P_leak·F_stack(Φ) — is
   the flux that threads the coil (the co-energy of the lumped loop is ∫λ dI with this λ).
   The incremental inductance is analytic from the branch slopes ([roters1941] ch. 5):
   ``L_inc = dλ/dI = N²·(1 + P·R_st)/(R_st + R_sh·(1 + P·R_st))`` with R_st = dF_stack/dΦ,
   R_sh = dF_shell/dΦ_shell; in the linear limit it is N²/(R_sh + R_st ∥ 1/P) = N²·P_total.
   (The leakage through the coil window counts as fully linked: an overestimate of L of
   the window's share, which is small.) The amplifier is a current loop, first order at
   its bandwidth f_c, until its supply V saturates: di/dt = min((I − i)/τ_a,
   (V − R i)/L_inc(i)), τ_a = 1/(2π f_c) ([franklin-powell-workman] §6: a first-order
   loop). A step 0 → I then takes t(i) = ∫₀ⁱ max(τ_a/(I − i'), L_inc(i')/(V − R i')) di';
   with i = I(1 − e^{−u}) the integrand max(τ_a, L_inc (I − i)/(V − R i)) is bounded, and
   Gauss–Legendre in u gives t(10 %) and t(90 %). The equivalent first-order time
   constant is τ_el = (t90 − t10)/ln 9 (exact for a first-order lag).

2. **Eddy currents** (1-D magnetic diffusion per steel part, combined into the gap
   flux's lag: ``magnetics.eddy_lag``, its boundary conditions and combination rule).
   Against the time-harmonic FEM (``magnetics.fem.eddy``, docs/dynamics.md) τ_eddy is
   within −11 … +23 %.

3. **Fluid.** The particle chains form in a fraction of a millisecond; the fluid is a
   first-order lag of ``FLUID_RESPONSE_TIME`` — an assumption (sub-millisecond is the
   common statement; [kubik2022] measures the fluid's own response time as a separate
   term), not a value measured for MRF-132DG.

**Torque response.** G(s) = Π_i 1/(1 + s T_i) over T = (τ_el, τ_eddy, τ_fluid): its step
response (fixed Talbot inversion, [abate-valko2004]), its −3 dB bandwidth, and the
**equivalent delay** τ_eq = Σ T_i — the low-frequency group delay of G (−d arg G/dω at
ω → 0). A pure delay τ_eq has the same phase slope at low frequency and more phase lag
above (atan x ≤ x) and no attenuation, so it is conservative for the haptic loop's
stability; its error on the largest stable K is measured against the lags themselves
(``mrclutch.haptics.delay.lag_stable_stiffness``; tests/magnetics/test_dynamics.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.regions import Regions
from geometry.validation import ParameterError, check_nonnegative, check_range
from magnetics.amplifier import Amplifier
from magnetics.circuit import MagneticPath, _kernels, _mmf, path_from_regions, solve_flux
from magnetics.eddy_lag import EddyPart, eddy_parts
from magnetics.laminations import Laminations
from magnetics.materials import MATERIALS, Magnetic
from magnetics.thermal import coil_resistance

FloatArray = NDArray[np.float64]

#: s, first-order lag of the fluid's chain formation: an assumption ("sub-millisecond",
#: module docstring, [kubik2022]).
FLUID_RESPONSE_TIME = 0.25e-3
#: The bias at which the eddy lag is taken, as a fraction of the peak gap flux: about the
#: middle of the torque range a rendered spring sweeps (the incremental μ depends on it).
BIAS = 0.5

#: Gauss nodes per interval of the current rise: 3 + 3 is within 2 % of 64 + 64 (largest
#: 1.3 % over 20 000 random designs, benchmarks/bench_dynamics.py); one value for the
#: sweeps and for one design, so a sweep row equals ``evaluate``.
RISE_NODES = 3


# ---- electrical -----------------------------------------------------------------------------


def _linkage(
    m: Mapping[str, FloatArray], turns: FloatArray, leak: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """λ = N·Φ_shell and dλ/dΦ = N·(1 + P·dF_stack/dΦ) from ``circuit._mmf``'s output at a
    gap flux Φ (module docstring): the one place the coil's linkage is written."""
    return turns * m["phi_shell"], turns * (1.0 + leak * m["dstack"])


def flux_linkage(
    path: MagneticPath, current: ArrayLike, materials: Mapping[str, Magnetic] | None = None
) -> tuple[FloatArray, FloatArray]:
    """(λ [Wb], L_inc = dλ/dI [H]) at currents (S, C) (module docstring: λ = N·Φ_shell,
    L_inc analytic from the branch slopes). The secant inductance is λ/I."""
    mats = MATERIALS if materials is None else materials
    cur = np.asarray(current, dtype=float)
    cur = np.broadcast_to(cur.reshape(cur.shape[0] if cur.ndim == 2 else 1, -1),
                          (path.turns.size, cur.shape[-1] if cur.ndim else 1))  # fmt: skip
    n = path.turns[:, None]
    kern = _kernels(path)
    phi = np.abs(solve_flux(path, n * cur, mats, kernels=kern))
    m = _mmf(path, mats, phi, kern)
    lam, dlam = _linkage(m, n, kern.leak)
    return lam * np.sign(cur), n * dlam / m["dtotal"]  # dλ/dI = (dλ/dΦ)/(dI/dΦ)


@dataclass(frozen=True)
class CurrentRise:
    """A step 0 → I of the current command (arrays (S,)): times to 10 % and 90 % [s],
    the 10–90 % rise time and the equivalent first-order time constant (rise/ln 9)."""

    t10: FloatArray
    t90: FloatArray

    @property
    def rise_time(self) -> FloatArray:
        fin = np.isfinite(self.t90)
        return np.where(fin, np.where(fin, self.t90, 0.0) - np.where(fin, self.t10, 0.0), np.inf)

    @property
    def time_constant(self) -> FloatArray:
        return self.rise_time / math.log(9.0)


def current_rise(
    path: MagneticPath,
    resistance: ArrayLike,
    current: ArrayLike,
    amplifier: Amplifier,
    materials: Mapping[str, Magnetic] | None = None,
    nodes: int = RISE_NODES,
    flux: FloatArray | None = None,
) -> CurrentRise:
    """The amplifier's step to ``current`` (S,) through the coil (resistance (S,) Ω).

    Integrated in the gap flux Φ, where the circuit is explicit (no solve at the nodes):
    i = F(Φ)/N, dλ/dΦ = N(1 + P·R_st), so dt/dΦ = max(τ_a (di/dΦ)/(I − i),
    (dλ/dΦ)/(V − R i)) (module docstring); with Φ = Φ_I(1 − e^{−u}) the first term is
    τ_a exactly in the linear regime. Gauss–Legendre, ``nodes`` points on [0, Φ(10 %)]
    and on [Φ(10 %), Φ(90 %)]; ``flux`` (S, 3): the gap flux at 0.1 I, 0.9 I and I if
    already known (the first two may be estimates: the times are corrected to first order
    to 10 % and 90 % of I); None: solved. t10 (t90) is inf where V ≤ 0.1 R·I (0.9 R·I):
    the supply cannot push that current through the coil (``supply_current``)."""
    mats = MATERIALS if materials is None else materials
    size = path.turns.size
    cur = np.broadcast_to(np.asarray(current, float), (size,))
    res = np.broadcast_to(np.asarray(resistance, float), (size,))
    n_t = path.turns
    kn = _kernels(path)
    if flux is None:
        flux = np.abs(solve_flux(path, n_t[:, None] * cur[:, None] * _RISE_FRACTIONS, mats,
                                 kernels=kn))  # fmt: skip
    f10, f90, f_end = flux[:, 0], flux[:, 1], flux[:, 2]
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    u_of = lambda f: -np.log1p(-f / f_end)  # noqa: E731
    u10, u90 = u_of(f10), u_of(f90)
    u = np.concatenate([0.5 * u10[:, None] * (x + 1),
                        u10[:, None] + 0.5 * (u90 - u10)[:, None] * (x + 1)], axis=1)  # fmt: skip
    wu = np.concatenate([0.5 * u10[:, None] * w, 0.5 * (u90 - u10)[:, None] * w], axis=1)
    phi = np.concatenate([f_end[:, None] * -np.expm1(-u), flux[:, :2]], axis=1)  # + the ends
    m = _mmf(path, mats, phi, kn)
    i = m["total"] / n_t[:, None]
    di = m["dtotal"] / n_t[:, None]  # di/dΦ
    dlam = _linkage(m, n_t[:, None], kn.leak)[1]  # dλ/dΦ
    dphi_du = f_end[:, None] - phi
    v = amplifier.supply_voltage
    head = v - res[:, None] * i
    volt = np.where(head > 0, dlam * dphi_du / np.where(head > 0, head, 1.0), np.inf)
    amp = amplifier.time_constant * di * dphi_du / (cur[:, None] - i)
    dt_du = np.maximum(amp, volt)
    g = dt_du[:, :-2] * wu
    n = int(nodes)
    # the ends may be approximate fluxes: first-order correction to 10 % and 90 % of I,
    # (f·I − i(Φ_end))·dt/di (exact ends: zero)
    dt_di = dt_du[:, -2:] / (di * dphi_du)[:, -2:]
    fix = (np.array([0.1, 0.9]) * cur[:, None] - i[:, -2:]) * np.where(np.isfinite(dt_di), dt_di, 0)
    t10 = np.sum(g[:, :n], axis=1) + fix[:, 0]
    t90 = np.sum(g, axis=1) + fix[:, 1]
    # the supply holds at most V/R: a fraction f of I is reached (in finite time) only
    # where f·R·I < V; the voltage-limited tail then ends at V/R, below the target
    return CurrentRise(np.where(v <= 0.1 * res * cur, np.inf, t10),
                       np.where(v <= 0.9 * res * cur, np.inf, t90))  # fmt: skip


#: Fractions of the step's current where the rise solves the circuit (10 %, 90 %, 100 %).
_RISE_FRACTIONS = np.array([0.1, 0.9, 1.0])


# ---- the torque response ------------------------------------------------------------------------


@dataclass(frozen=True)
class TorqueResponse:
    """Current command → torque of S designs (arrays (S,), SI): module docstring."""

    current: FloatArray  # A, the step's target (the design's current limit)
    resistance: FloatArray  # Ω at the coil temperature
    inductance_zero: FloatArray  # H, incremental at 0 A
    inductance_peak: FloatArray  # H, incremental at the peak current
    inductance_secant: FloatArray  # H, λ/I at the peak current
    rise: CurrentRise
    eddy: Mapping[str, EddyPart] = field(default_factory=dict)
    fluid_time: float = FLUID_RESPONSE_TIME

    @property
    def tau_electrical(self) -> FloatArray:
        return self.rise.time_constant

    @property
    def tau_eddy(self) -> FloatArray:
        return np.sum([p.contribution for p in self.eddy.values()], axis=0)

    @property
    def lags(self) -> FloatArray:
        """(S, 3) time constants of the lags in series: electrical, eddy, fluid."""
        size = self.current.size
        return np.stack([self.tau_electrical, self.tau_eddy, np.full(size, self.fluid_time)], 1)

    @property
    def equivalent_delay(self) -> FloatArray:
        """τ_eq = Σ T_i, the low-frequency group delay (module docstring)."""
        return self.lags.sum(axis=1)

    @property
    def bandwidth_hz(self) -> FloatArray:
        return lag_bandwidth(self.lags) / (2 * np.pi)

    def step(self, t: ArrayLike) -> FloatArray:
        """Torque/final torque after a current-command step, (S, T) at times ``t`` [s]."""
        return lag_step(self.lags, t)

    def item(self, i: int) -> dict[str, float | dict[str, dict[str, float]]]:
        """Design ``i``'s figures as plain floats (SI keys, for JSON)."""
        eddy = {
            k: {
                "time_constant_s": float(p.tau1[i]),
                "mean_delay_s": float(p.mean_delay[i]),
                "weight": float(p.weight[i]),
                "contribution_s": float(p.contribution[i]),
                "diffusion_length_m": float(p.size[i]),
            }
            for k, p in self.eddy.items()
        }
        return {
            "inductance_0A_H": float(self.inductance_zero[i]),
            "inductance_peak_H": float(self.inductance_peak[i]),
            "inductance_secant_peak_H": float(self.inductance_secant[i]),
            "coil_resistance_ohm": float(self.resistance[i]),
            "current_rise_10_90_s": float(self.rise.rise_time[i]),
            "electrical_time_constant_s": float(self.tau_electrical[i]),
            "eddy_time_constant_s": float(self.tau_eddy[i]),
            "fluid_time_constant_s": float(self.fluid_time),
            "torque_delay_s": float(self.equivalent_delay[i]),
            "torque_bandwidth_hz": float(self.bandwidth_hz[i]),
            "eddy": eddy,
        }


def torque_response(
    rg: Regions,
    current: ArrayLike,
    amplifier: Amplifier | None = None,
    laminations: Laminations | None = None,
    *,
    path: MagneticPath | None = None,
    coil_temperature: float = 20.0,
    bias: float = BIAS,
    fluid_time: float = FLUID_RESPONSE_TIME,
    materials: Mapping[str, Magnetic] | None = None,
    nodes: int = RISE_NODES,
    eddy: bool = True,
    flux_peak: ArrayLike | None = None,
) -> TorqueResponse:
    """The torque response of the designs of ``rg`` to a step to ``current`` (S,) A: the
    amplifier's rise through the coil, the eddy lag at ``bias``× the peak gap flux and the
    fluid's lag
    (module docstring). ``path`` reuses a circuit already built from ``rg``; ``flux_peak``
    (S,) Wb the gap flux at ``current`` where already solved (the torque's solve)."""
    amp = Amplifier() if amplifier is None else amplifier
    check_range("bias", bias, 0.0, 1.0, "")
    check_nonnegative("fluid_time", fluid_time, " s")
    pth = path_from_regions(rg, materials) if path is None else path
    size = pth.turns.size
    cur = np.broadcast_to(np.asarray(current, float), (size,))
    if not np.all(np.isfinite(cur)) or np.any(cur <= 0):
        raise ParameterError("current: the step's target must be finite and > 0 A")
    at = rg.at
    res = np.broadcast_to(
        np.asarray(coil_resistance(rg.fields, at["coil_in"], at["coil_out"], coil_temperature),
                   float), (size,))  # fmt: skip
    mats = MATERIALS if materials is None else materials
    kn = _kernels(pth)
    n_t = pth.turns[:, None]
    ni = n_t * cur[:, None]
    if flux_peak is None:
        peak = np.abs(solve_flux(pth, ni, mats, rtol=1e-8, kernels=kn))
    else:
        peak = np.abs(np.broadcast_to(np.asarray(flux_peak, float), (size,)))[:, None]
    m = _mmf(pth, mats, np.concatenate([np.zeros((size, 1)), peak], 1), kn)
    # the flux at 10 % and 90 % of I, not solved: the linear circuit's, and one Newton step
    # back from the peak; current_rise corrects its times to first order (tests: within
    # 2 % of the solved ends with 64 nodes)
    f10 = np.minimum(0.1 * ni / m["dtotal"][:, :1], 0.5 * peak)
    f90 = np.clip(peak - 0.1 * ni / m["dtotal"][:, 1:], f10, 0.999 * peak)
    fl = np.concatenate([f10, f90, peak], 1)
    lam, dlam = _linkage(m, n_t, kn.leak)
    L = n_t * dlam / m["dtotal"]  # as flux_linkage, explicit in Φ
    rise = current_rise(pth, res, cur, amp, mats, nodes, flux=fl)
    parts = eddy_parts(pth, cur, laminations, materials=mats, flux=bias * fl[:, 2]) if eddy else {}
    return TorqueResponse(cur.copy(), res.copy(), L[:, 0], L[:, 1], lam[:, 1] / cur, rise,
                          parts, float(fluid_time))  # fmt: skip


# ---- lags: step response and bandwidth ---------------------------------------------------------


def lag_bandwidth(lags: ArrayLike) -> FloatArray:
    """ω₋₃dB [rad/s] of Π 1/(1 + sT_i) (rows of ``lags`` (S, n)): Π(1 + ω²T_i²) = 2,
    increasing in ω, by bisection in log ω. inf where every T_i is 0."""
    t = np.atleast_2d(np.asarray(lags, float))
    tmax = t.max(axis=1)
    ok = tmax > 0
    lo = np.where(ok, 1e-3 / np.where(ok, tmax, 1.0), 1.0)
    hi = np.where(ok, 1.0 / np.where(ok, tmax, 1.0), 1.0)  # |G| ≤ 1/√2 at 1/T_max
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        f = np.sum(np.log1p((mid[:, None] * t) ** 2), axis=1) - math.log(2.0)
        lo, hi = np.where(f < 0, mid, lo), np.where(f < 0, hi, mid)
    return np.where(ok, np.sqrt(lo * hi), np.inf)


_TALBOT_M = 32


def talbot(transform, t: ArrayLike, m: int = _TALBOT_M) -> FloatArray:  # type: ignore[no-untyped-def]
    """f(t) from its Laplace transform F(s) (vectorised: ``transform`` maps an array of s,
    broadcasting) by the fixed Talbot contour [abate-valko2004]: f(t) ≈ (2/(5t))·Σ_k
    Re[γ_k F(δ_k/t)], δ₀ = 2M/5, δ_k = (2kπ/5)(cot(kπ/M) + i). t > 0."""
    k = np.arange(1, m)
    th = k * np.pi / m
    cot = 1.0 / np.tan(th)
    delta = np.concatenate([[2.0 * m / 5.0], 2.0 * k * np.pi / 5.0 * (cot + 1j)])
    gamma = np.concatenate(
        [[0.5 * np.exp(2.0 * m / 5.0)], (1 + 1j * th * (1 + cot**2) - 1j * cot) * np.exp(delta[1:])]
    )
    tt = np.asarray(t, float)
    s = delta / tt[..., None]
    return 0.4 / tt * np.sum((gamma * transform(s)).real, axis=-1)


def lag_step(lags: ArrayLike, t: ArrayLike) -> FloatArray:
    """Unit-step response (S, T) of Π 1/(1 + sT_i) at times ``t`` (T,) [s] (0 at t ≤ 0)."""
    lg = np.atleast_2d(np.asarray(lags, float))
    tt = np.atleast_1d(np.asarray(t, float))
    pos = np.where(tt > 0, tt, 1.0)

    def g(s: NDArray) -> NDArray:  # s (T, M) → (S, T, M)
        return 1.0 / (s * np.prod(1.0 + s[None, :, :, None] * lg[:, None, None, :], axis=-1))

    y = talbot(g, pos)
    return np.where(tt > 0, y, 0.0)
