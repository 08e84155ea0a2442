"""What the hand feels of the steel's memory and of the rotors' runout (issue 41, items 1
and 2): the residual torque and the torque–current loop (``magnetics.hysteresis``), the
runout ripple (``magnetics.ripple``), each carried to the hand through the design's
transmission (F = T·nG/l, [lebel] Eq. 4) and set beside what a hand can tell apart.

"Negligible" in the paper's sense ([lebel] Fig. 2b: "negligible magnetic hysteresis"):
the hand cannot tell the rising branch from the falling one — the loop's widest gap,
against the torque at the current limit (% of full scale), is below the force
discrimination threshold of the hand, a just-noticeable difference of about 7 % of the
reference force ([pang1991], 2.5–10 N squeezed between finger and thumb). The same
threshold is set beside the ripple (its amplitude against the full-scale torque). An
absolute force-detection threshold of the hand for a sinusoid at the ripple's frequency
(~9 Hz at 530 rpm) is published for a pen-hold grip [israr2006]; its value could not be
read in this work and is not used (docs/hysteresis.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.params import MIN_GAP, valid
from magnetics.circuit import MagneticPath, path_from_regions, path_from_section
from magnetics.hysteresis import coercive_current, pulse_train, torque_loop
from magnetics.network import network_from_regions
from magnetics.ripple import GAP_STEP, gap_derivatives, ripple_amplitude
from magnetics.torque import network_torque_and_flux
from mrclutch.batch import batch_fields
from mrclutch.design import ClutchDesign, current_limit
from mrclutch.design_network import network_yield, section_network

#: % of the reference force: the hand's force JND ([pang1991], about 7 %).
FORCE_JND_PCT = 7.0
#: Currents on the loop's table (0 … the current limit).
LOOP_POINTS = 15
#: The sweep's and the optimiser's columns of this module (``feel_batch``).
FEEL_COLUMNS = ("residual_torque_N_m", "hysteresis_width_pct", "ripple_torque_N_m",
                "ripple_force_N")  # fmt: skip


def slip_frequency(design: ClutchDesign) -> float:
    """Hz: the input's speed against an output held by the hand (ω_out ≈ 0)."""
    return design.operating.input_speed_rpm / 60.0


def feel_figures(design: ClutchDesign, max_torque: float, yield_torque: float,
                 off_torque: float, backdrive: float | None = None,
                 path: MagneticPath | None = None) -> dict[str, Any]:  # fmt: skip
    """The residual torque, the loop and the ripple of one design, and what each is at the
    hand (N), as ``evaluate --json``'s ``feel``. ``max_torque``, ``yield_torque`` and
    ``off_torque`` (N·m): the clutch figures at the current limit; ``backdrive`` (N): the
    unpowered lever's backdrive force, to which the residual force adds. ``path``: the
    design's circuit (``path_from_section``) where the caller built it already."""
    section, net = section_network(design.clutch, design.materials)  # evaluate's network
    path = path_from_section(section) if path is None else path
    peak = design.current_limit
    reduction = design.transmission.reduction  # F = T·nG/l [lebel] Eq. 4

    def torque_at(cur: ArrayLike) -> np.ndarray:
        return network_yield(section, net, np.asarray(cur, float))

    ic = float(coercive_current(path, [peak])[0])
    loop = torque_loop(torque_at, peak, ic, LOOP_POINTS)
    pulses = pulse_train(peak)
    ic_pulse = float(coercive_current(path, [abs(pulses[-1])])[0])
    t_pulse = float(torque_at([ic_pulse])[0])
    width_pct = 100.0 * float(np.max(loop.width)) / yield_torque
    floor = off_torque + loop.residual
    residual_force = loop.residual * reduction
    hyst = {
        "peak_current_A": peak,
        "coercive_current_A": ic,
        "residual_torque_N_m": loop.residual,
        "residual_force_N": residual_force,
        "pulse_currents_A": [float(x) for x in pulses],
        "coercive_current_after_pulse_A": ic_pulse,
        "residual_torque_after_pulse_N_m": t_pulse,
        "loop": {
            "current_A": loop.current.tolist(),
            "rising_N_m": loop.rising.tolist(),
            "falling_N_m": loop.falling.tolist(),
        },
        "hysteresis_width_pct": width_pct,
        "force_jnd_pct": FORCE_JND_PCT,
        "negligible": bool(width_pct < FORCE_JND_PCT),
        "dynamic_range_with_residual_dB": float(20 * np.log10(max_torque / floor)),
        "backdrive_force_with_residual_N": (
            None if backdrive is None else float(backdrive + residual_force)
        ),
    }
    gd = gap_derivatives(design.clutch, peak, design.materials)
    ecc = design.process.runout / 2  # TIR R → eccentricity R/2 (mrclutch.process)
    amp = float(ripple_amplitude(gd.second, ecc, ecc))
    ripple = {
        "runout_m": design.process.runout,
        "d_torque_d_gap_N_m_per_m": gd.first,
        "d2_torque_d_gap2_N_m_per_m2": gd.second,
        "fd_check": gd.fd_check,
        "ripple_torque_N_m": amp,
        "ripple_frequency_hz": slip_frequency(design),
        "ripple_force_N": amp * reduction,
        "ripple_pct": 100.0 * amp / max_torque,
        "force_jnd_pct": FORCE_JND_PCT,
    }
    return {"hysteresis": hyst, "ripple": ripple}


def feel_batch(fields: Mapping[str, Any], base: ClutchDesign,
               columns: tuple[str, ...] = FEEL_COLUMNS) -> dict[str, np.ndarray]:  # fmt: skip
    """``FEEL_COLUMNS`` for S designs (a sweep's fields around ``base``): the same models
    as ``feel_figures`` on arrays, by drum count. The loop's width is read at 8 currents
    (0 … the limit), the ripple's T'' by central differences at ±``GAP_STEP``. Rows that
    fail validation are NaN."""
    p, mats = batch_fields(fields, base)
    ok = valid(p)
    op = base.operating
    current = np.array(np.broadcast_to(current_limit(op, p["wire_diameter"]), ok.shape), float)
    want_ripple = any(c.startswith("ripple") for c in columns)
    frac = np.linspace(0.0, 1.0, 8)

    def yield_at(rg: regions.Regions, cur: np.ndarray) -> np.ndarray:
        return network_torque_and_flux(network_from_regions(rg), cur)[0].sum(-1)

    def hyst(rg: regions.Regions, rows: np.ndarray) -> dict[str, Any]:
        i = current[rows]
        ic = coercive_current(path_from_regions(rg), i)
        cur = i[:, None] * frac[None, :]
        t = yield_at(rg, np.concatenate([np.abs(cur - ic[:, None]), cur + ic[:, None],
                                         i[:, None]], axis=1))  # fmt: skip
        n = frac.size
        width = (t[:, n : 2 * n] - t[:, :n]).max(axis=1)
        return {"residual": t[:, n], "width_pct": 100.0 * width / t[:, -1]}

    # as gap_derivatives: near the smallest gap the stencil moves up (every point valid)
    centre = np.maximum(p["gap"], MIN_GAP + GAP_STEP)

    def at_gap(step: float) -> np.ndarray:
        q = {**p, "gap": centre + step}
        return regions.per_topology(q, ok, lambda rg, rows: {
            "t": yield_at(rg, current[rows][:, None])[:, 0]}, mats)["t"]  # fmt: skip

    h = regions.per_topology(p, ok, hyst, mats)
    out = {"residual_torque_N_m": h["residual"], "hysteresis_width_pct": h["width_pct"]}
    if want_ripple:
        t0, tp, tm = at_gap(0.0), at_gap(GAP_STEP), at_gap(-GAP_STEP)
        d2 = (tp - 2 * t0 + tm) / GAP_STEP**2  # central second difference
        ecc = base.process.runout / 2
        amp = ripple_amplitude(d2, ecc, ecc)
        out["ripple_torque_N_m"] = amp
        out["ripple_force_N"] = amp * base.transmission.reduction
    return {k: out[k] for k in columns if k in out}
