"""Heat: a lumped thermal network of the clutch, its continuous rating and its peak time.

Three nodes with heat capacities from the region table, and the ambient air::

    coil ──G_cc── core ──G_kh── housing ──G_ha── air
      └───────────────G_ch─────────┘

* **coil**: copper + epoxy of the coil window; Joule power I²R(T), R linear in T.
* **core**: the inner stack — steel core, input and output drums, hub, shaft and the fluid;
  it receives the slip power T·ω of the clutch. The fluid's temperature is taken as this
  node's (the slip heat is made in the fluid; a lumped node cannot resolve the film).
* **housing**: shell, sleeve and end caps; it loses heat to the air.

Conductances (stated estimates, SI):

* through the winding radially, half its depth to each side, with the transverse
  conductivity of aligned conducting cylinders in the insulation + epoxy,
  k_w = k_m (1 + f)/(1 − f) at copper fraction f [rayleigh1892];
* radial cylindrical walls ln(r1/r0)/(2π k L) [incropera] for the sleeve and the stack of
  fluid films and drums between the core and the poles (over the band length from the
  coil, over the two zones to the housing's poles);
* the core into the back cap (axial, half its thickness) and out through the cap to the
  shell (radial) [incropera];
* the housing's outer surface to still air: natural convection of a horizontal cylinder
  (Churchill & Chu) [churchill-chu1975] at a film temperature difference of half the
  fluid's allowed rise, plus radiation (emissivity 0.3, machined steel) [incropera]. The
  housing's rotation and the mounts' conduction would cool more: neglected, so the rating
  is conservative.

Results: steady temperatures at a current (closed form — the coil's R(T) makes the
network linear in T with one rank-one term, solved by Sherman–Morrison), the continuous
current at the wire insulation's and the fluid's temperature limits (closed form), the
network's time constants, and the time from ambient to each limit at a peak current
(modal solution of the linear ODE).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.materials import (
    COIL,
    DENSITY,
    DENSITY_COPPER,
    DENSITY_EPOXY,
    RECORDS,
    copper_fraction,
)
from geometry.regions import Regions, layer, n_layers, rho

RHO_CU_20 = 1.72e-8  # Ω·m at 20 °C [materials] (docs/references.md)
ALPHA_CU = 0.00393  # 1/K, copper resistivity temperature coefficient [materials]

#: J/(kg·K): every registered material's (its data file: [incropera] Table A.1 for the
#: steels, AISI 304 and aluminium; the fluids' sheets), copper [incropera], epoxy typical.
SPECIFIC_HEAT: Mapping[str, float] = MappingProxyType(
    {**{n: float(r["specific_heat"]) for n, r in RECORDS.items()},
     "copper": 385.0, "epoxy": 1100.0}
)  # fmt: skip
#: W/(m·K): every registered material's (its data file), copper [incropera], epoxy + wire
#: enamel typical.
CONDUCTIVITY: Mapping[str, float] = MappingProxyType(
    {**{n: float(r["thermal_conductivity"]) for n, r in RECORDS.items()},
     "copper": 401.0, "epoxy": 0.2}
)  # fmt: skip
EMISSIVITY = 0.3  # machined steel, typical 0.2–0.4 [incropera]
SIGMA = 5.670374419e-8  # W/(m²·K⁴), Stefan–Boltzmann
# Air at 300 K [incropera] Table A.4: ν, thermal diffusivity, k, Pr
AIR_NU, AIR_ALPHA, AIR_K, AIR_PR = 15.89e-6, 22.5e-6, 0.0263, 0.707
#: IEC 60949 adiabatic short-time current: I²t = K² S² ln((θf + β)/(θi + β)), copper
#: K = 226 A·s^½/mm², β = 234.5 K [iec60949].
K_ADIABATIC_CU = 226e6  # A·s^½/m²
BETA_CU = 234.5  # K


def adiabatic_current_density(duration: Any, t_initial: Any, t_final: Any) -> Any:
    """Current density [A/m²] that heats copper adiabatically from ``t_initial`` to
    ``t_final`` (°C) in ``duration`` (s) [iec60949]."""
    ratio = (np.asarray(t_final) + BETA_CU) / (np.asarray(t_initial) + BETA_CU)
    return K_ADIABATIC_CU * np.sqrt(np.log(ratio) / np.asarray(duration))


def coil_resistance(fields: Mapping[str, Any], r_in: Any, r_out: Any, temperature: Any) -> Any:
    """Coil resistance [Ω] at ``temperature`` (°C): R = ρ(T) l / A, mean-turn length
    π(r_in + r_out) (floats or arrays)."""
    rho_e = RHO_CU_20 * (1 + ALPHA_CU * (np.asarray(temperature) - 20.0))  # [materials]
    length = fields["coil_turns"] * np.pi * (r_in + r_out)
    return rho_e * length / (np.pi * fields["wire_diameter"] ** 2 / 4)


def _wall(r0: Any, r1: Any, k: float, length: Any) -> Any:
    """Thermal resistance [K/W] of a cylindrical wall, ln(r1/r0)/(2π k L) [incropera]."""
    return np.log(r1 / r0) / (2 * np.pi * k * length)


def churchill_chu_h(diameter: Any, delta_t: Any, t_ambient: float) -> Any:
    """Natural-convection coefficient [W/(m²·K)] of a horizontal cylinder in air,
    Nu = {0.6 + 0.387 Ra^(1/6) / [1 + (0.559/Pr)^(9/16)]^(8/27)}² [churchill-chu1975]."""
    beta = 1.0 / (t_ambient + 273.15 + np.asarray(delta_t) / 2)
    ra = 9.81 * beta * np.asarray(delta_t) * diameter**3 / (AIR_NU * AIR_ALPHA)
    nu = (0.6 + 0.387 * ra ** (1 / 6) / (1 + (0.559 / AIR_PR) ** (9 / 16)) ** (8 / 27)) ** 2
    return nu * AIR_K / diameter


@dataclass(frozen=True)
class Network:
    """The three-node network of S designs (or one): capacities C [J/K] (…, 3), the
    conductance matrix G [W/K] (…, 3, 3) including the loss to air, the coil's resistance
    at 20 °C [Ω] and the ambient temperature [°C]."""

    capacity: Any
    conductance: Any
    to_air: Any  # W/K, housing to air
    r20: Any
    ambient: float
    inverse: Any  # G⁻¹ (…, 3, 3)


def network(rg: Regions, ambient: float = 20.0, fluid_limit: float = 130.0) -> Network:
    """The network of the designs of ``rg`` (module docstring)."""
    p, at = rg.fields, rg.at
    # capacities: every region's mass × specific heat, lumped by node
    cap = {"coil": 0.0, "core": 0.0, "housing": 0.0}
    r_ci, r_co = at["coil_in"], at["coil_out"]
    frac = copper_fraction(p["coil_turns"], p["wire_diameter"], p["coil_depth"] * p["band_length"])
    for sp in rg:
        r0, r1, z0, z1 = rg.bounds(sp)
        vol = np.pi * (r1**2 - r0**2) * (z1 - z0)
        if sp.material == COIL:
            c = vol * (frac * DENSITY_COPPER * SPECIFIC_HEAT["copper"]
                       + (1 - frac) * DENSITY_EPOXY * SPECIFIC_HEAT["epoxy"])  # fmt: skip
            cap["coil"] = cap["coil"] + c
            continue
        c = vol * DENSITY[sp.material] * RECORDS[sp.material]["specific_heat"]
        node = "housing" if sp.part == "housing" and sp.name != "core" else "core"
        cap[node] = cap[node] + c
    # conductances
    k_of = lambda name: float(RECORDS[name]["thermal_conductivity"])  # noqa: E731
    mat = rg.materials
    k_m = CONDUCTIVITY["epoxy"]
    k_w = k_m * (1 + frac) / (1 - frac)  # aligned cylinders, transverse [rayleigh1892]
    band = p["band_length"]
    r_cm = (r_ci + r_co) / 2
    pole = rg.pole_radius
    stack = 0.0  # K·m/W: the fluid/drum stack per unit length, core → poles
    for j in range(n_layers(rg.n)):
        kind = layer(j)[0]
        k = k_of(mat.fluid) if kind == "gap" else k_of(mat.drums)
        stack = stack + np.log(at[rho(j + 1)] / at[rho(j)]) / (2 * np.pi * k)
    r_coil_core = (_wall(r_ci, r_cm, k_w, band) + _wall(pole, r_ci, k_of(mat.housing), band)
                   + stack / band)  # fmt: skip
    r_coil_housing = _wall(r_cm, r_co, k_w, band)
    t_cap = p["end_cap_thickness"]
    r_core = rg.core_radius
    r_cap = (t_cap / 2) / (k_of(mat.housing) * np.pi * r_core**2) + _wall(
        r_core, rg.outer_radius, k_of(mat.housing), t_cap
    )
    g_core_housing = 2 * p["zone_length"] / stack + 1 / r_cap
    diameter = 2 * rg.outer_radius
    length = at["back"] - at["front"]
    area = np.pi * diameter * length + 2 * np.pi * rg.outer_radius**2
    dt = (fluid_limit - ambient) / 2  # film temperature difference (module docstring)
    t_s = ambient + dt + 273.15
    t_a = ambient + 273.15
    h_rad = EMISSIVITY * SIGMA * (t_s**2 + t_a**2) * (t_s + t_a)  # linearised radiation
    to_air = (churchill_chu_h(diameter, dt, ambient) + h_rad) * area
    g_cc, g_ch = 1 / r_coil_core, 1 / r_coil_housing
    shape = np.shape(g_cc)
    G = np.zeros((*shape, 3, 3))
    for i, j, g in ((0, 1, g_cc), (0, 2, g_ch), (1, 2, g_core_housing)):
        G[..., i, i] += g
        G[..., j, j] += g
        G[..., i, j] -= g
        G[..., j, i] -= g
    G[..., 2, 2] += to_air
    capacity = np.stack(np.broadcast_arrays(cap["coil"], cap["core"], cap["housing"]), -1)
    r20 = coil_resistance(p, r_ci, r_co, 20.0)
    return Network(capacity, G, to_air, r20, ambient, _inverse3(G))


def _inverse3(g: Any) -> Any:
    """Inverse of a stack (…, 3, 3) of matrices by the adjugate over the determinant
    (Cramer's rule): the same numbers as ``np.linalg.inv``, 5× faster on small matrices."""
    a = np.asarray(g, dtype=float)
    adj = np.empty_like(a)
    for i in range(3):
        for j in range(3):
            r0, r1 = (j + 1) % 3, (j + 2) % 3  # cofactor of (j, i), cyclic: signs built in
            c0, c1 = (i + 1) % 3, (i + 2) % 3
            adj[..., i, j] = a[..., r0, c0] * a[..., r1, c1] - a[..., r0, c1] * a[..., r1, c0]
    det = np.einsum("...j,...j->...", a[..., 0, :], adj[..., :, 0])
    return adj / det[..., None, None]


def steady(net: Network, current: Any, slip_power: Any = 0.0) -> Any:
    """Steady node temperatures [°C] (…, 3) — coil, core, housing — at ``current`` [A]
    with ``slip_power`` [W] into the core: (G − x a e0e0ᵀ) T = g T_amb + x c e0 + P e1,
    x = I², a = R20 α, c = R20 (1 − 20 α) (R linear in T). inf where the coil runs away
    (x a M00 ≥ 1)."""
    M = net.inverse
    x = np.asarray(current, dtype=float) ** 2
    a, c = net.r20 * ALPHA_CU, net.r20 * (1 - 20 * ALPHA_CU)
    base = _base(net, M, slip_power)
    den = 1 - x * a * M[..., 0, 0]
    t_coil = (base[..., 0] + x * c * M[..., 0, 0]) / den
    rest = base[..., 1:] + (x * (c + a * t_coil))[..., None] * M[..., 1:, 0]
    out = np.concatenate([t_coil[..., None], rest], -1)
    return np.where((den > 0)[..., None], out, np.inf)


def _base(net: Network, M: Any, slip_power: Any) -> Any:
    """Node temperatures with no coil current: ambient + the slip power's rise."""
    p = np.asarray(slip_power, dtype=float)
    return net.ambient + p[..., None] * M[..., :, 1]


def continuous_current(
    net: Network, wire_limit: float, fluid_limit: float, slip_power: Any = 0.0
) -> Any:
    """Largest current [A] whose steady coil temperature stays at or below ``wire_limit``
    and core (fluid) temperature at or below ``fluid_limit`` (°C), closed form from
    ``steady``; 0 where the slip power alone breaks a limit."""
    x = continuous_current_sq(net, wire_limit, fluid_limit)(slip_power)
    return np.sqrt(np.maximum(x, 0.0))


def continuous_current_sq(net: Network, wire_limit: float, fluid_limit: float) -> Any:
    """P ↦ I²: the square of ``continuous_current`` as a function of the slip power, its
    per-design constants computed once (the sweeps bisect on it). From ``steady``:
    coil at the limit when I² = (L_w − T0)/(M00 (c + a L_w)); core at the limit when
    I² = ΔT/(M10 (c + a T0) + a M00 ΔT), T0 and ΔT = L_f − T1 the no-current temperatures."""
    M = net.inverse
    a, c = net.r20 * ALPHA_CU, net.r20 * (1 - 20 * ALPHA_CU)
    m00, m10, m01, m11 = M[..., 0, 0], M[..., 1, 0], M[..., 0, 1], M[..., 1, 1]
    k_coil = 1 / (m00 * (c + a * wire_limit))
    amb = net.ambient

    def x_of(slip_power: Any) -> Any:
        p = np.asarray(slip_power, dtype=float)
        t0 = amb + p * m01
        dt = fluid_limit - (amb + p * m11)
        return np.minimum((wire_limit - t0) * k_coil, dt / (m10 * (c + a * t0) + a * m00 * dt))

    return x_of


def time_constants(net: Network) -> Any:
    """The network's time constants [s] (…, 3), longest first (coil resistance at 20 °C
    in its linear term left out: the current's own heating changes them little)."""
    lam = np.linalg.eigvals(np.linalg.solve(_diag(net.capacity), net.conductance)).real
    return np.sort(1 / lam, axis=-1)[..., ::-1]


def _diag(c: Any) -> Any:
    d = np.zeros((*np.shape(c), np.shape(c)[-1]))
    idx = np.arange(np.shape(c)[-1])
    d[..., idx, idx] = c
    return d


def time_to_limits(
    net: Network, current: float, slip_power: float, wire_limit: float, fluid_limit: float
) -> tuple[float, float]:
    """Seconds from ambient until the coil reaches ``wire_limit`` and the core (fluid)
    ``fluid_limit`` at a held ``current`` and ``slip_power`` (one design; inf if never):
    the linear ODE C dT/dt = −(G − x a e0e0ᵀ) T + g T_amb + x c e0 + P e1 solved by modes
    (``time_to_limits_batch`` on a batch of one)."""
    tw, tf = time_to_limits_batch(net, current, slip_power, wire_limit, fluid_limit)
    return float(tw[0]), float(tf[0])


def time_to_limits_batch(
    net: Network, current: Any, slip_power: Any, wire_limit: float, fluid_limit: float
) -> tuple[Any, Any]:
    """``time_to_limits`` for a batch of S designs at once (arrays (S,) of seconds, inf if
    never): the linear ODE solved by modes, T(t) = V diag(e^{λt}) V⁻¹ (T0 + A⁻¹b) − A⁻¹b,
    each limit bracketed on a log grid of times, then bisected."""
    S = np.broadcast_shapes(np.shape(net.capacity)[:-1], np.shape(current),
                            np.shape(slip_power), np.shape(net.r20))  # fmt: skip
    S = int(np.prod(S))
    C = np.array(np.broadcast_to(net.capacity, (S, 3)), dtype=float)
    G = np.array(np.broadcast_to(net.conductance, (S, 3, 3)), dtype=float)
    x = np.broadcast_to(np.asarray(current, dtype=float) ** 2, (S,))
    r20 = np.broadcast_to(np.asarray(net.r20, dtype=float), (S,))
    a, c = r20 * ALPHA_CU, r20 * (1 - 20 * ALPHA_CU)
    G[:, 0, 0] -= x * a
    to_air = np.broadcast_to(np.asarray(net.to_air, dtype=float), (S,))
    p_slip = np.broadcast_to(np.asarray(slip_power, dtype=float), (S,))
    q = np.stack([x * c, p_slip, to_air * net.ambient], -1)
    A = -G / C[:, :, None]
    b = q / C
    lam, V = np.linalg.eig(A)  # real: A is similar to the symmetric −C^-½ G C^-½
    lam, V = lam.real, V.real
    Vi = np.linalg.inv(V)
    p = np.linalg.solve(A, b[..., None])[..., 0]
    w0 = np.einsum("sij,sj->si", Vi, net.ambient + p)

    def temps(t: np.ndarray, node: int) -> np.ndarray:
        """Temperature of ``node`` at times t (S, N)."""
        # past e^300 every limit is crossed (e^700 × V w0 overflowed, issue 32)
        e = np.exp(np.minimum(lam[:, :, None] * t[:, None, :], 300.0))
        return np.einsum("sj,sjn->sn", V[:, node, :] * w0, e) - p[:, node, None]

    grid = np.concatenate([[0.0], np.logspace(-3, 6, 400)])
    out = []
    for node, limit in ((0, wire_limit), (1, fluid_limit)):
        above = temps(np.broadcast_to(grid, (S, grid.size)), node) >= limit
        hit = above.any(-1)
        first = np.where(hit, above.argmax(-1), 1)
        lo, hi = grid[np.maximum(first - 1, 0)], grid[first]
        for _ in range(60):  # bisection to a relative 1e-12 of the bracket
            mid = 0.5 * (lo + hi)
            up = temps(mid[:, None], node)[:, 0] >= limit
            hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
        out.append(np.where(hit, hi, np.inf))
    return out[0], out[1]
