"""MR fluids' rheology: Carlson's yield stress τy(H) and its integral along a decaying field
(a fringe's flux tube), the off-state viscosity and its temperature law. The fluids' data
files and their B–H curves are read by ``magnetics.materials`` (the registry ``FLUIDS``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.validation import ParameterError, check_positive, check_range

FloatArray = NDArray[np.float64]

_CARLSON_K = 6.33e-6  # m/A, Carlson's field scale in τy = τ_max·tanh(k·H) [carlson]
# ∫_u^∞ tanh(t)/t² dt = Q(ln u), and S(v) = e^v·Q(v), tabulated in v on [_S_LO, _S_HI]:
# S' = S − tanh(e^v); below the table S = e^v·(Q∞ − v) to e^{3v}/6 (tanh t = t − t³/3 …,
# Q∞ = Q + ln u as u → 0); above it tanh(e^v) = 1 in double precision, so S = 1.
_S_LO, _S_HI, _S_N = -12.0, 4.0, 1 << 12
_S_STEP = (_S_HI - _S_LO) / (_S_N - 1)


@functools.cache
def _carlson_s_table() -> tuple[float, FloatArray, FloatArray]:
    """(Q∞, S, dS/dv) on the uniform grid [_S_LO, _S_HI] (_S_N points). Q from its
    derivative −tanh(e^v)·e^−v by the composite Simpson rule on a grid 16× finer (error
    < 1e-12), from the top, where Q(_S_HI) = e^−_S_HI (tanh = 1 beyond); Q∞ = Q + v at
    the bottom (Q + v → Q∞ − e^{2v}/6 …)."""
    fine = np.linspace(_S_LO, _S_HI, 16 * (_S_N - 1) + 1)
    d = np.tanh(np.exp(fine)) * np.exp(-fine)  # −dQ/dv
    h = fine[1] - fine[0]
    pair = (h / 3) * (d[:-2:2] + 4 * d[1:-1:2] + d[2::2])  # Simpson over each 2 steps
    q = math.exp(-_S_HI) + np.concatenate([np.cumsum(pair[::-1])[::-1], [0.0]])[::8]
    v = fine[::16]
    q_inf = float(q[0] + v[0] + math.exp(2 * _S_LO) / 6)
    s = np.exp(v) * q
    return q_inf, s, s - np.tanh(np.exp(v))


def _carlson_s(v: FloatArray) -> FloatArray:
    """S(v) = e^v·∫_{e^v}^∞ tanh(t)/t² dt (``_carlson_s_table``): cubic Hermite in the
    table from S and its exact slope (error ~h⁴/384·|S⁗| < 1e-12), the series below it,
    1 above it (the clipped table's end)."""
    q_inf, s_at, d_at = _carlson_s_table()  # built on first use (2 ms), not at import
    t = np.clip((v - _S_LO) / _S_STEP, 0.0, _S_N - 1.000001)
    i = t.astype(np.intp)
    t -= i
    s0, s1 = np.take(s_at, i), np.take(s_at, i + 1)
    d0, d1 = np.take(d_at, i) * _S_STEP, np.take(d_at, i + 1) * _S_STEP
    s = s0 + t * (d0 + t * (3 * (s1 - s0) - 2 * d0 - d1 + t * (2 * (s0 - s1) + d0 + d1)))
    low = np.minimum(v, _S_LO)
    return np.where(v < _S_LO, np.exp(low) * (q_inf - low), s)


@dataclass(frozen=True)
class MRFluid:
    """Rheology and bulk data of an MR fluid: Carlson's yield-stress closed form, the
    off-state (plastic) viscosity at its reference temperature and the carrier's
    viscosity–temperature line that carries it to other temperatures.

    Temperature law: the particles' contribution to the viscosity depends on their volume
    fraction, not on temperature, so η(T) = η(T_ref)·ν_c(T)/ν_c(T_ref) with ν_c the
    carrier's kinematic viscosity (the carrier's density change, < 2 % over the range,
    is neglected). ν_c(T) is the Walther line through two points [astm-d341].
    """

    name: str
    phi: float  # iron volume fraction
    carrier_c: float  # Carlson's carrier coefficient (1.0 hydrocarbon)
    viscosity: float  # Pa·s, off-state plastic viscosity at viscosity_temperature
    source: str
    viscosity_temperature: float = 40.0  # °C at which ``viscosity`` was measured
    #: carrier kinematic viscosity (°C, m²/s) at two temperatures: the Walther line
    carrier_points: tuple[tuple[float, float], tuple[float, float]] = (
        (40.0, 19.0e-6),
        (100.0, 4.1e-6),
    )
    carrier: str = "carrier"  # what the carrier points are
    temperature_range: tuple[float, float] = (-40.0, 130.0)  # °C, maker's operating range
    thermal_conductivity: float = 0.65  # W/(m·K)
    specific_heat: float = 800.0  # J/(kg·K)
    #: 1/K, the carrier's volumetric expansion: sets τy(T) (magnetics.hot); None: no data
    carrier_expansion: float | None = None
    #: J/m³, lifetime dissipated energy per volume (magnetics.life); None: no data
    lifetime_energy: float | None = None

    def __post_init__(self) -> None:
        check_positive(f"{self.name}.phi", self.phi)
        if self.carrier_expansion is not None:
            check_range(f"{self.name}.carrier_expansion", self.carrier_expansion, 0.0, 1e-2,
                        " 1/K")  # fmt: skip
        if self.lifetime_energy is not None:
            check_positive(f"{self.name}.lifetime_dissipated_energy", self.lifetime_energy,
                           " J/m³")  # fmt: skip
        check_positive(f"{self.name}.viscosity", self.viscosity, " Pa·s")
        (t0, n0), (t1, n1) = self.carrier_points
        if not (t1 > t0 and n0 > n1 > 0):
            raise ParameterError(
                f"{self.name}.carrier_points = {self.carrier_points!r}: need two (°C, m²/s) "
                "points, the hotter one less viscous"
            )

    @property
    def tau_y_max(self) -> float:
        # Carlson (LORD) [carlson], τy,sat = C·271700·φ^1.5239 Pa
        return self.carrier_c * 271700.0 * self.phi**1.5239

    def tau_y(self, h: ArrayLike) -> FloatArray:
        """Yield stress τy(|H|), Pa. Carlson: τy = C·271700·φ^1.5239·tanh(6.33e-6·H)."""
        return self.tau_y_max * np.tanh(_CARLSON_K * np.abs(np.asarray(h, dtype=float)))

    def tau_y_decay(self, h: ArrayLike, w: ArrayLike) -> FloatArray:
        """∫0^W τy(|H|·e^−v)·e^v dv (Pa), W = ``w`` ≥ 0, elementwise: the yield stress
        summed along a field that decays hyperbolically, H(s) = H·g/(g + κs), for
        s = (g/κ)(e^v − 1) (a fringe's flux tube, ``magnetics.torque``); × g/κ it is
        ∫0^h τy(H(s)) ds with W = ln(1 + κh/g).

        Closed form of Carlson's law: with a = k·|H| and t = a·e^−v it is
        τ_max·a·∫_{a e^−W}^{a} tanh(t)/t² dt = τ_max·[e^W·S(ln a − W) − S(ln a)], S(v) =
        e^v·∫_{e^v}^∞ tanh(t)/t² dt (``_carlson_s``). Limits: a·W·τ_max for a weak field
        (τy linear in H), (e^W − 1)·τ_max in deep saturation (S = 1). It is ``tau_y``'s
        law: a fluid with another law overrides both."""
        a = np.minimum(_CARLSON_K * np.abs(np.asarray(h, dtype=float)), 1e200)
        w = np.asarray(w, dtype=float)
        v = np.log(np.maximum(a, 1e-300))
        f = np.exp(w) * _carlson_s(v - w) - _carlson_s(v)
        return self.tau_y_max * np.where(a > 0, f, 0.0)

    def carrier_viscosity(self, temperature: ArrayLike) -> Any:
        """Carrier kinematic viscosity ν_c (m²/s) at ``temperature`` (°C): the Walther
        line log log(ν + 0.7) = A − B log T through the two carrier points [astm-d341]
        (ν in mm²/s, T in K)."""
        (t0, n0), (t1, n1) = self.carrier_points

        def w(nu: Any) -> Any:
            return np.log10(np.log10(nu * 1e6 + 0.7))

        x0, x1 = np.log10(t0 + 273.15), np.log10(t1 + 273.15)
        slope = (w(n1) - w(n0)) / (x1 - x0)
        wt = w(n0) + slope * (np.log10(np.asarray(temperature, dtype=float) + 273.15) - x0)
        return (10.0 ** (10.0**wt) - 0.7) * 1e-6

    def viscosity_at(self, temperature: ArrayLike) -> Any:
        """Off-state plastic viscosity η (Pa·s) at ``temperature`` (°C; floats or arrays):
        η(T_ref)·ν_c(T)/ν_c(T_ref) (class docstring)."""
        t = np.asarray(temperature, dtype=float)
        lo, hi = self.temperature_range
        if np.any(~np.isfinite(t) | (t < lo) | (t > hi)):
            bad = t[~np.isfinite(t) | (t < lo) | (t > hi)].flat[0]
            raise ParameterError(
                f"fluid_temperature = {bad:g} °C: outside {self.name}'s range [{lo:g}, {hi:g}] °C"
            )
        ratio = self.carrier_viscosity(t) / self.carrier_viscosity(self.viscosity_temperature)
        out = self.viscosity * ratio
        return float(out) if np.ndim(out) == 0 else out
