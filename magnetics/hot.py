"""Hot torque: the yield stress τy(T), the viscosity η(T) and the coil's resistance R(T)
fed back from the thermal network (``magnetics.thermal``) over a duty cycle.

**τy(T), the dilution law.** The iron barely expands (its volumetric expansion is ~1/20 of
an oil's), the carrier does: heated by ΔT, a volume of fluid of iron fraction φ0 holds the
same iron in (φ0 + (1 − φ0)(1 + β ΔT)) of its volume, so

    φ(T) = φ0 / (φ0 + (1 − φ0)(1 + β (T − T0)))

and with Carlson's τy ∝ φ^1.5239 [carlson] at any field (the tanh in H does not depend on φ)

    τy(T)/τy(T0) = (φ(T)/φ0)^1.5239,  d/dT at T0: −1.5239 (1 − φ0) β  (1/K),

β the carrier's volumetric expansion (``MRFluid.carrier_expansion``), T0 = 20 °C, the
temperature every other figure of the tool is computed at. This is a *lower bound on the
loss*: measured losses of the MR stress exceed what the constituents' own thermal changes
predict [ocalan-mckinley2013] (the particles' magnetisation, which also falls, is left
out); the coefficient is marked unverified in the fluids' files. A fluid with no β has no
τy(T) (factor 1, said by ``tau_y_factor``'s caller).

**η(T)** is ``MRFluid.viscosity_at`` (the carrier's Walther line [astm-d341]) and **R(T)**
the coil's copper law inside the thermal network (``thermal.coil_resistance``).

**The march.** Over a duty the load sets the coil current and the slip power from the
node temperatures (the current to hold a torque rises as τy falls; the slip power is the
torque times the slip speed); within a step of length h both are frozen and the linear
network C dT/dt = −(G − x a e0e0ᵀ) T + q (x = I², the coil's R(T) as in
``thermal.steady``) is solved exactly, T(t + h) = T* + e^{−C⁻¹G'h} (T − T*), T* = G'⁻¹q.
With a constant load the march is the exact transient; with feedback its error is the
lag of one step (first order in h).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry.validation import ParameterError, check_positive, check_range
from magnetics.fluid import MRFluid
from magnetics.thermal import ALPHA_CU, Network

#: °C: the temperature τy is referred to (the tool's room temperature, drag.ROOM_TEMPERATURE).
TAU_Y_REFERENCE = 20.0
#: Carlson's exponent of φ in τy,sat = C·271700·φ^1.5239 [carlson].
CARLSON_PHI_EXPONENT = 1.5239


def phi_at(phi0: float, expansion: float, temperature: Any) -> Any:
    """Iron volume fraction at ``temperature`` (°C) of a fluid of fraction ``phi0`` at
    ``TAU_Y_REFERENCE`` whose carrier expands by ``expansion`` (1/K) and the iron not
    (module docstring)."""
    dt = np.asarray(temperature, dtype=float) - TAU_Y_REFERENCE
    return phi0 / (phi0 + (1 - phi0) * (1 + expansion * dt))


def tau_y_factor(fluid: MRFluid, temperature: Any) -> Any:
    """τy(T)/τy(20 °C) (module docstring): (φ(T)/φ0)^1.5239 [carlson]; 1 for a fluid with
    no carrier expansion given."""
    if fluid.carrier_expansion is None:
        return np.ones_like(np.asarray(temperature, dtype=float))
    ratio = phi_at(fluid.phi, fluid.carrier_expansion, temperature) / fluid.phi
    return ratio**CARLSON_PHI_EXPONENT  # τy ∝ φ^1.5239 [carlson]


def tau_y_coefficient(fluid: MRFluid) -> float | None:
    """d(τy/τy0)/dT at 20 °C (1/K): −1.5239 (1 − φ0) β; None with no carrier expansion."""
    if fluid.carrier_expansion is None:
        return None
    return -CARLSON_PHI_EXPONENT * (1 - fluid.phi) * fluid.carrier_expansion


@dataclass(frozen=True)
class Load:
    """What the clutch does at node temperatures (coil, core/fluid, housing; °C): the coil
    current [A] and the slip power into the core [W]."""

    current: float
    slip_power: float

    def __post_init__(self) -> None:
        check_range("current", self.current, 0.0, 1e4, " A")
        check_range("slip_power", self.slip_power, 0.0, 1e7, " W")


@dataclass(frozen=True)
class March:
    """Node temperatures over a duty: times (N+1,) [s], temperatures (N+1, 3) [°C] and the
    load of each step (N,) — current [A] and slip power [W] — frozen over the step."""

    times: np.ndarray
    temperatures: np.ndarray
    currents: np.ndarray
    slip_powers: np.ndarray

    @property
    def final(self) -> np.ndarray:
        """(coil, fluid, housing) °C at the end."""
        return self.temperatures[-1]


def march(
    net: Network, load: Callable[[np.ndarray], Load], duration: float, steps: int = 300
) -> March:
    """Node temperatures of one design (``net`` of one design) from ambient over
    ``duration`` seconds, the load re-read from the temperatures at each of ``steps``
    equal steps (module docstring)."""
    check_positive("duration", duration, " s")
    if not (isinstance(steps, int) and steps >= 1):
        raise ParameterError(f"steps = {steps!r}: must be a whole number ≥ 1")
    cap = np.asarray(net.capacity, dtype=float).reshape(3)
    g0 = np.asarray(net.conductance, dtype=float).reshape(3, 3)
    r20 = float(np.asarray(net.r20).reshape(()))
    to_air = float(np.asarray(net.to_air).reshape(()))
    a, c = r20 * ALPHA_CU, r20 * (1 - 20 * ALPHA_CU)  # R = a T + c (thermal.steady)
    h = duration / steps
    s = np.sqrt(cap)  # C^½: C⁻¹G' is similar to the symmetric C^-½ G' C^-½
    s_inv = 1 / s
    ss = np.outer(s, s)  # every step's C^½ C^½ᵀ (``_expm_sym``)
    t = np.full(3, float(net.ambient))
    temps, cur, pw = [t.copy()], [], []
    x_last = g = e = None
    for _ in range(steps):
        ld = load(t)
        x = ld.current**2
        # G' and e^{-Mh} depend on the step only through x: a step holding the last step's
        # current (a peak hold's first steps) reuses them, the same bits (x = I² ≥ 0 has no
        # −0, so == is bit-equality; a NaN never equals and is recomputed)
        if not (x_last is not None and x == x_last):
            g = g0.copy()
            g[0, 0] -= x * a  # the coil's R(T): its Joule heat rises with its temperature
            e = _expm_sym(g, s, h, ss)
            x_last = x
        q = np.array([x * c, ld.slip_power, to_air * net.ambient])
        t_star = np.linalg.solve(g, q)
        t = t_star + s_inv * (e @ (s * (t - t_star)))
        temps.append(t.copy())
        cur.append(ld.current)
        pw.append(ld.slip_power)
    return March(np.linspace(0.0, duration, steps + 1), np.array(temps), np.array(cur),
                 np.array(pw))  # fmt: skip


def march_batch(
    net: Network,
    load: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    duration: float,
    steps: int = 300,
) -> March:
    """``march`` of S designs at once (``net`` of S designs: capacities (S, 3), conductances
    (S, 3, 3)): ``load`` maps the node temperatures (S, 3) to the currents (S,) [A] and
    slip powers (S,) [W] of the step. The same steps as ``march``, each design's 3×3 solve
    and eigendecomposition stacked; the March's temperatures are (N+1, S, 3)."""
    check_positive("duration", duration, " s")
    if not (isinstance(steps, int) and steps >= 1):
        raise ParameterError(f"steps = {steps!r}: must be a whole number ≥ 1")
    cap = np.asarray(net.capacity, dtype=float).reshape(-1, 3)
    n = cap.shape[0]
    g0 = np.asarray(net.conductance, dtype=float).reshape(n, 3, 3)
    r20 = np.broadcast_to(np.asarray(net.r20, dtype=float).reshape(-1), (n,))
    to_air = np.broadcast_to(np.asarray(net.to_air, dtype=float).reshape(-1), (n,))
    a, c = r20 * ALPHA_CU, r20 * (1 - 20 * ALPHA_CU)  # R = a T + c (thermal.steady)
    h = duration / steps
    s = np.sqrt(cap)  # C^½, as in ``march``
    s_inv = 1 / s
    ss = s[:, :, None] * s[:, None, :]
    t = np.full((n, 3), float(net.ambient))
    temps, cur, pw = [t.copy()], [], []
    g = g0.copy()
    for _ in range(steps):
        i, p = (np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in load(t))
        x = i**2
        g[:, 0, 0] = g0[:, 0, 0] - x * a  # the coil's R(T), as in ``march``
        q = np.stack([x * c, p, to_air * net.ambient], axis=1)
        t_star = np.linalg.solve(g, q[..., None])[..., 0]
        lam, v = np.linalg.eigh(g / ss)
        e = (v * np.exp(-lam * h)[:, None, :]) @ np.swapaxes(v, 1, 2)
        t = t_star + s_inv * (e @ (s * (t - t_star))[..., None])[..., 0]
        temps.append(t.copy())
        cur.append(i.copy())
        pw.append(p.copy())
    return March(np.linspace(0.0, duration, steps + 1), np.array(temps), np.array(cur),
                 np.array(pw))  # fmt: skip


def _expm_sym(g: np.ndarray, s: np.ndarray, h: float, ss: np.ndarray | None = None) -> np.ndarray:
    """e^{−M h} of M = C^-½ G C^-½ (symmetric, ``s`` = C^½) by its eigenvectors, so that
    e^{−C⁻¹G h} = C^-½ e^{−M h} C^½. ``ss``: ``np.outer(s, s)`` if already formed (a
    march's steps share it)."""
    lam, v = np.linalg.eigh(g / (np.outer(s, s) if ss is None else ss))
    return (v * np.exp(-lam * h)) @ v.T
