"""Remanence and hysteresis of the steels: what an "off" clutch still transmits after a
peak current, and the torque–current loop (issue 41, item 1). SI units.

Model, in two steps.

1. **The steel's loop** from three numbers of each steel's data file (``[hysteresis]``:
   the major loop's coercivity Hc and remanence Br, each with its source: typical values
   for the grade, unverified where not read — a sister alloy's read figure for Hiperco
   50 [modelica-msl-hysteresis]; as-received stainless measures harder than handbooks
   say [oxley2009]) and its B–H table (the saturation polarisation Js = B − μ0·H at the
   table's last point). Takács's T(x) model [takacs2001]: the branches of a loop
   reaching ±Hm are

       J↓(H) = Js·tanh((H + Hc)/a) − b,   J↑(H) = Js·tanh((H − Hc)/a) + b,
       a = Hc / artanh(Br/Js)  (the major loop, b → 0, passes through (0, Br)),
       b = (Js/2)·[tanh((Hm + Hc)/a) − tanh((Hm − Hc)/a)]  (the branches meet at ±Hm),

   so the loop reached from a peak field Hm has the coercivity (J↑ = 0)

       Hc(Hm) = Hc − a·artanh(b/Js),

   which rises from 0 at Hm = 0 to Hc for a peak far past the knee (``coercivity_after``).

2. **The clutch's loop** by the shifted-curve model: on a branch of coercivity Hc,m each
   steel element's H(B) is the library's (single-valued) curve shifted by ∓Hc,m. Around
   the flux loop ∮H·dl = N·I, so the shift moves to the right-hand side: the falling branch
   at current I is the single-valued network at I + I_c, the rising one at I − I_c, with
   the **coercive current**

       I_c = Σ_steel Hc,m·l / N  (``coercive_current``)

   over the loop's steel elements (core, poles, back iron, drum walls; lengths from the
   magnetic circuit, ``magnetics.circuit.MagneticPath``), each Hc,m read at the element's
   peak field (the circuit's flux density at the peak current on the library curve). At
   0 A after the peak the clutch therefore transmits the single-valued yield torque at
   I_c: the **residual torque**.

A **demagnetising pulse train** (``PULSE_RATIO``, ``PULSE_STEPS``): the current reversed and
halved at each step, I_p·(−1/2)^k, k = 1…n, then 0. The state left is that of the last,
smallest loop (amplitude I_p/2^n), whose coercivity Hc(Hm) falls towards 0 with its peak
field: the residual after the train is the yield torque at that loop's coercive current.

Where it breaks down: the shifted curve shifts every element by the same Hc,m whatever
its B, so near the loop's tip (deep saturation) it overstates the width — the branches do
not close exactly at ±I_p; the drum walls are taken with the single loop's flux (the
circuit), not the ladder's; eddy currents (rate-dependent loops) are the torque
response's business (``magnetics.dynamics``), not this static loop's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.materials import RECORDS
from geometry.validation import ParameterError, check_positive
from magnetics.circuit import MagneticPath, solve_path
from magnetics.materials import MATERIALS, MU0, BHCurve, Magnetic

FloatArray = NDArray[np.float64]
#: The demagnetising train: each pulse reverses and scales the last by this ratio …
PULSE_RATIO = -0.5
#: … this many times after the peak, then the current returns to 0.
PULSE_STEPS = 6


@dataclass(frozen=True)
class Hysteresis:
    """A steel's major loop: coercivity Hc (A/m), remanence Br (T), saturation
    polarisation Js (T) and where Hc and Br come from."""

    name: str
    coercivity: float  # A/m
    remanence: float  # T
    saturation: float  # T, polarisation Js = B − μ0 H at saturation
    source: str = ""

    def __post_init__(self) -> None:
        check_positive(f"{self.name}.saturation", self.saturation, " T")
        if not (0.0 < self.coercivity <= 1e5 and math.isfinite(self.coercivity)):
            raise ParameterError(f"{self.name}.coercivity_A_per_m = {self.coercivity!r}: must "
                                 "be in (0, 1e5] A/m (a soft magnetic steel)")  # fmt: skip
        if not 0.0 < self.remanence < self.saturation:
            raise ParameterError(f"{self.name}.remanence_T = {self.remanence!r}: must be in "
                                 f"(0, {self.saturation:.4g}) T (below Js)")  # fmt: skip

    @property
    def shape(self) -> float:
        """a = Hc / artanh(Br/Js), A/m: the major loop's width scale [takacs2001]."""
        return self.coercivity / math.atanh(self.remanence / self.saturation)

    def closure(self, h_peak: ArrayLike) -> FloatArray:
        """b(Hm) = (Js/2)·[tanh((Hm + Hc)/a) − tanh((Hm − Hc)/a)], T: the offset that
        closes the loop reaching ±Hm [takacs2001]."""
        hm = np.abs(np.asarray(h_peak, dtype=float))
        a, hc = self.shape, self.coercivity
        return 0.5 * self.saturation * (np.tanh((hm + hc) / a) - np.tanh((hm - hc) / a))

    def coercivity_after(self, h_peak: ArrayLike) -> FloatArray:
        """Hc(Hm) = Hc − a·artanh(b(Hm)/Js), A/m: the coercivity of the loop reached from a
        peak field Hm (A/m): 0 at Hm = 0, Hc far past the knee [takacs2001]."""
        b = self.closure(h_peak)
        return self.coercivity - self.shape * np.arctanh(b / self.saturation)

    def falling(self, h: ArrayLike, h_peak: ArrayLike) -> FloatArray:
        """J↓(H) = Js·tanh((H + Hc)/a) − b(Hm), T: the loop's falling branch."""
        h = np.asarray(h, dtype=float)
        return self.saturation * np.tanh((h + self.coercivity) / self.shape) - self.closure(h_peak)

    def rising(self, h: ArrayLike, h_peak: ArrayLike) -> FloatArray:
        """J↑(H) = Js·tanh((H − Hc)/a) + b(Hm), T: the loop's rising branch."""
        h = np.asarray(h, dtype=float)
        return self.saturation * np.tanh((h - self.coercivity) / self.shape) + self.closure(h_peak)


def saturation_polarisation(curve: Magnetic) -> float:
    """Js = B − μ0·H at the B–H table's last point, T (the table reaches saturation)."""
    if not isinstance(curve, BHCurve):
        raise ParameterError(f"{curve.name}: linear material, no saturation polarisation")
    return float(curve.b_table[-1] - MU0 * curve.h_table[-1])


def hysteresis_of(rec: Mapping[str, Any], curve: Magnetic, where: str) -> Hysteresis:
    """A steel record's ``[hysteresis]`` table (``coercivity_A_per_m``, ``remanence_T``,
    ``source``), every field checked, Js from its B–H ``curve``."""
    tab = rec.get("hysteresis")
    if not isinstance(tab, Mapping):
        raise ParameterError(f"{where}: [hysteresis]: missing (coercivity_A_per_m, "
                             "remanence_T, source)")  # fmt: skip
    bad = sorted(set(tab) - {"coercivity_A_per_m", "remanence_T", "source"})
    if bad:
        raise ParameterError(f"{where}: [hysteresis].{bad[0]}: unknown key")
    vals = {}
    for key in ("coercivity_A_per_m", "remanence_T"):
        v = tab.get(key)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ParameterError(f"{where}: [hysteresis].{key} = {v!r}: must be a finite number")
        vals[key] = float(v)
    try:
        return Hysteresis(rec["name"], vals["coercivity_A_per_m"], vals["remanence_T"],
                          saturation_polarisation(curve), str(tab.get("source", "")))  # fmt: skip
    except ParameterError as e:
        raise ParameterError(f"{where}: {e}") from None


#: Every steel's loop, keyed by material name (the registry's steels).
HYSTERESIS: Mapping[str, Hysteresis] = MappingProxyType(
    {
        n: hysteresis_of(r, MATERIALS[n], f"{n}.toml")
        for n, r in RECORDS.items()
        if r["kind"] == "steel"
    }
)


def hysteresis(name: str) -> Hysteresis:
    """A steel's loop by name; ParameterError lists the steels that have one."""
    try:
        return HYSTERESIS[name]
    except KeyError:
        raise ParameterError(f"material = {name!r}: no hysteresis data; known: "
                             f"{', '.join(sorted(HYSTERESIS))}") from None  # fmt: skip


def steel_elements(path: MagneticPath) -> dict[str, tuple[FloatArray, str]]:
    """The flux loop's steel elements: name → (length along the flux (S,) m, steel):
    the core and the back iron axially, the poles and the drum walls (those in the zones,
    both zones) radially (``magnetics.circuit``)."""
    drums = np.where(path.drum_mask, path.drum_r1 - path.drum_r0, 0.0).sum(-1)
    return {
        "core": (path.core_len, path.core_steel),
        "drums": (drums, path.steel),
        "pole_A": (path.pole_r1[:, 0] - path.pole_r0[:, 0], path.shell_steel),
        "pole_B": (path.pole_r1[:, 1] - path.pole_r0[:, 1], path.shell_steel),
        "back_iron": (path.back_len, path.shell_steel),
    }


def coercive_mmf(lengths: Mapping[str, FloatArray], h_peak: Mapping[str, FloatArray],
                 loops: Mapping[str, Hysteresis]) -> FloatArray:  # fmt: skip
    """Σ_elements Hc(Hm)·l, A: the MMF the loop's steel holds on a branch reached from
    the peak fields ``h_peak`` (A/m) — ``lengths`` (m) and ``loops`` by element."""
    return sum(loops[k].coercivity_after(h_peak[k]) * lengths[k] for k in lengths)  # type: ignore[return-value]


def coercive_current(path: MagneticPath, peak: ArrayLike,
                     materials: Mapping[str, Magnetic] | None = None) -> FloatArray:  # fmt: skip
    """I_c (S,) A of the S designs of ``path`` after a peak current ``peak`` (S,) A: the
    falling branch is the single-valued clutch at I + I_c (module docstring). The peak
    fields are the circuit's largest flux density of each element at the peak, on the
    element's library B–H curve."""
    mats = MATERIALS if materials is None else materials
    peak = np.broadcast_to(np.abs(np.asarray(peak, dtype=float)), path.turns.shape)
    res = solve_path(path, peak[:, None], mats)
    elems = steel_elements(path)
    h_peak = {k: np.asarray(mats[steel].h_of_b(res.steel_b[k][:, 0]))
              for k, (_, steel) in elems.items()}  # fmt: skip
    loops = {k: hysteresis(steel) for k, (_, steel) in elems.items()}
    lengths = {k: length for k, (length, _) in elems.items()}
    return coercive_mmf(lengths, h_peak, loops) / path.turns


def pulse_train(peak: float, ratio: float = PULSE_RATIO, steps: int = PULSE_STEPS) -> FloatArray:
    """The demagnetising train's currents after a peak (A): peak·ratio^k, k = 1…steps."""
    if not -1.0 < ratio < 0.0:
        raise ParameterError(f"ratio = {ratio!r}: must be in (−1, 0) (reverse and shrink)")
    if steps < 1:
        raise ParameterError(f"steps = {steps!r}: must be ≥ 1")
    return peak * ratio ** np.arange(1, steps + 1)


@dataclass(frozen=True)
class Loop:
    """The clutch's yield torque against current on a loop from ±``peak`` (the cycle
    −I_p → I_p → −I_p, torque even in the flux): ``rising`` = T(|I − I_c|),
    ``falling`` = T(I + I_c) at ``current`` ≥ 0, T the single-valued yield torque."""

    peak: float  # A
    coercive_current: float  # A
    current: FloatArray  # A, 0 … peak
    rising: FloatArray  # N·m
    falling: FloatArray  # N·m

    @property
    def residual(self) -> float:
        """N·m: the falling branch at 0 A."""
        return float(self.falling[0])

    @property
    def width(self) -> FloatArray:
        """N·m: falling − rising at each current."""
        return self.falling - self.rising


def torque_loop(torque_at: Any, peak: float, coercive: float, n: int = 15) -> Loop:
    """The loop of a clutch whose single-valued yield torque is ``torque_at(currents)``
    (N·m at an array of A), after a peak ``peak`` A with coercive current ``coercive`` A,
    sampled at ``n`` currents 0…peak (module docstring, shifted-curve model)."""
    cur = np.linspace(0.0, peak, n)
    t = np.asarray(torque_at(np.concatenate([np.abs(cur - coercive), cur + coercive])))
    return Loop(peak, coercive, cur, t[:n], t[n:])
