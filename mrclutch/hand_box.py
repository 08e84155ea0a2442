"""From the uncertain inputs to a box of the haptic parameters at the hand, for S designs
at once (``hand_box_batch``, docs/verdicts.md): the fast path at the geometry's corners,
the viscosity, temperature and runout factors on b1, the delay's range and the lot
spreads on K_max."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.materials import SLOTS, MaterialChoice
from magnetics.drag import drag_terms, totals
from mrclutch.at_hand import mr_at_hand
from mrclutch.batch import batch_fields
from mrclutch.design import ClutchDesign
from mrclutch.fast_batch import evaluate_batch
from mrclutch.haptics.actuator import HapticParams
from mrclutch.hot_rows import duty_hot_ends
from mrclutch.uncertainty import Uncertainty, default_uncertainty

# ---- from the uncertain inputs to a box of the haptic parameters -----------------------


@dataclass(frozen=True)
class HandBox:
    """Per design (1-D arrays of S), the haptic parameters at the hand: nominal and the
    (low, high) hull over the uncertain inputs. ``K`` is the rendered K_max = F_max/d
    (Eq. 4); ``k``, ``b``, ``m2`` (the transmission) are certain."""

    m1: tuple[np.ndarray, np.ndarray, np.ndarray]  # (nominal, low, high) kg
    b1: tuple[np.ndarray, np.ndarray, np.ndarray]  # N·s/m
    delay: tuple[np.ndarray, np.ndarray, np.ndarray]  # s
    K: tuple[np.ndarray, np.ndarray, np.ndarray]  # N/m
    k: np.ndarray
    b: np.ndarray
    m2: np.ndarray
    valid: np.ndarray  # bool

    def params(self, m1: Any, b1: Any, delay: Any) -> HapticParams:
        """HapticParams at these values (arrays broadcasting against (S, …) rows)."""
        extra = np.ndim(m1) - 1
        sh = (-1,) + (1,) * max(extra, 0)
        return HapticParams(m1, b1, self.k.reshape(sh), self.b.reshape(sh),
                            self.m2.reshape(sh), delay=delay)  # fmt: skip

    @property
    def nominal(self) -> HapticParams:
        return self.params(self.m1[0], self.b1[0], self.delay[0])


def _hand_of(rows: Mapping[str, np.ndarray], base: Any) -> tuple[np.ndarray, ...]:
    """(m1, b1, f_max, τ_eq, valid) at the hand of evaluate_batch's rows (``mr_at_hand``)."""
    ok = rows["valid"] > 0
    out = [np.full(ok.shape, np.nan) for _ in range(4)]
    if ok.any():
        inertia = rows["rotor_inertia_kg_m2"][ok] + rows["fluid_inertia_kg_m2"][ok]
        hp = mr_at_hand(base, inertia, rows["drag_damping_N_m_s"][ok], rows["max_torque_N_m"][ok],
                        rows["clutch_mass_kg"][ok], rows["torque_delay_s"][ok])  # fmt: skip
        for o, v in zip(out, (hp.m1, hp.b1, hp.f_max, rows["torque_delay_s"][ok]), strict=True):
            o[ok] = np.broadcast_to(v, (int(ok.sum()),))
    return (*out, ok)


def _temperature_factors(p: Mapping[str, np.ndarray], ok: np.ndarray, base: Any,
                         temps: tuple[Any, Any],
                         mats: MaterialChoice | np.ndarray | None = None,
                         ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(low, high) of the drag damping over the fluid temperature range, relative to its
    value at the operating temperature (η(T) monotone: the range's ends bound it; each end
    a float, or S of them: one a row); ``mats``: the rows' materials (None: the base
    design's)."""
    op = base.operating

    def fn(rg: Any, rows: np.ndarray) -> dict[str, Any]:
        at = [t if np.ndim(t) == 0 else np.asarray(t)[rows] for t in temps]  # per row: "duty"
        d = [totals(drag_terms(rg, op.input_speed, t, base.support))[1]
             for t in (op.fluid_temperature, *at)]  # fmt: skip
        return {"lo": d[1] / d[0], "hi": d[2] / d[0]}

    f = regions.per_topology(p, ok, fn, base.materials if mats is None else mats)
    return np.fmin(f["lo"], f["hi"]), np.fmax(f["lo"], f["hi"])


def hand_box_batch(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign | None = None,
    uncertainty: Uncertainty | None = None,
    nominal: Mapping[str, np.ndarray] | None = None,
) -> HandBox:
    """The :class:`HandBox` of S designs (the field arrays ``evaluate_batch`` takes) over
    ``uncertainty`` (None: ``default_uncertainty(base)``).

    * geometry: the fast path (``evaluate_batch``) at the four corners of gap ± tolerance
      × drum thickness ± tolerance besides the nominal; m1, b1, F_max and τ_eq take the
      hull of the five (interior points lie inside it: tested);
    * b1 × (1 ± viscosity spread) × the drag's range over the fluid temperatures
      (``_temperature_factors``; a ``"duty"`` range's hot end is each row's own, the end
      of its duty hold: ``mrclutch.hot_rows.duty_hot_ends``); its top × g/√(g² − e²) for a
      runout e (the mean of 1/(g − e cos θ) around the drum: (1/2π)∫dθ/(g − e cos θ) =
      1/√(g² − e²), by residues), then + bench damping;
    * τ: the declared range, or the typed delay to the geometry's τ_eq (all corners);
    * K = F_max/d × the torque factor (yield stress and B–H lot spreads).

    ``nominal``: ``evaluate_batch(fields, base)``'s rows if already computed."""
    base = base if base is not None else ClutchDesign()
    unc = uncertainty if uncertainty is not None else default_uncertainty(base)
    p, mats = batch_fields(fields, base)  # a material column: per row (issue 45)
    names = {}  # the material columns, one name a row, for the corners' fast-path runs
    if not isinstance(mats, MaterialChoice):
        names = {k: np.array([getattr(m, k) for m in mats], object) for k in SLOTS if k in fields}
    at = {**p, **names}
    size = np.asarray(p["gap"]).size
    corner_rows = None
    if unc.gap_tolerance > 0 or unc.drum_thickness_tolerance > 0:
        # the four corners as one batch of 4 S designs (one fast-path call, not four)
        corners = [
            (dg, dt)
            for dg in (-unc.gap_tolerance, unc.gap_tolerance)
            for dt in (-unc.drum_thickness_tolerance, unc.drum_thickness_tolerance)
        ]
        q = {k: np.tile(v, 4) for k, v in at.items()}
        q["gap"] = np.concatenate([p["gap"] + dg for dg, _ in corners])
        q["drum_thickness"] = np.concatenate([p["drum_thickness"] + dt for _, dt in corners])
        if nominal is None:  # the nominal rows in the same call (a row's figures are its own)
            both = evaluate_batch({k: np.concatenate([at[k], q[k]]) for k in q}, base,
                                  continuous=False)  # fmt: skip
            nominal = {k: v[:size] for k, v in both.items()}
            corner_rows = {k: v[size:] for k, v in both.items()}
        else:
            corner_rows = evaluate_batch(q, base, continuous=False)
    # the box reads m1, b1, F_max and τ_eq of the rows: no continuous torque (issue 40)
    rows0 = nominal if nominal is not None else evaluate_batch(at, base, continuous=False)
    m1_0, b1_0, f_0, teq_0, ok = _hand_of(rows0, base)
    stack = [x[None] for x in (m1_0, b1_0, f_0, teq_0)]
    if corner_rows is not None:
        hand = _hand_of(corner_rows, base)[:4]
        stack = [np.concatenate([s, c.reshape(4, -1)]) for s, c in zip(stack, hand, strict=True)]
    # hull over the corners; a corner the validation refuses (NaN) is left out
    (m1_lo, b1_lo, f_lo, teq_lo), (m1_hi, b1_hi, f_hi, teq_hi) = (
        [np.where(ok, fn.reduce(s, axis=0), np.nan) for s in stack] for fn in (np.fmin, np.fmax)
    )
    op = base.operating
    t_lo, t_hi = unc.fluid_temperature if unc.fluid_temperature is not None else (
        op.fluid_temperature, op.fluid_temperature)  # fmt: skip
    if unc.fluid_temperature_from == "duty":  # each row's own duty hold (mrclutch.hot_rows)
        t_hi = duty_hot_ends({**p, **names}, base, ok)
    ft_lo, ft_hi = _temperature_factors(p, ok, base, (t_lo, t_hi), mats)
    g = p["gap"]
    runout = g / np.sqrt(np.maximum(g * g - unc.runout**2, 1e-30))  # e < g: the drums clear
    b1_lo = b1_lo * (1 - unc.viscosity_spread) * ft_lo + unc.bench_damping[0]
    b1_hi = b1_hi * (1 + unc.viscosity_spread) * ft_hi * runout + unc.bench_damping[1]
    d0 = teq_0 if op.delay_source == "geometry" else np.full(ok.shape, op.delay)
    if unc.delay is not None:
        tau_lo, tau_hi = np.full(ok.shape, unc.delay[0]), np.full(ok.shape, unc.delay[1])
    else:
        tau_lo, tau_hi = np.fmin(teq_lo, op.delay), np.fmax(teq_hi, op.delay)
    w = base.transmission.workspace
    c_lo, c_hi = unc.torque_factor
    tr = base.transmission
    n = ok.shape
    # a corner with no finite figure (a torque response that never settles: τ_eq = inf)
    # leaves the design unjudged (NaN) rather than judged on a part of its ranges
    for x in (m1_lo, m1_hi, b1_lo, b1_hi, f_lo, f_hi, tau_lo, tau_hi):
        ok = ok & np.isfinite(x)
    return HandBox(
        m1=(m1_0, m1_lo, m1_hi),
        b1=(b1_0, b1_lo, b1_hi),
        delay=tuple(np.where(ok, x, np.nan) for x in (d0, tau_lo, tau_hi)),
        K=(f_0 / w, f_lo * c_lo / w, f_hi * c_hi / w),
        k=np.full(n, tr.k), b=np.full(n, tr.b), m2=np.full(n, tr.m2), valid=ok,
    )  # fmt: skip
