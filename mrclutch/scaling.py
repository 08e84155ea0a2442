"""The paper's scaling study (Fig. 7b) with real geometry: reach k× torque three ways.

The paper scales the clutch abstractly (2× torque → +14 % total reflected inertia). Here
the torque is raised by changing the geometry, each route on the fast path:

* ``more drums`` — the smallest drum count whose torque reaches the target (a drum count
  is an integer, so the torque lands at or above it);
* ``longer drums`` — the active zone length that gives exactly the target torque;
* ``larger diameter`` — the drum inner diameter that gives exactly the target torque.

For each: the torque ratio reached and the changes in rotor inertia, total moving mass at
the hand (m1 + m2), reflected damping b1, clutch mass and the lumped rendering bandwidth
√(K/(m1+m2)) (Eq. 1) two ways: at the base design's K_max (``bandwidth_lumped_same_K``:
the same K on a heavier pair, so it falls — negative whenever the route adds moving mass,
whatever the materials) and at the route's own K_max (``bandwidth_lumped_own_K``: K_max ∝
the torque, so it rises with it). Each route's ``note`` says so when the first is negative.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from geometry.numerics import illinois
from geometry.params import INT_RANGES
from geometry.validation import ParameterError, check_range
from mrclutch.design import ClutchDesign
from mrclutch.pipeline import evaluate_batch

#: The most drums a design takes (DrumClutch's n_drums range): the drums route stops there.
MAX_DRUMS = next(hi for name, _, hi in INT_RANGES if name == "n_drums")
#: Paper §IV-B: "2X scaling increase by 14 % the total reflected inertia of MR system".
PAPER_TOTAL_INERTIA_INCREASE_2X = 0.14
#: The study's steps, as ``scaling_study`` reports them done: the base design, the three
#: routes' searches, the routes' figures.
STEPS = ("the base design", "more drums", "longer drums", "larger diameter",
         "the routes' figures")  # fmt: skip


@dataclass(frozen=True)
class Route:
    name: str
    parameter: str
    value: float  # SI, or a count
    torque_ratio: float
    changes: dict[str, float]  # relative changes against the base design
    note: str | None = None  # why a change is negative (bandwidth_note)


def _figures(design: ClutchDesign, fields: dict[str, Any]) -> dict[str, float]:
    r = evaluate_batch(fields, design)
    if r["valid"][0] != 1:
        raise ParameterError(f"scaling: {fields} gives an invalid clutch")
    return {k: float(v[0]) for k, v in r.items()}


def scaling_study(
    design: ClutchDesign,
    factor: float = 2.0,
    progress: Callable[[int, str], None] | None = None,
) -> tuple[dict[str, float], list[Route], list[str]]:
    """Base figures and the three routes to ``factor`` × the base torque, and the notes on
    routes out of reach. ``progress(n, what)``: called as each of the ``STEPS`` ends, with
    the steps done and the one about to start ("" after the last)."""
    check_range("factor", factor, 1.0, 10.0, lo_open=True)
    done = _steps(progress)
    c = design.clutch
    base = _figures(design, {})
    done()
    target = factor * base["max_torque_N_m"]

    def torque(name: str, value: float) -> float:
        return _figures(design, {name: value})["max_torque_N_m"] - target

    routes: list[tuple[str, str, float]] = []
    notes: list[str] = []
    n = c.n_drums
    while n < MAX_DRUMS and torque("n_drums", n) < 0:
        n += 1
    if torque("n_drums", n) < 0:  # the other routes may still reach it: not a refusal
        notes.append(
            f"more drums: {factor:g}× torque is out of reach with up to {MAX_DRUMS} drums "
            f"(the most drums a design takes); the row is at {n} drums"
        )
    routes.append(("more drums", "n_drums", n))
    done()
    for name, route, hi in (
        ("zone_length", "longer drums", 0.1),
        ("drum_inner_diameter", "larger diameter", 0.1),
    ):
        v0, f_hi = getattr(c, name), torque(name, hi)
        if f_hi >= 0:  # the root between the base design (below the target) and hi
            # Illinois regula falsi ([dowell-jarratt1971], geometry.numerics), not scipy's
            # brentq: its import alone was ~0.5 s of scale's CPU (issue 40)
            f0 = np.array([base["max_torque_N_m"] - target])
            v = illinois(lambda _act, x, nm=name: np.array([torque(nm, float(x[0]))]),
                         np.array([v0]), np.array([hi]), f0, np.array([f_hi]), 1e-10)  # fmt: skip
            routes.append((route, name, float(v[0])))
            done()
            continue
        # not reachable: report the best this route can do (the steel saturates)
        grid = np.linspace(v0, hi, 200)  # one batch, not 200 single designs (issue 40)
        r = evaluate_batch({name: grid}, design)
        best = grid[int(np.argmax(np.where(r["valid"] == 1, r["max_torque_N_m"], -np.inf)))]
        routes.append((route, name, float(best)))
        notes.append(
            f"{route}: {factor:g}× torque is out of reach — the magnetic circuit saturates; "
            f"the most it gives is at {name} = {best * 1e3:.3g} mm"
        )
        done()
    out = []
    m_tot0 = base["m1_kg"] + design.transmission.m2
    for route, name, value in routes:
        f = _figures(design, {name: value})
        m_tot = f["m1_kg"] + design.transmission.m2
        changes = {
            "rotor_inertia": f["rotor_inertia_kg_m2"] / base["rotor_inertia_kg_m2"] - 1,
            "moving_inertia": _moving(f) / _moving(base) - 1,
            "total_moving_mass": m_tot / m_tot0 - 1,
            "damping_b1": f["b1_N_s_per_m"] / base["b1_N_s_per_m"] - 1,
            "clutch_mass": f["clutch_mass_kg"] / base["clutch_mass_kg"] - 1,
            "bandwidth_lumped_same_K": float(np.sqrt(m_tot0 / m_tot)) - 1,  # Eq. 1 at fixed K
            # Eq. 1 at the route's own K_max = F_max/d (evaluate_batch's K and bandwidth)
            "bandwidth_lumped_own_K": f["bandwidth_lumped_hz"] / base["bandwidth_lumped_hz"] - 1,
        }
        out.append(
            Route(
                route,
                name,
                float(value),
                f["max_torque_N_m"] / base["max_torque_N_m"],
                changes,
                bandwidth_note(changes, base["K_N_per_m"], f["K_N_per_m"]),
            )
        )
    done()
    return base, out, notes


def _steps(progress: Callable[[int, str], None] | None) -> Callable[[], None]:
    """A ``done()`` that reports the next of ``STEPS`` ended to ``progress`` (nothing
    without it)."""
    count = [0]

    def done() -> None:
        count[0] += 1
        if progress is not None:
            progress(count[0], STEPS[count[0]] if count[0] < len(STEPS) else "")

    return done


def bandwidth_note(changes: dict[str, float], k_base: float, k_own: float) -> str | None:
    """Why a route's bandwidth change at the base design's K is negative (None when it is
    not): the same K [N/m] on more moving mass, √(K/(m1+m2)) (Eq. 1); beside it, the change
    at the route's own K_max."""
    same, own = changes["bandwidth_lumped_same_K"], changes["bandwidth_lumped_own_K"]
    if not same < 0:
        return None
    return (
        f"bandwidth_lumped_same_K {same:+.1%}: at the base design's K_max "
        f"({k_base:.4g} N/m) the route's added moving mass (m1+m2 "
        f"{changes['total_moving_mass']:+.1%}) lowers √(K/(m1+m2)) (Eq. 1) — a cost, not an "
        f"error; at its own K_max ({k_own:.4g} N/m, ∝ its torque) it changes by {own:+.1%}"
    )


def _moving(f: Any) -> float:
    """Rotor + the fluid it carries: what m1 reflects (Eq. 3)."""
    return float(np.ravel(f["rotor_inertia_kg_m2"] + f["fluid_inertia_kg_m2"])[0])


def as_json(
    base: dict[str, float], routes: list[Route], notes: list[str], design: ClutchDesign
) -> dict[str, Any]:
    return {
        "base": {
            "max_torque_N_m": base["max_torque_N_m"],
            "rotor_inertia_kg_m2": base["rotor_inertia_kg_m2"],
            "m1_kg": base["m1_kg"],
            "m2_kg": design.transmission.m2,
            "b1_N_s_per_m": base["b1_N_s_per_m"],
            "K_N_per_m": base["K_N_per_m"],
            "bandwidth_lumped_hz": base["bandwidth_lumped_hz"],
        },
        "paper_total_inertia_increase_2x": PAPER_TOTAL_INERTIA_INCREASE_2X,
        "notes": notes,
        "routes": [
            {
                "route": r.name,
                "parameter": r.parameter,
                "value": r.value,
                "torque_ratio": r.torque_ratio,
                "changes": r.changes,
                **({"note": r.note} if r.note else {}),
            }
            for r in routes
        ],
    }
