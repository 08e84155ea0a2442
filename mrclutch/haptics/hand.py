"""The hand on the lever: coupled stability and transparency (issue 15). SI units, angular
frequencies in rad/s, frequencies in Hz where the name says so.

**Coupled model.** The 2-DOF lever of [lebel] (Fig. 4b, ``mrclutch.haptics.model``) with
the human hand/arm gripping the end effector x2, modelled as a mass–spring–damper to
ground, Z_h(s) = m_h s + b_h + k_h/s [N·s/m], the usual lumped model of a grasping limb
(as in [hogan1989], [dolan1993], [tsuji1995]). The hand's mass moves with x2; its damping and
stiffness act between x2 and ground (the body), *not* between x1 and x2 like the
transmission's b and k. With F_a = −K E(s) x2 (E = e^{−sτ} × the zero-order hold's
fundamental, as ``impedance._hold``) and the hand's voluntary force set to zero::

    m1 s² x1 = −K E x2 − b1 s x1 − (bs + k)(x1 − x2)
    (m2 + m_h) s² x2 = −(b_h s + k_h) x2 + (bs + k)(x1 − x2)

The first line gives D1 x1 = (bs + k − K E) x2, D1 = m1 s² + (b1+b) s + k; the second,
times D1, gives [((m2+m_h) s² + b_h s + k_h + bs + k) D1 − (bs + k)(bs + k − K E)] x2 = 0.
With s Num = (m2 s² + bs + k) D1 − (bs + k)² (Eq. 2's numerator, checked by expanding
Num = m2 s D1 + (bs + k)(m1 s + b1)) the coupled characteristic quasi-polynomial is::

    χ_h(s) = s Num(s) + s Z_h(s) D1(s) + K E(s)(bs + k)
           = s D1(s) [Z_p(s) + Z_h(s)] + K E(s)(bs + k)

with s Z_h D1 = (m_h s² + b_h s + k_h) D1. Hands off (m_h = b_h = k_h = 0) it is
``limits._chi`` exactly; a mass-only hand is the lever with m2 → m2 + m_h (Num is affine in
m2 through m2 s D1); b_h and k_h are no change of HapticParams (they are to ground).

**Stability** (D-subdivision, as ``limits._crossings``). P_h = s Num + s Z_h D1 has degree
4 (leading m1(m2 + m_h)) and K E (bs + k) degree 1: χ_h is retarded. At K = 0 its roots are
the zeros of s D1 (Z_p + Z_h): Z_p + Z_h is positive real (both passive), so they lie in the
closed left half-plane; with k_h > 0 none is at 0, with k_h = 0 the rigid-body root at 0
leaves with ds/dK = −1/(b1 + b_h) < 0. Roots reach the right half-plane only by crossing the
imaginary axis at jω where X(ω) = −P_h(jω)/((k + jbω) E(jω)) is real and positive (then
K_c = X); each crossing moves a conjugate pair in the direction sign Re[−E (bs+k)/χ_h'(s)].
Without delay or hold the crossing frequencies are the positive real roots of the
polynomial Im[−P_h(jω)(k − jbω)]; otherwise sign changes of Im X on ``limits``' grid (each
cell refined until the phase bound turns by at most π/16: ``limits._phase_refine_rows``,
with P_h's zeros and the pole −k/b), refined
by Illinois regula falsi [dowell-jarratt1971], up to a frequency beyond which the
increasing lower bound |lead|(ω − ω_a)⁴/(k + bω) ≤ |X(ω)| (ω_a the largest |root| of P_h,
|E| ≤ 1) exceeds the gains sought. The stable K form (0, K_lim]: K_lim is the first K_c
where the count 2 Σ sign turns positive. A hand changes only P_h, so hands off the crossings
are ``limits._crossings``' (same grid) and K_lim is ``limits.max_stable_stiffness``.
The scan runs every hand of a search at once (``mrclutch.haptics.hand_scan``: the same
grid per hand, one pass).

**Coupled-stability invariant** ([colgate-hogan1988]): if the device at K is passive
(Re Z_cl ≥ 0, ``limits.max_passive_stiffness``) then Z_cl + Z_h is positive real for every
passive hand, and the coupled loop is stable: K_lim(hand) ≥ K_passive for every hand.

**Transparency.** In free motion (K = 0) the hand moving the lever as x2 = X sin ωt feels
F = Z_p(jω) jω X (Eq. 2), of peak |Z_p(jω)| ω X; the felt damping is Re Z_p and the felt
mass Im Z_p/ω (the effective impedance of [mehling2005] at K = 0). Default motion: 10 mm at
2 Hz, a slow voluntary exploration well inside the ≤ 10 Hz band of active, controlled
human motion [kern-hatzfeld2023] (our choice of point in that band; the force is ∝ X).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from geometry.validation import ParameterError, check_int, check_nonnegative, check_positive
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.hand_scan import _chi_c, _crossings_hands, _limits_hands, _p_hands
from mrclutch.haptics.impedance import _check_K, _num_coeffs
from mrclutch.haptics.limits import _FIELDS, max_passive_stiffness

__all__ = [
    "DEFAULT_AMPLITUDE",
    "DEFAULT_FREQUENCY",
    "HAND_RANGE",
    "CoupledStability",
    "FeltImpedance",
    "Hand",
    "HandRange",
    "backdrive_force",
    "coupled_stability",
    "felt_impedance",
    "hand_figures",
    "hand_figures_at",
    "is_stable_coupled",
    "max_stable_stiffness_coupled",
]

TWO_PI = 2.0 * math.pi
DEFAULT_AMPLITUDE = 0.010  # [m] hand motion amplitude (module docstring: our choice)
DEFAULT_FREQUENCY = 2.0  # [Hz] ≤ 10 Hz voluntary band [kern-hatzfeld2023]; 2–5 Hz [brooks1990]


@dataclass(frozen=True)
class Hand:
    """A grasping hand/arm at the handle: mass m [kg] moving with x2, damping b [N·s/m] and
    stiffness k [N/m] to ground, Z_h = m s + b + k/s."""

    m: float = 0.0
    b: float = 0.0
    k: float = 0.0

    def __post_init__(self) -> None:
        check_nonnegative("m_h", self.m, " kg")
        check_nonnegative("b_h", self.b, " N·s/m")
        check_nonnegative("k_h", self.k, " N/m")


NO_HAND = Hand()


@dataclass(frozen=True)
class HandRange:
    """A box of hand impedances: [m_min, m_max] kg, [b_min, b_max] N·s/m, [k_min, k_max] N/m,
    with the sources each bound is taken from or reasoned from."""

    m_min: float
    m_max: float
    b_min: float
    b_max: float
    k_min: float
    k_max: float
    sources: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name, unit in (("m", " kg"), ("b", " N·s/m"), ("k", " N/m")):
            lo = check_nonnegative(f"{name}_min", getattr(self, f"{name}_min"), unit)
            hi = check_nonnegative(f"{name}_max", getattr(self, f"{name}_max"), unit)
            if hi < lo:
                raise ParameterError(
                    f"{name}_max = {hi:.6g}{unit}: must be >= {name}_min = {lo:.6g}"
                )

    def grid(self, n: int) -> list[Hand]:
        """n values per axis (geometric spacing where the lower bound is > 0, else linear),
        ends included: the 8 corners, and for n ≥ 3 interior points; n³ hands in all."""
        check_int("n", n, 2, 50)

        def axis(lo: float, hi: float) -> np.ndarray:
            return np.geomspace(lo, hi, n) if lo > 0 else np.linspace(lo, hi, n)

        ms = axis(self.m_min, self.m_max)
        bs = axis(self.b_min, self.b_max)
        ks = axis(self.k_min, self.k_max)
        return [Hand(float(m), float(b), float(k)) for m in ms for b in bs for k in ks]


#: Hand/arm impedance at a grasped handle, one translational direction. Anchor (verified):
#: one trial of [van-beek2015], postural arm at a haptic handle: M = 0.554 kg, B = 6.45
#: N·s/m, K = 135 N/m. The bounds around it are our assumptions, by order of magnitude:
#: m_h from a fingertip/pinch grip (≈ 0.05 kg: finger segments) to the hand and forearm
#: moving with it (≈ 1 kg); b_h 2–20 N·s/m (relaxed to co-contracted grip, factor ≈ 3 either
#: side of the anchor); k_h 20–1000 N/m (relaxed grasp to a stiffened arm; postural endpoint
#: stiffnesses are of order 10²–10³ N/m [dolan1993], [tsuji1995]; not checked against
#: their tables).
HAND_RANGE = HandRange(
    m_min=0.05,
    m_max=1.0,
    b_min=2.0,
    b_max=20.0,
    k_min=20.0,
    k_max=1000.0,
    sources=(
        "anchor: van Beek et al. 2015, Sci. Rep. 5:18004, one trial M 0.554 kg, "
        "B 6.45 N·s/m, K 135 N/m (verified)",
        "order of magnitude of k_h: Dolan, Friedman & Nagurka 1993, IEEE Trans. SMC 23(3); "
        "Tsuji et al. 1995, Biol. Cybern. 72 (values not checked)",
        "bounds m 0.05–1 kg, b 2–20 N·s/m, k 20–1000 N/m: assumptions (module docstring)",
    ),
)


# --- coupled stability -----------------------------------------------------------------


def _one(p: HapticParams) -> HapticParams:
    if p.shape:
        raise ParameterError(f"design shape = {p.shape}: need one design (scalar fields)")
    return p


def _hand_rows(hands: Any) -> np.ndarray:
    """Hands as rows (m_h, b_h, k_h): a list of Hand, or an (H, 3) array."""
    if isinstance(hands, Hand):
        hands = [hands]
    if len(hands) and isinstance(hands[0], Hand):
        return np.array([[h.m, h.b, h.k] for h in hands], dtype=float).reshape(-1, 3)
    return np.asarray(hands, dtype=float).reshape(-1, 3)


def _p_hand(p: HapticParams, h: Hand) -> np.ndarray:
    """P_h = s Num + (m_h s² + b_h s + k_h) D1, coefficients descending (degree 4)."""
    return _p_hands(p, _hand_rows(h))[0]


def _chi_h(p: HapticParams, h: Hand, K: Any, s: Any) -> Any:
    """χ_h(s) = P_h(s) + K E(s)(bs + k) (module docstring), vectorised over K and s."""
    return _chi_c(p, _p_hand(p, h), K, s)


def _crossings_h(
    p: HapticParams, h: Hand, k_stop: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Imaginary-axis crossings of χ_h: ω_c [rad/s], K_c [N/m] ascending, directions. Every
    crossing with K_c ≤ ``k_stop`` (None: up to the first, the stability limit) is found."""
    _, wc, Kc, dirs = _crossings_hands(p, _hand_rows(h), k_stop)
    return wc, Kc, dirs


def max_stable_stiffness_coupled(p: HapticParams, hand: Hand = NO_HAND) -> Any:
    """Largest K [N/m] with the loop and hand stable for every K in (0, K] (module
    docstring: first destabilising crossing of χ_h; exact for a pure delay up to the scan).
    inf if none. Vectorised designs are handled one by one, as limits.max_stable_stiffness.
    Hands off it equals ``limits.max_stable_stiffness``."""
    if p.shape:
        n = int(np.prod(p.shape))
        flat = HapticParams(
            **{f: np.ravel(np.broadcast_to(getattr(p, f), p.shape)) for f in _FIELDS}
        )
        out = [max_stable_stiffness_coupled(flat.item(i), hand) for i in range(n)]
        return np.array(out).reshape(p.shape)
    return float(_limits_hands(p, _hand_rows(hand))[0])


def is_stable_coupled(p: HapticParams, K: float, hand: Hand = NO_HAND) -> bool:
    """Whether χ_h at K has no root with Re s ≥ 0 (D-subdivision count). K = 0 with k_h = 0
    keeps the rigid-body root at 0 (marginal), reported True as ``limits.is_stable`` does."""
    K = _check_K(K)
    _one(p)
    if K == 0:
        return True
    _, Kc, dirs = _crossings_h(p, hand, k_stop=K)
    if np.any(np.isclose(Kc, K, rtol=1e-12)):
        return False
    return bool(np.sum(2 * dirs[Kc < K]) == 0)


@dataclass(frozen=True)
class CoupledStability:
    """``coupled_stability``'s verdict at K: ``stable`` for every hand checked, the
    ``worst_hand`` (smallest stability limit), ``max_stable_K`` [N/m] = that limit (the
    largest K stable for every hand checked), ``hands_off_max_stable_K`` beside it and
    ``hands_checked`` (the count)."""

    K: float
    stable: bool
    worst_hand: Hand
    max_stable_K: float
    hands_off_max_stable_K: float
    hands_checked: int


def _compass_move(worst: Hand, name: str, sgn: float, step: float, lo: float, hi: float
                  ) -> Hand | None:  # fmt: skip
    """The compass search's neighbour of ``worst`` along ``name`` (None: clipped onto it)."""
    v = getattr(worst, name)
    new = v * math.exp(sgn * step) if v > 0 else lo + 0.1 * (hi - lo)
    new = min(max(new, lo), hi)
    return None if new == v else replace(worst, **{name: new})


def coupled_stability(
    p: HapticParams, K: float, hand_range: HandRange = HAND_RANGE, n: int = 3
) -> CoupledStability:
    """Stability of one design's loop at K with every hand of ``hand_range`` on a grid of n
    values per axis (n³ hands: corners and, n ≥ 3, interior points), then a compass search
    from the worst of them inside the box (log steps halved 8 times). For each hand the
    limit is exact (first destabilising crossing of χ_h); over the box it is sampled, not
    certified (a dip of the limit between samples could be missed). Stable iff
    K ≤ the least limit. Hands off (``hands_off_max_stable_K``) is model's limit.

    The grid and the hands-off loop are one scan (``_limits_hands``); the compass search
    polls its remaining directions from the current point in one scan and takes them in
    order up to the first that improves (the rest are polled again from there): the same
    points, order and moves as polling one neighbour at a time."""
    _one(p)
    K = float(_check_K(K))
    if not isinstance(hand_range, HandRange):
        raise ParameterError(f"hand_range = {hand_range!r}: must be a HandRange")
    hands = hand_range.grid(n)
    lims = _limits_hands(p, _hand_rows([*hands, NO_HAND]))
    hands_off = float(lims[-1])
    j = int(np.argmin(lims[:-1]))
    worst, best = hands[j], float(lims[j])
    checked = len(hands)
    # compass search in log space from the worst sample, clipped to the box
    bounds = {
        "m": (hand_range.m_min, hand_range.m_max),
        "b": (hand_range.b_min, hand_range.b_max),
        "k": (hand_range.k_min, hand_range.k_max),
    }
    dirs = [(name, sgn, lo, hi) for name, (lo, hi) in bounds.items() if hi > lo
            for sgn in (-1.0, 1.0)]  # fmt: skip
    step = 0.5 * math.log(2.0)
    known: dict[Hand, float] = {}  # the limits scanned so far, by hand

    def polled(cands: list[Hand], level: int) -> list[float]:
        """The limits of ``cands``; those not yet scanned are scanned in one call with,
        ahead of need, the polls of every later step from ``worst`` (what the search asks
        next unless it moves: a search that never moves scans twice, not nine times). A
        hand's limit is its own in any scan, so the answers are those of the polls alone."""
        if any(c not in known for c in cands):
            ahead = [m for j in range(level + 1, 8) for name, sgn, lo, hi in dirs
                     if (m := _compass_move(worst, name, sgn, step * 0.5 ** (j - level),
                                            lo, hi)) is not None]  # fmt: skip
            ask = list(dict.fromkeys(h for h in (*cands, *ahead) if h not in known))
            known.update(zip(ask, map(float, _limits_hands(p, _hand_rows(ask))), strict=True))
        return [known[c] for c in cands]

    for level in range(8):
        moved = True
        while moved:
            moved = False
            i = 0
            while i < len(dirs):
                moves = [(d, _compass_move(worst, name, sgn, step, lo, hi))
                         for d, (name, sgn, lo, hi) in enumerate(dirs) if d >= i]  # fmt: skip
                cands = [(d, c) for d, c in moves if c is not None]
                if not cands:
                    break
                i = len(dirs)
                lims_c = polled([c for _, c in cands], level)
                for (d, cand), lim in zip(cands, lims_c, strict=True):
                    checked += 1
                    if lim < best * (1 - 1e-9):
                        worst, best, moved, i = cand, float(lim), True, d + 1
                        break
        step *= 0.5
    return CoupledStability(
        K=K,
        stable=bool(K <= best),
        worst_hand=worst,
        max_stable_K=float(best),
        hands_off_max_stable_K=hands_off,
        hands_checked=checked,
    )


# --- transparency ----------------------------------------------------------------------


def _check_motion(amplitude: Any, frequency: Any) -> tuple[Any, Any]:
    for name, v, unit in (("amplitude", amplitude, " m"), ("frequency", frequency, " Hz")):
        if np.ndim(v) == 0:
            check_positive(name, float(v), unit)
        else:
            a = np.asarray(v, dtype=float)
            bad = ~np.isfinite(a) | (a <= 0)
            if bad.any():
                raise ParameterError(f"{name} = {a[bad].flat[0]:.6g}{unit}: must be finite and > 0")
    return np.asarray(amplitude, dtype=float), np.asarray(frequency, dtype=float)


def _zp(p: HapticParams, w: Any) -> Any:
    s = 1j * w
    a3, a2, a1, a0 = _num_coeffs(p)
    num = ((a3 * s + a2) * s + a1) * s + a0  # Eq. 2 numerator [lebel]
    return num / ((p.m1 * s + (p.b1 + p.b)) * s + p.k)  # Eq. 2 [lebel]


def backdrive_force(
    p: HapticParams, amplitude: Any = DEFAULT_AMPLITUDE, frequency: Any = DEFAULT_FREQUENCY
) -> Any:
    """Peak force [N] felt moving the unpowered lever (K = 0) as x2 = X sin(2πf t):
    |Z_p(jω)| ω X (module docstring). ``amplitude`` X [m] > 0, ``frequency`` f [Hz] > 0;
    fields of ``p``, X and f broadcast (float when all are scalars)."""
    X, f = _check_motion(amplitude, frequency)
    w = TWO_PI * f
    out = np.abs(_zp(p, w)) * w * X  # |F| = |Z_p(jω)| |jω X|, Eq. 2 [lebel]
    return out if np.ndim(out) else float(out)


@dataclass(frozen=True)
class FeltImpedance:
    """Felt damping Re Z_p [N·s/m] and mass Im Z_p/ω [kg] at a frequency (free motion)."""

    damping: Any
    mass: Any


def felt_impedance(p: HapticParams, frequency: Any = DEFAULT_FREQUENCY) -> FeltImpedance:
    """The unpowered lever's effective damping Re Z_p and mass Im Z_p/ω at ``frequency``
    [Hz] > 0 ([mehling2005] decomposition at K = 0). Vectorised like ``backdrive_force``."""
    _, f = _check_motion(1.0, frequency)
    w = TWO_PI * f
    z = _zp(p, w)
    b, m = z.real, z.imag / w  # b_eff = Re Z, m_eff = Im Z/ω [mehling2005]
    if np.ndim(b) == 0:
        return FeltImpedance(float(b), float(m))
    return FeltImpedance(b, m)


def felt_notes(felt: FeltImpedance, frequency: float = DEFAULT_FREQUENCY) -> list[str]:
    """Why a felt mass is negative: Im Z_p < 0 is a spring's reactance −k/ω, not a mass's
    mω (k = −m ω²): the transmission's compliance before a heavily damped actuator."""
    m = float(felt.mass)
    if not m < 0:
        return []
    k = -m * (TWO_PI * frequency) ** 2
    return [f"felt mass {m:.3g} kg is negative: at {frequency:g} Hz the unpowered lever's "
            f"reactance is a spring's (Im Z_p < 0: the transmission's compliance before the "
            f"damped actuator), felt as about {k:.3g} N/m, not as a mass"]  # fmt: skip


# --- figures of one design -----------------------------------------------------------


def hand_figures(
    p: HapticParams, K: float | None = None, hand_range: HandRange = HAND_RANGE, n: int = 3
) -> dict[str, Any]:
    """One design's hand figures at K (default its K_max, Eq. 4): coupled stability over
    ``hand_range``, the hands-off and passive limits ([colgate-hogan1988]: the passive one
    bounds the coupled one from below), and the backdrive force and felt impedance at the
    default motion. For the paper preset, pass ``pipeline.evaluate(...).mr`` (docs/hand.md)."""
    _one(p)
    K = float(p.k_max) if K is None else float(_check_K(K))
    cs = coupled_stability(p, K, hand_range, n)
    felt = felt_impedance(p)
    return {
        "K_N_per_m": K,
        "coupled_stable": cs.stable,
        "max_stable_K_all_hands_N_per_m": cs.max_stable_K,
        "worst_hand": {
            "m_kg": cs.worst_hand.m,
            "b_N_s_per_m": cs.worst_hand.b,
            "k_N_per_m": cs.worst_hand.k,
        },
        "hands_checked": cs.hands_checked,
        "max_stable_K_hands_off_N_per_m": cs.hands_off_max_stable_K,
        "max_passive_K_N_per_m": float(max_passive_stiffness(p)),
        "backdrive_force_N": backdrive_force(p),
        "felt_damping_N_s_per_m": felt.damping,
        "felt_mass_kg": felt.mass,
        "motion": {"amplitude_m": DEFAULT_AMPLITUDE, "frequency_hz": DEFAULT_FREQUENCY},
        "notes": felt_notes(felt),
    }


def hand_figures_at(fig: Mapping[str, Any], K: float) -> dict[str, Any]:
    """``fig`` (``hand_figures`` of one design) at another K [N/m]: only ``K_N_per_m`` and
    ``coupled_stable`` depend on K; the search over the hands, the limits and the
    transparency do not, so the verdict is taken again against the same least limit
    (``coupled_stability``: stable iff K ≤ it)."""
    K = float(_check_K(K))
    return {**fig, "K_N_per_m": K,
            "coupled_stable": bool(K <= fig["max_stable_K_all_hands_N_per_m"])}  # fmt: skip
