"""Actuators, the cable transmission and the 2-DOF haptic parameters they reflect to.

Reference: Lebel et al., "Performance Study of Low Inertia Magnetorheological Actuators
for Kinesthetic Haptic Devices" [lebel] (docs/references.md), Eq. 3–4, Table 1 and Table 2.

* :class:`Actuator` — rotor inertia, rotary damping, maximum torque, delay, mass (SI, at
  the actuator shaft). The catalogue :data:`ACTUATORS` holds Table 1 (max torque rule: a
  motor gets 2× rated torque, the paper's 25 % duty-cycle rule; an MR clutch its saturation
  torque). An MR actuator is an antagonistic *pair* of clutches: both output rotors move
  with the lever, one clutch pulls in each direction.
* :class:`Transmission` — pulley ratio n = r_pulley / r_actuator, lever length l, gearing
  G (multiplies n), transmission stiffness k and damping b and lever mass m2 (linear, at
  the end effector) and the workspace d that sets K_max (Eq. 4).
* :class:`HapticParams` — the 2-DOF model's linear parameters at the end effector (fields
  may be numpy arrays that broadcast, for vectorised sweeps) and :func:`reflect`.

The pulley ratio is *derived* from Table 2: the theoretical reflected masses on the 170 mm
lever (136209: 38.5 g, 118890: 3.7 g, MR pair 2×2.7 g·cm²: 1.0 g) each give n² = m1 l²/I;
:func:`pulley_ratio_from_table2` fits one n² to the three by least squares on the
relative error (n ≈ 7.31: 14 mm winding drums, r_actuator = 7 mm, r_pulley ≈ 51 mm).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from geometry.validation import (
    ParameterError,
    check_choice,
    check_nonnegative,
    check_positive,
    check_range,
)

__all__ = [
    "ACTUATORS",
    "EM_75",
    "EM_170",
    "MR_75",
    "MR_170",
    "PULLEY_RATIO",
    "TABLE2_EM_118890",
    "TABLE2_EM_136206",
    "TABLE2_EM_136209",
    "TABLE2_MR",
    "Actuator",
    "HapticParams",
    "Transmission",
    "actuator",
    "geared",
    "pulley_ratio_from_table2",
    "reflect",
    "transmission_for",
]

G_CM2 = 1e-7  # 1 g·cm² in kg·m²
LEVER_170 = 0.170  # paper §II-B: lever length, axis to load-cell centre [m]
LEVER_75 = 0.075  # paper §II-B: the short lever [m]
DEFAULT_WORKSPACE = 0.050  # [m] K_max workspace d (Eq. 4); the paper gives no value: our choice
MR_DELAY = 1e-3  # paper §IV-B: 1 ms pure delay for MR actuators

# Table 2, theoretical m1 on the 170 mm lever: (rotor inertia moving with the lever, m1).
_TABLE2_THEORETICAL: tuple[tuple[float, float], ...] = (
    (209 * G_CM2, 38.5e-3),  # Maxon 136209
    (20 * G_CM2, 3.7e-3),  # Maxon 118890
    (2 * 2.7 * G_CM2, 1.0e-3),  # MR pair, Table 1: 2.7 g·cm² per clutch
)


def pulley_ratio_from_table2() -> float:
    """n = r_pulley / r_actuator fitted to Table 2's theoretical m1 (170 mm lever), Eq. 3.

    Eq. 3: m1 = I n² / l², so each pair (I, m1) gives n² = m1 l² / I. One n² is fitted to
    the three by least squares on the *relative* error, minimising Σ (n² a_i / m_i − 1)²
    with a_i = I_i / l², whose solution is n² = Σ(a_i/m_i) / Σ(a_i/m_i)². (The absolute
    least squares would be set by the 136209 alone.) Result: n² ≈ 53.4, n ≈ 7.31.
    """
    q = np.array([i / LEVER_170**2 / m for i, m in _TABLE2_THEORETICAL])
    return math.sqrt(float(q.sum() / (q**2).sum()))


PULLEY_RATIO = pulley_ratio_from_table2()


def _check_pos_array(name: str, value: Any, unit: str, *, allow_zero: bool = False) -> Any:
    """Scalar: the geometry.validation check. Array: every element finite and > 0 (≥ 0)."""
    if np.ndim(value) == 0:
        v = value.item() if isinstance(value, np.ndarray) else value
        return check_nonnegative(name, v, unit) if allow_zero else check_positive(name, v, unit)
    a = np.asarray(value, dtype=float)
    bad = ~np.isfinite(a) | ((a < 0) if allow_zero else (a <= 0))
    if bad.any():
        first = a[bad].flat[0]
        rng = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{name} = {first:.6g}{unit}: must be finite and {rng}")
    return a


@dataclass(frozen=True)
class Actuator:
    """An actuator at its shaft, SI: inertia [kg·m²], damping [N·m·s/rad], torque [N·m].

    ``rotor_inertia`` counts every rotor that moves with the lever (both clutches of an MR
    pair). ``max_torque`` is the torque available in one direction. ``delay`` [s] is the
    pure delay between command and torque; ``mass`` [kg] the actuator's mass.
    """

    name: str
    kind: str
    rotor_inertia: float
    damping: float
    max_torque: float
    delay: float = 0.0
    mass: float = 0.0

    def __post_init__(self) -> None:
        check_choice("kind", self.kind, ("mr", "em"))
        _check_pos_array("rotor_inertia", self.rotor_inertia, " kg·m²")
        _check_pos_array("damping", self.damping, " N·m·s/rad", allow_zero=True)
        _check_pos_array("max_torque", self.max_torque, " N·m")
        check_nonnegative("delay", self.delay, " s")
        _check_pos_array("mass", self.mass, " kg", allow_zero=True)

    @classmethod
    def mr_pair(
        cls,
        clutch_inertia: float,
        clutch_damping: float,
        clutch_max_torque: float,
        clutch_mass: float,
        delay: float = MR_DELAY,
        name: str = "mr-pair",
    ) -> Actuator:
        """Antagonistic pair of MR clutches (paper §II-A): both output rotors move with the
        lever, so inertia, drag and mass double; each direction gets one clutch's torque.
        The clutch figures may be arrays (one entry per design)."""
        _check_pos_array("clutch_inertia", clutch_inertia, " kg·m²")
        _check_pos_array("clutch_damping", clutch_damping, " N·m·s/rad", allow_zero=True)
        _check_pos_array("clutch_mass", clutch_mass, " kg", allow_zero=True)
        return cls(
            name=name,
            kind="mr",
            rotor_inertia=2.0 * clutch_inertia,
            damping=2.0 * clutch_damping,
            max_torque=clutch_max_torque,
            delay=delay,
            mass=2.0 * clutch_mass,
        )


#: Lever (handle) length of a haptic device: 1 mm (a fingertip device) to 2 m (an arm
#: exoskeleton). Far outside, the reflected impedance runs the stability search out of
#: memory (``--lever-mm 1e-9`` asked for a 743 TiB frequency grid).
LEVER_RANGE = (1e-3, 2.0)
#: Gear factor on the transmission ratio: haptic gearing stays within two decades of 1
#: (the paper uses 1 and 4); ``gearing = 1e-6`` exhausted memory as the lever did.
GEARING_RANGE = (1e-2, 1e2)
#: The handle's mass m2 (kg) and the workspace (m) a transmission accepts: a gram's tenth to
#: 100 kg, a millimetre to 2 m (1e-300 g gave an overflowing characteristic polynomial).
M2_RANGE = (1e-4, 1e2)
WORKSPACE_RANGE = (1e-3, 2.0)
#: The virtual stiffness (N/m) the command line accepts: beyond any haptic device.
STIFFNESS_MAX = 1e7


@dataclass(frozen=True)
class Transmission:
    """Cable transmission and lever. Lengths [m]; k [N/m], b [N·s/m], m2 [kg] are linear
    values at the end effector (Table 2); ``workspace`` d [m] sets K_max = F_max/d (Eq. 4).
    """

    ratio: float
    lever: float
    gearing: float = 1.0
    k: float = 6000.0
    b: float = 10.0
    m2: float = 14.0e-3
    workspace: float = DEFAULT_WORKSPACE

    def __post_init__(self) -> None:
        check_positive("ratio", self.ratio)
        check_positive("lever", self.lever, " m")
        check_range("lever", self.lever, *LEVER_RANGE, " m")
        check_positive("gearing", self.gearing)
        check_range("gearing", self.gearing, *GEARING_RANGE)
        check_positive("k", self.k, " N/m")
        check_nonnegative("b", self.b, " N·s/m")
        check_positive("m2", self.m2, " kg")
        check_range("m2", self.m2, *M2_RANGE, " kg")
        check_positive("workspace", self.workspace, " m")
        check_range("workspace", self.workspace, *WORKSPACE_RANGE, " m")

    @property
    def reduction(self) -> float:
        """Rotary-to-linear factor nG/l [1/m]: x = θ l/(nG), F = T nG/l."""
        return self.ratio * self.gearing / self.lever

    def with_lever(self, lever: float) -> Transmission:
        """The same cables and pulleys on another lever: k and b are rotary stiffness and
        damping at the lever axis, so their linear values scale as (l_old/l_new)². m2 is
        kept: the tip load cell dominates the lever's end-effector mass (our assumption;
        the paper gives no m2 for the 75 mm lever)."""
        check_positive("lever", lever, " m")
        s = (self.lever / lever) ** 2
        return replace(self, lever=lever, k=self.k * s, b=self.b * s)


# Table 2 transmissions (170 mm lever): EM capstan k 6000, b 10; MR cables k 4000, b 20.
EM_170 = Transmission(ratio=PULLEY_RATIO, lever=LEVER_170, k=6000.0, b=10.0, m2=14.0e-3)
MR_170 = Transmission(ratio=PULLEY_RATIO, lever=LEVER_170, k=4000.0, b=20.0, m2=14.0e-3)
EM_75 = EM_170.with_lever(LEVER_75)
MR_75 = MR_170.with_lever(LEVER_75)


def _rotary_damping(b1_linear: float) -> float:
    """Table 2 linear b1 on the 170 mm lever → rotary damping c = b1 l²/n² (Eq. 3 form)."""
    return b1_linear * LEVER_170**2 / PULLEY_RATIO**2


def _motor(name: str, rated: float, inertia_gcm2: float, mass: float, b1: float) -> Actuator:
    # paper §IV-B: T_max = 2 × rated torque for a motor (25 % duty cycle, one-minute cycle)
    return Actuator(name, "em", inertia_gcm2 * G_CM2, _rotary_damping(b1), 2.0 * rated, 0.0, mass)


# b1 of the 136206 (not identified in the paper): Table 2 identifies b1 = 0.1 for the
# 118890 (20 g·cm²) and 1.1 for the 136209 (209 g·cm²); we interpolate linearly in rotor
# inertia: 0.1 + (119 − 20)/(209 − 20) × 1.0 = 0.624 N·s/m.
B1_136206 = 0.1 + (119.0 - 20.0) / (209.0 - 20.0) * (1.1 - 0.1)

#: Table 1 catalogue (SI). Damping from Table 2's identified b1 through the same n, l.
ACTUATORS: dict[str, Actuator] = {
    "mr-paper": Actuator.mr_pair(
        clutch_inertia=2.7 * G_CM2,
        clutch_damping=_rotary_damping(1.0) / 2.0,  # Table 2: b1 = 1.0 N·s/m for the pair
        clutch_max_torque=0.4,  # Table 1 / Fig. 2b: saturation torque ~0.4 N·m
        clutch_mass=85e-3,
        name="mr-paper",
    ),
    "maxon-118890": _motor("maxon-118890", 0.046, 20.0, 0.270, 0.1),
    "maxon-136206": _motor("maxon-136206", 0.174, 119.0, 0.850, B1_136206),
    "maxon-136209": _motor("maxon-136209", 0.35, 209.0, 1.100, 1.1),
}


def actuator(name: str) -> Actuator:
    """The catalogue actuator ``name`` (ParameterError naming the known ones otherwise)."""
    check_choice("actuator", name, tuple(ACTUATORS))
    return ACTUATORS[name]


def transmission_for(act: Actuator, lever: float = LEVER_170) -> Transmission:
    """The paper's bench transmission for this kind of actuator (EM capstan or MR cables)."""
    base = MR_170 if act.kind == "mr" else EM_170
    return base if lever == base.lever else base.with_lever(lever)


@dataclass(frozen=True)
class HapticParams:
    """Linear 2-DOF parameters at the end effector (paper Fig. 4b, Eq. 2), SI.

    m1 [kg], b1 [N·s/m]: actuator reflected mass and grounded damping; k [N/m], b [N·s/m]:
    transmission; m2 [kg]: lever; delay [s]: actuator pure delay; f_max [N]: force capacity
    per direction; workspace [m]: K_max = f_max / workspace (Eq. 4); sample_period [s]:
    controller sample-and-hold period (0 = continuous, as in the paper). Fields may be
    numpy arrays that broadcast together (vectorised sweeps).
    """

    m1: Any
    b1: Any
    k: Any
    b: Any
    m2: Any
    delay: Any = 0.0
    f_max: Any = math.inf
    workspace: Any = DEFAULT_WORKSPACE
    sample_period: Any = 0.0

    def __post_init__(self) -> None:
        for name, unit in (("m1", " kg"), ("k", " N/m"), ("m2", " kg"), ("workspace", " m")):
            object.__setattr__(self, name, _check_pos_array(name, getattr(self, name), unit))
        # b1 > 0: every real actuator drags, and the stability analysis needs it (the free
        # lever's rigid-body root leaves s = 0 at −K/b1 when K > 0).
        object.__setattr__(self, "b1", _check_pos_array("b1", self.b1, " N·s/m"))
        for name, unit in (("b", " N·s/m"), ("delay", " s"), ("sample_period", " s")):
            v = _check_pos_array(name, getattr(self, name), unit, allow_zero=True)
            object.__setattr__(self, name, v)
        fm = np.asarray(self.f_max, dtype=float)  # +inf allowed: no force limit
        bad = np.isnan(fm) | (fm <= 0)
        if bad.any():
            raise ParameterError(f"f_max = {fm[bad].flat[0]:.6g} N: must be > 0 (inf allowed)")
        object.__setattr__(self, "f_max", float(fm) if fm.ndim == 0 else fm)
        np.broadcast_shapes(*(np.shape(getattr(self, f)) for f in _FIELDS))

    @classmethod
    def _of_checked(cls, **fields: Any) -> HapticParams:
        """The fields as they are, not checked again: float64 arrays taken from fields of
        HapticParams already checked (their rows, reshapes, broadcasts), the rest at their
        defaults as ``__post_init__`` leaves them. Checking costs ~9 NumPy reductions a
        construction, and a Z-width made ~120 of these (issue 40)."""
        p = object.__new__(cls)
        for f in _FIELDS:
            object.__setattr__(p, f, fields[f] if f not in _CHECKED_DEFAULTS
                               else fields.get(f, _CHECKED_DEFAULTS[f]))  # fmt: skip
        return p

    @property
    def k_max(self) -> Any:
        """Eq. 4: the largest stiffness rendered over the workspace without saturation."""
        return self.f_max / self.workspace

    @functools.cached_property
    def shape(self) -> tuple[int, ...]:  # cached: the fields are frozen
        return np.broadcast_shapes(*(np.shape(getattr(self, f)) for f in _FIELDS))

    @classmethod
    def stack(cls, ps: Sequence[HapticParams]) -> HapticParams:
        """Single designs as one 1-D vectorised set (the inverse of :meth:`item`)."""
        return cls(**{f: np.array([float(getattr(p, f)) for p in ps]) for f in _FIELDS})

    def item(self, i: int) -> HapticParams:
        """Design ``i`` of a 1-D vectorised set, as scalars (its fields' values, checked when
        the set was made: as floats, what ``__post_init__`` leaves a scalar field)."""
        return HapticParams._of_checked(
            **{f: float(np.broadcast_to(getattr(self, f), self.shape)[i]) for f in _FIELDS}
        )


_FIELDS = ("m1", "b1", "k", "b", "m2", "delay", "f_max", "workspace", "sample_period")
#: The defaults as ``HapticParams.__post_init__`` leaves them (floats), for ``_of_checked``.
_CHECKED_DEFAULTS = {"delay": 0.0, "f_max": math.inf, "workspace": DEFAULT_WORKSPACE,
                     "sample_period": 0.0}  # fmt: skip


def reflect(act: Actuator, tr: Transmission) -> HapticParams:
    """The actuator seen at the end effector through the transmission.

    Eq. 3 (with gearing G multiplying n): m1 = I (nG)²/l²; likewise b1 = c (nG)²/l²;
    F_max = T_max nG/l and K_max = F_max/d (Eq. 4).
    """
    r = tr.reduction
    return HapticParams(
        m1=act.rotor_inertia * r**2,
        b1=act.damping * r**2,
        k=tr.k,
        b=tr.b,
        m2=tr.m2,
        delay=act.delay,
        f_max=act.max_torque * r,
        workspace=tr.workspace,
    )


def geared(p: HapticParams, gearing: float) -> HapticParams:
    """Add a gear stage G between actuator and cable: m1 and b1 × G², F_max × G (Eq. 3–4)."""
    check_positive("gearing", gearing)
    return replace(p, m1=p.m1 * gearing**2, b1=p.b1 * gearing**2, f_max=p.f_max * gearing)


def _table2(m1: float, b1: float, act: str, *, mr: bool) -> HapticParams:
    tr = MR_170 if mr else EM_170
    return HapticParams(
        m1=m1,
        b1=b1,
        k=tr.k,
        b=tr.b,
        m2=tr.m2,
        delay=MR_DELAY if mr else 0.0,
        f_max=ACTUATORS[act].max_torque * tr.reduction,
        workspace=tr.workspace,
    )


#: Table 2 identified sets (170 mm lever). F_max from Table 1 through n/l.
TABLE2_MR = _table2(1.5e-3, 1.0, "mr-paper", mr=True)
TABLE2_EM_118890 = _table2(3.7e-3, 0.1, "maxon-118890", mr=False)
TABLE2_EM_136209 = _table2(30.8e-3, 1.1, "maxon-136209", mr=False)
#: The 136206 is not identified in the paper: Table 1 inertia through Eq. 3, b1 interpolated.
TABLE2_EM_136206 = reflect(ACTUATORS["maxon-136206"], EM_170)
