"""The current a clutch needs for a torque: ``mrclutch torque --for NM``.

The clutch torque T(I) (yield + viscous drag at the slip speed, magnetics.torque) rises
monotonically with the coil current from the off-state torque T(0) (the yield stress
τy(H) rises with H, and H with the ampere-turns, through saturation), so the current for
a torque T* is the one root of T(I) − T* on [0, I_limit], found by Brent's method
(scipy.optimize.brentq; R. P. Brent, Algorithms for Minimization without Derivatives,
1973) on the method's own T(I): the reluctance network (the fast path), the single-loop
circuit or the FEM (the reference). Out of reach (T* above T(I_limit)) the answer is the
most the clutch gives, at the limit; below the off-state torque it is 0 A.
"""

from __future__ import annotations

from typing import Any

from geometry.section import build_section
from magnetics.torque import torque_curve
from mrclutch.design import ClutchDesign

#: A: the current's resolution of the answer (well under any amplifier's).
CURRENT_TOL = 1e-4
#: What each method is, as printed beside its answer.
METHOD_LABELS = {"network": "reluctance network (fast)", "circuit": "single-loop circuit",
                 "fem": "FEM (reference)"}  # fmt: skip


def current_for(design: ClutchDesign, torque: float, method: str = "network",
                limit: float | None = None, *, speed_rpm: float | None = None,
                temperature: float | None = None) -> dict[str, Any]:  # fmt: skip
    """The current (A) at which ``method`` gives ``torque`` (N·m) on ``design``, searched on
    [0, ``limit``] (None: the design's current limit): a dict of the method, the current
    (None when out of reach), the torque at 0 A and at the limit, and a one-line ``text``.
    ``speed_rpm`` / ``temperature`` (°C): the slip speed and the fluid temperature (None:
    the design's operating ones)."""
    from scipy.optimize import brentq

    op = design.operating
    limit = design.current_limit if limit is None else float(limit)
    speed = op.input_speed_rpm if speed_rpm is None else speed_rpm
    temp = op.fluid_temperature if temperature is None else temperature
    section = build_section(design.clutch, design.materials)

    def T(i: float) -> float:
        c = torque_curve(section, [i], method=method, speed_rpm=speed, temperature=temp,
                         support=design.support)  # fmt: skip
        return float(c.torque[0])

    t0, t_lim = T(0.0), T(limit)
    out: dict[str, Any] = {"method": method, "torque_N_m": torque, "limit_A": limit,
                           "torque_at_0A_N_m": t0, "torque_at_limit_N_m": t_lim}  # fmt: skip
    label = METHOD_LABELS[method]
    cap = design.current_limit
    end = ("the current limit" if limit == cap else
           f"the search's end, past the design's current limit {cap:.4g} A")  # fmt: skip
    if torque > t_lim:
        out["current_A"] = None
        out["text"] = (f"{label}: {torque:.4g} N·m is out of reach: the most is {t_lim:.4g} N·m "
                       f"at {limit:.4g} A ({end})")  # fmt: skip
    elif torque <= t0:
        out["current_A"] = 0.0
        out["text"] = (f"{label}: 0 A — the off-state torque {t0:.4g} N·m (drag at "
                       f"{speed:g} rpm) already reaches {torque:.4g} N·m")  # fmt: skip
    else:
        i = float(brentq(lambda x: T(x) - torque, 0.0, limit, xtol=CURRENT_TOL))
        out["current_A"] = i
        out["text"] = (f"{label}: {i:.4g} A for {torque:.4g} N·m (at {speed:g} rpm, fluid "
                       f"{temp:g} °C; {limit:.4g} A, {end}, gives {t_lim:.4g} N·m)")  # fmt: skip
    return out
