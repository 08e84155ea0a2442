"""What ``mrclutch torque`` and ``mrclutch field`` compute: the currents asked for, the
torque curves by each method, the network-vs-FEM difference, the flux linkage and
inductance beside them, and the FEM flux-density map at one current.

The CLI (mrclutch/cli/commands/magnetics.py) parses, calls these and formats. A FEM that
does not converge ends in a ParameterError (one line, exit 2), as any bad input does.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from geometry.section import Section, build_section
from geometry.validation import ParameterError
from magnetics.circuit import path_from_section
from magnetics.drag import Support
from magnetics.dynamics import flux_linkage
from magnetics.fem import DEFAULT_SIZE, FEMConvergenceError, solve_fem
from magnetics.fem.grid import check_memory, time_estimate
from magnetics.network import flux_linkage as network_flux_linkage
from magnetics.network import network_from_regions
from magnetics.torque import TorqueCurve, torque_curve
from mrclutch.design import ClutchDesign, current_notes
from mrclutch.torque_for import current_for

#: m: the FEM's element size for the torque curves (magnetics.fem.DEFAULT_SIZE).
FEM_SIZE = DEFAULT_SIZE
#: the most currents one ``--current START:STOP:STEP`` may ask for.
MAX_POINTS = 10_000


def parse_currents(text: str) -> np.ndarray:
    """``A``, ``START:STOP:STEP`` (inclusive of STOP) or ``A,B,C`` in amperes."""
    too_many = False
    try:
        if ":" in text:
            a, b, s = (float(x) for x in text.split(":"))
            if not (s > 0 and b >= a) or not all(np.isfinite([a, b, s])):
                raise ValueError
            too_many = (b - a) / s > MAX_POINTS
            vals = np.arange(a, b + s * 1e-9, s) if not too_many else np.zeros(0)
        else:
            vals = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise ParameterError(
            f"--current {text!r}: give A, A,B,C or START:STOP:STEP with STEP > 0, STOP ≥ START"
        ) from None
    if too_many:
        raise ParameterError(f"--current {text}: more than {MAX_POINTS} points")
    if not np.all(np.isfinite(vals)) or vals.size == 0:
        raise ParameterError(f"--current {text!r}: currents must be finite numbers (A)")
    return vals


def currents_asked(design: ClutchDesign, text: str | None, ignore_limit: bool) -> np.ndarray:
    """The currents ``text`` asks for (None: 0 to the design's current limit in 0.5 A steps),
    each within [0, the design's current limit] unless ``ignore_limit``."""
    limit = design.current_limit
    if text is None:
        steps = np.arange(0.0, limit, 0.5)
        return np.append(steps, limit) if limit - steps[-1] > 1e-9 else steps
    currents = parse_currents(text)
    if ignore_limit:
        return currents
    if np.any(currents < 0):
        raise ParameterError(f"--current {text}: {currents.min():g} A is negative; the "
                             "yield torque does not depend on the current's sign (give "
                             "--ignore-limit to compute it anyway)")  # fmt: skip
    if np.any(currents > limit * (1 + 1e-9)):
        why = "; ".join(current_notes(design)) or f"max_current_A = {limit:g}"
        raise ParameterError(f"--current {text}: {currents.max():g} A is above the design's "
                             f"current limit {limit:.4g} A ({why}); give --ignore-limit to "
                             "compute it anyway")  # fmt: skip
    return currents


def fem_seconds(section: Section, n: int) -> float:
    """Seconds ``n`` FEM solves at FEM_SIZE are estimated to take (magnetics.fem.grid's
    measured rate per grid node); refuses a grid past the memory first."""
    check_memory(section, FEM_SIZE)
    return time_estimate(section, FEM_SIZE, n)


def torque_curves(section: Section, currents: Any, methods: tuple[str, ...], *,
                  speed_rpm: float, temperature: float,
                  support: Support | None = None) -> list[TorqueCurve]:  # fmt: skip
    """The torque curve (magnetics.torque.torque_curve) of each method at the currents (A),
    the slip speed (rpm) and the fluid temperature (°C), with ``support``'s bearing and
    seal drag (a design's ``[support]``; None: magnetics.drag's default)."""
    try:
        return [torque_curve(section, currents, method=m, speed_rpm=speed_rpm,
                             temperature=temperature, support=support)
                for m in methods]  # fmt: skip
    except FEMConvergenceError as exc:
        raise ParameterError(str(exc)) from None
    except FloatingPointError as exc:  # pragma: no cover - defensive
        raise ParameterError(str(exc)) from None


def largest_difference(network: TorqueCurve, fem: TorqueCurve) -> float:
    """The largest relative network-vs-FEM torque difference where the FEM torque is not ~0
    (above 10× its off-state torque: 0 A gives only drag); 0 where none is."""
    c, f = network.torque, fem.torque
    keep = f > 10 * fem.off_state_torque
    return float(np.max(np.abs(c[keep] / f[keep] - 1))) if keep.any() else 0.0


def inductance(section: Section, currents: Any, model: str = "circuit") -> tuple[Any, Any]:
    """Flux linkage λ (Wb) and incremental inductance dλ/dI (H) at the currents, by the
    saturating circuit (magnetics.dynamics.flux_linkage) or the reluctance network
    (magnetics.network.flux_linkage: within 1 % of the FEM's λ on the paper preset)."""
    section = section if hasattr(section, "regions") else build_section(section)
    cur = np.asarray(currents, dtype=float)[None, :]
    if model == "network":
        net = network_from_regions(section.table)
        lam, ind = network_flux_linkage(net, net.turns[:, None] * cur)
    else:
        lam, ind = flux_linkage(path_from_section(section), cur)
    return lam[0], ind[0]


def currents_for(design: ClutchDesign, torque: float, methods: tuple[str, ...], limit: float,
                 *, speed_rpm: float, temperature: float) -> list[dict[str, Any]]:  # fmt: skip
    """``torque --for``: mrclutch.torque_for.current_for by each method."""
    try:
        return [current_for(design, torque, m, limit, speed_rpm=speed_rpm,
                            temperature=temperature) for m in methods]  # fmt: skip
    except FEMConvergenceError as exc:
        raise ParameterError(str(exc)) from None


def field_map(design: ClutchDesign, current: float, size: float | None) -> tuple[Section, Any]:
    """The design's section and its FEM solution (magnetics.fem.solve_fem) at ``current``
    (A), element size ``size`` (m; None: the FEM's default)."""
    section = build_section(design.clutch, design.materials)
    try:
        return section, solve_fem(section, current, size=size)
    except FEMConvergenceError as exc:
        raise ParameterError(str(exc)) from None


def b_max(solution: Any) -> float:
    """The largest |B| (T) of a FEM solution."""
    return float(solution.b.max())


def overload_note(design: ClutchDesign, current: float) -> str | None:
    """Why a field past the design's current limit is so high (the copper's current density,
    the air-core ampere-turns past the steel's saturation), or None within the limit."""
    limit = design.current_limit
    amps = abs(current)
    if amps <= limit:
        return None
    c = design.clutch
    j = amps / (math.pi * c.wire_diameter**2 / 4) * 1e-6  # A/mm²: I over the wire's area
    return (f"{amps:g} A is {amps / limit:.3g}× the design's current limit "
            f"({limit:.3g} A): {j:.3g} A/mm² in the copper, which the wire does not "
            "survive; past the steel's saturation (about 2 T) the rest of |B| is the "
            f"air-core field of {c.coil_turns * amps:.3g} ampere-turns")  # fmt: skip
