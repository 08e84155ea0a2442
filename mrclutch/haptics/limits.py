"""The limits of the rendered spring on the 2-DOF lever (``mrclutch.haptics.impedance``):
the largest passive K and the largest stable K (D-subdivision), and the tests at a K.

**Passivity.** Re Z_cl(jω) = Re Z_p(jω) + K g(ω) with g = Re[E (bs+k)/(s D1)] is affine in
K and Re Z_p ≥ 0, so the passive K form the interval [0, K_p] with
K_p = inf over {g < 0} of Re Z_p/(−g) (dense log grid, then five 20× zooms on its minimum).

**Stability** (exact for a pure delay, D-subdivision). For K > 0 small, the roots of χ are
those of s Num (left half-plane) with the rigid-body root moved from 0 to ≈ −K/b1. Roots
reach the right half-plane only by crossing the imaginary axis (χ is retarded), at jω with
K E(jω) = −jω Num(jω)/(k + jbω) =: K(ω)·E — i.e. where X(ω) = −jω Num/((k+jbω)E) is real
and positive, with K_c = X. Every crossing frequency is found (polynomial roots when there
is no delay; otherwise sign changes of Im X on a grid over whose cells arg X turns by at
most π/16 (the delay's phase and each mode's, ``_phase_refine``), from below
``quiet_below`` (no crossing lies lower), refined by Illinois regula falsi, up to a
frequency beyond which the lower bound ω|Num(jω)|/|k+jbω| ≤ K(ω), increasing there,
exceeds the best K_c), with its crossing
direction sign Re(ds/dK) = Re[−E (bs+k)/χ'(s)]. The number of right-half-plane roots at K
is 2 Σ sign over crossings with K_c < K: stable iff it is 0. The largest stable K is the
first K_c where that count turns positive.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from geometry.numerics import illinois
from geometry.validation import ParameterError
from mrclutch.haptics.actuator import HapticParams
from mrclutch.haptics.impedance import TWO_PI, _check_K, _hold, _num_coeffs

#: Most frequencies one step of the crossing search may take (memory: 8 bytes each).
MAX_GRID = 2_000_000
#: Most frequencies a phase-refined grid may hold (``_phase_refine_rows``): the phase bound
#: Φ rises by ~ω_a·τ across the first grid, so this is ω_a·τ ≲ 4·10⁴ (the presets: ~10,
#: a 1 g hand behind 64 ms: 2·10³, a 10 µg lever on 10⁵ N/m behind 0.1 s: 10⁴); beyond
#: it the loop is refused (StabilitySearchError) rather than scanned for a fifth of a
#: second per call (1.2–1.6·10⁶ points a scan, 80 s an evaluate's robust search, for a
#: 0.01 gearing behind a 1 V supply's delay).
MAX_REFINED = 200_000


def max_passive_stiffness(p: HapticParams) -> Any:
    """Largest K [N/m] with Re Z_cl(jω) ≥ 0 at every ω (module docstring): inf over g < 0
    of Re Z_p/(−g), on a log grid 1e-3 Hz – 1 MHz (40 per decade) around each design's
    minimum, zoomed five times by a 41-point grid over the two neighbouring cells (each
    zoom narrows the cell 20×: 0.025 → 8e-9 decade; the minimum's value is quadratic in
    that). inf if g ≥ 0 everywhere. Vectorised over designs."""
    shape = p.shape
    m1, b1, k, b, m2, tau, T = (
        np.ravel(np.broadcast_to(np.asarray(getattr(p, f), float), shape))[:, None]
        for f in ("m1", "b1", "k", "b", "m2", "delay", "sample_period")
    )
    # p's fields as columns, checked when p was made (a check costs ~9 NumPy reductions)
    q = HapticParams._of_checked(m1=m1, b1=b1, k=k, b=b, m2=m2, delay=tau, sample_period=T)
    a3, a2, a1, a0 = _num_coeffs(q)

    def ratio(u: np.ndarray) -> np.ndarray:  # Re Z_p/(−g) where g < 0, else inf
        w = TWO_PI * 10.0**u
        s = 1j * w
        d1 = (m1 * s + (b1 + b)) * s + k  # Eq. 2 denominator
        g = (_hold(q, w, None) * (b * s + k) / (s * d1)).real
        re = ((((a3 * s + a2) * s + a1) * s + a0) / d1).real  # Re Z_p, Eq. 2
        neg = g < 0
        return np.where(neg, re / np.where(neg, -g, 1.0), np.inf)

    rows = np.arange(m1.shape[0])
    u = np.broadcast_to(np.linspace(-3.0, 6.0, 361), (rows.size, 361))
    best = np.full(rows.size, np.inf)
    zoom = np.linspace(-1.0, 1.0, 41)
    for _ in range(6):  # the full grid, then five zooms on [j−1, j+1]
        r = ratio(u)
        j = np.argmin(r, axis=1)
        best = np.minimum(best, r[rows, j])
        if not np.isfinite(best).any():
            break
        du = u[:, 1:2] - u[:, 0:1]
        u = u[rows, j][:, None] + du * zoom
    return best.reshape(shape) if shape else float(best[0])


def is_passive(p: HapticParams, K: Any) -> Any:
    """Whether the closed loop at K is passive (Re Z_cl ≥ 0 at every frequency)."""
    return _check_K(K) <= max_passive_stiffness(p) * (1.0 + 1e-9)


# --- stability (D-subdivision) -------------------------------------------------------


def _scalar(p: HapticParams) -> HapticParams:
    if p.shape:
        raise ParameterError(f"design shape = {p.shape}: need one design (scalar fields)")
    return p


def _chi(p: HapticParams, K: Any, s: Any) -> Any:
    """χ(s) = s Num(s) + K E(s)(bs + k), vectorised over K and s."""
    a3, a2, a1, a0 = _num_coeffs(p)
    num = ((a3 * s + a2) * s + a1) * s + a0
    E = np.exp(-s * p.delay)
    if p.sample_period > 0:
        E = E * (1 - np.exp(-s * p.sample_period)) / (s * p.sample_period)
    return s * num + K * E * (p.b * s + p.k)


def _scan_imaginary_axis(
    X: Callable[[Any], Any],
    w_a: float,
    tau: float,
    lower: Callable[[float], float],
    limit: float | None,
    w_lo: float | None = None,
    roots: Any = (),
) -> np.ndarray:
    """Frequencies ω > 0 [rad/s] where Im X(ω) changes sign (D-subdivision: a crossing of
    the imaginary axis where X, the gain that puts a root at jω, is real and > 0).

    Log grid below ω_a (the largest mode; from ``w_lo`` if lower), then linear chunks of
    doubling span with a step fine against both the delay's phase period π/(16τ) and the
    modes, each bracket refined by regula falsi. ``lower(ω)``: an increasing lower bound
    on |X| for ω ≥ ω_a; the scan stops once it exceeds ``limit`` (None: the smallest real
    positive X found so far, i.e. up to the first crossing) or at 10⁴ (ω_a + 1/τ).

    Every grid is then refined (``_phase_refine``) until no cell turns arg X by more than
    π/16, counting the delay (ωτ) and ``roots``, the zeros and poles of X's rational part
    (closed left half-plane): a 2.3 % log cell below ω_a turns the delay's phase by
    0.023 ω_aτ (9 rad at ω_aτ = 403) and steps over a mode whose damping is below the cell,
    so a crossing could fall between two points of the same sign."""
    step = min(w_a / 50.0, math.pi / (16.0 * tau))
    r = np.asarray(roots, dtype=complex).ravel()
    grid = _phase_refine(_start_grid(w_a, w_lo), tau, r)
    found, best = [], math.inf
    while True:
        xi = X(grid).imag
        sc = np.nonzero(np.sign(xi[:-1]) * np.sign(xi[1:]) < 0)[0]
        w = illinois(lambda _, x: X(x).imag, grid[sc], grid[sc + 1], xi[sc], xi[sc + 1], 1e-13)
        found.append(w)
        xv = X(w)
        ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
        best = min(best, float(np.min(xv.real[ok]))) if ok.any() else best
        w_end = float(grid[-1])
        if (w_end >= w_a and lower(w_end) > (best if limit is None else limit)) or (
            w_end > 1e4 * (w_a + 1 / tau)
        ):
            break
        grid = _phase_refine(_chunk_grid(w_end, step, tau), tau, r)
    return np.concatenate(found)


def _start_grid(w_a: float, w_lo: float | None) -> np.ndarray:
    """The crossing scan's first grid [rad/s] before ``_phase_refine``: 401 points log
    spaced over [10⁻⁴ ω_a, ω_a], 100 more from ``w_lo`` if lower (None or NaN: none).
    Shared with ``hand_scan`` (one grid per hand row)."""
    grid = w_a * np.logspace(-4, 0, 401)
    if w_lo is not None and w_lo < grid[0]:  # a slow mode below the grid: start lower
        grid = np.concatenate([np.geomspace(w_lo, grid[0], 101)[:-1], grid])
    return grid


def _chunk_grid(w_end: float, step: float, tau: float) -> np.ndarray:
    """The scan's next chunk [w_end, 2 w_end], ``step`` apart, before ``_phase_refine``;
    StabilitySearchError beyond MAX_GRID points. Shared with ``hand_scan``."""
    n = math.ceil(w_end / step) + 1
    if n > MAX_GRID:  # an absurd delay or stiffness: refuse rather than fill memory
        raise StabilitySearchError(
            f"stability search: delay {tau:.3g} s needs more than {MAX_GRID:.0e} "
            "frequencies per scan step; not a haptic loop"
        )
    return np.linspace(w_end, 2 * w_end, n)


#: Most turn of arg X [rad] one cell of the crossing scan may hold (``_phase_refine``).
PHASE_STEP = math.pi / 16.0


def _phase_bound(w: np.ndarray, tau: Any, roots: np.ndarray) -> np.ndarray:
    """Φ(ω) = ωτ + Σ_r atan2(ω − Im r, −Re r): increasing for Re r ≤ 0, and
    |Δ arg X| ≤ ΔΦ over any interval, arg X being ±π/2 + ωτ ± Σ_r arg(jω − r)
    (each arg(jω − r) = atan2(ω − Im r, −Re r) increasing; the sum of the terms'
    variations bounds the variation of their signed sum)."""
    turns = np.arctan2(w[..., None] - roots.imag, -roots.real)
    return w * tau + np.sum(turns, axis=-1)


def _phase_refine(grid: np.ndarray, tau: float, roots: np.ndarray) -> np.ndarray:
    """``grid`` (ascending) with each cell split evenly until Φ (``_phase_bound``) rises
    by at most PHASE_STEP over every cell, so arg X turns by at most π/16 between two
    neighbours: Im X cannot change sign twice in a cell unless arg X touches 0 or π and
    turns back within π/16 (a near-tangent pair of crossings). StabilitySearchError
    beyond MAX_REFINED points (the count is checked before a grid is built)."""
    return _phase_refine_rows(grid, np.zeros(grid.size, int), tau, roots[None, :])[0]


def _phase_refine_rows(
    grid: np.ndarray, row: np.ndarray, tau: Any, roots: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``_phase_refine`` of several grids at once (``hand_scan``: one per hand): ``grid``
    the rows' grids end to end, ``row`` each point's row (non-decreasing), ``roots``
    (rows, n) and ``tau`` (a float, or (rows,)) each row's; returns the refined (grid,
    row). MAX_REFINED bounds each row."""
    per_row = np.ndim(tau) > 0
    phi = _phase_bound(grid, tau[row] if per_row else tau, roots[row])
    for _ in range(60):  # each pass splits the cells still over the step (Φ of new points)
        same = row[1:] == row[:-1]  # cells within a row
        parts = np.where(same, np.ceil(np.diff(phi) / PHASE_STEP), 1.0)
        wide = parts > 1
        if not wide.any():
            return grid, row
        parts = np.where(wide, parts, 1.0)
        total = np.bincount(row[:-1][same], parts[same], minlength=roots.shape[0]) + 1
        if float(np.max(total)) > MAX_REFINED:  # an absurd delay or mode: refuse
            t = float(tau[np.argmax(total)]) if per_row else tau
            raise StabilitySearchError(
                f"stability search: delay {t:.3g} s and modes need more than "
                f"{MAX_REFINED:.0e} frequencies per scan step; not a haptic loop"
            )
        cells = np.nonzero(wide)[0]
        n = parts[cells].astype(int)
        # the inner points of each wide cell: lo + i (hi − lo)/n, i = 1 … n − 1
        i = np.arange(int(np.sum(n - 1))) - np.repeat(np.cumsum(n - 1) - (n - 1), n - 1) + 1
        lo, hi = np.repeat(grid[cells], n - 1), np.repeat(grid[cells + 1], n - 1)
        new = lo + i * (hi - lo) / np.repeat(n, n - 1)
        at = np.repeat(cells + 1, n - 1)
        rnew = np.repeat(row[cells], n - 1)
        finer = np.insert(grid, at, new)  # ascending: in its cell
        rfiner = np.insert(row, at, rnew)
        pfiner = np.insert(phi, at, _phase_bound(new, tau[rnew] if per_row else tau, roots[rnew]))
        # repeats at float resolution dropped (within a row)
        keep = np.concatenate([[True], (np.diff(finer) > 0) | (np.diff(rfiner) != 0)])
        finer, rfiner, pfiner = finer[keep], rfiner[keep], pfiner[keep]
        if finer.size == grid.size:  # cells at the float resolution: nothing left to split
            return grid, row
        grid, row, phi = finer, rfiner, pfiner
    return grid, row


def _poles_and_zeros(roots: np.ndarray, p: HapticParams, *extra: complex) -> np.ndarray:
    """The zeros of Num and the pole −k/b of X (where b > 0), with ``extra`` roots."""
    return np.array([*roots, *([-p.k / p.b] if p.b > 0 else []), *extra], dtype=complex)


def quiet_below(w_z: Any, tau: Any, n_zeros: int = 3) -> Any:
    """A frequency [rad/s] below which Im X < 0, so no crossing lies there: half of
    min(w_z/2, (π/2)/(4/w_z + τ)), w_z the smallest |zero| of Num (Hurwitz), τ the delay
    (plus half the hold). For ω ≤ w_z/2 each zero turns arg Num(jω) by at most (4/3)ω/w_z
    (a real one atan(ω/σ); a pair atan(2σω/(|z|² − ω²)) ≤ (8/3)ω/|z|), so arg X =
    −π/2 + arg Num(jω) + ωτ − atan(bω/k) stays in (−π, 0) while ω(4/w_z + τ) < π/2.
    The scans start no higher (a low, delay-driven crossing near √(K/(m1 + m2)) lies far
    below 10⁻⁴ ω_a where b1 is small and b/m1 large). ``n_zeros``: how many zeros (in the
    closed left half-plane, none nearer 0 than w_z) turn the phase: 4/w_z becomes
    (n_zeros/3)·4/w_z (the loop with a hand, ``hand_scan``: 4). Vectorised."""
    return 0.5 * np.minimum(0.5 * w_z, 0.5 * math.pi / ((n_zeros / 3.0) * 4.0 / w_z + tau))


def _crossings(
    p: HapticParams, k_stop: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Imaginary-axis crossings of χ for one design: frequencies ω_c [rad/s], gains K_c
    [N/m] and directions sign Re(ds/dK) (+1: into the right half-plane) — every crossing
    with K_c ≤ ``k_stop`` (None: up to the smallest K_c, the stability limit), possibly
    more. Above ω_a (the largest |root| of Num) the bound K(ω) ≥ ω|Num(jω)|/|k + jbω| is
    increasing, so the scan stops where it exceeds the gains sought."""
    a = _num_coeffs(p)
    roots = np.roots(a)
    w_a = float(np.max(np.abs(roots)))
    tau = p.delay + 0.5 * p.sample_period

    def X(w: Any) -> Any:  # K(ω)·e^{jφ}: crossing where X is real and > 0
        s = 1j * np.asarray(w, dtype=float)
        num = ((a[0] * s + a[1]) * s + a[2]) * s + a[3]
        return -s * num / ((p.b * s + p.k) * _hold(p, np.asarray(w, float), None))

    def real_positive(xv: np.ndarray) -> np.ndarray:
        return (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))

    if tau == 0.0:
        # Im[−jωNum(jω)(k − jbω)] is a polynomial in ω: its positive real roots, exactly.
        from numpy.polynomial import polynomial as P  # zero delay only (not haptic's)

        c = np.array(a[::-1], dtype=complex) * (1j ** np.arange(4))  # Num(jω) in ω
        poly = P.polymul(P.polymul([0, -1j], c), [p.k, -1j * p.b])
        rts = np.roots(poly.imag[::-1])
        wc = np.sort(rts.real[(np.abs(rts.imag) < 1e-9 * np.abs(rts)) & (rts.real > 0)])
    else:

        def lower(w: float) -> float:  # |X| ≥ ω|Num(jω)|/|k + jbω| (|E| ≤ 1), increasing
            return abs(1j * w * np.polyval(a, 1j * w)) / abs(p.k + p.b * 1j * w)

        w_z = float(np.min(np.abs(roots)))  # the slowest zero of Num
        rz = _poles_and_zeros(roots, p)
        wc = _scan_imaginary_axis(X, w_a, tau, lower, k_stop, w_lo=quiet_below(w_z, tau), roots=rz)
    xv = X(wc)
    ok = real_positive(xv)
    wc, Kc = wc[ok], xv.real[ok]
    s, h = 1j * wc, 1e-6 * wc
    dchi = (_chi(p, Kc, s + h) - _chi(p, Kc, s - h)) / (2 * h)
    dchi_dK = _chi(p, Kc + 1.0, s) - _chi(p, Kc, s)  # ∂χ/∂K = E (bs + k)
    dirs = np.sign((-dchi_dK / dchi).real)
    order = np.argsort(Kc)
    return wc[order], Kc[order], dirs[order]


class StabilitySearchError(ParameterError):
    """The stability scan would need more than MAX_GRID frequencies per step."""


def max_stable_stiffness(p: HapticParams) -> Any:
    """Largest K [N/m] such that the free closed loop is stable for every K in (0, K]:
    the first crossing gain at which the count of right-half-plane roots turns positive
    (module docstring; exact for a pure delay). inf if no crossing destabilises; NaN where
    the scan would need more than MAX_GRID frequencies a step (StabilitySearchError: an
    extreme transmission or delay), so the limit is unknown.
    Vectorised fields: every design's scan at once (``_stable_rows``), each row's value
    bit for bit the scalar call's."""
    if p.shape:
        flat = HapticParams._of_checked(  # p's fields flattened, checked when p was made
            **{f: np.ravel(np.broadcast_to(getattr(p, f), p.shape)) for f in _FIELDS}
        )
        return _stable_rows(flat).reshape(p.shape)
    try:
        _, Kc, dirs = _crossings(p)
    except StabilitySearchError:  # the scan cannot resolve this loop: the limit is unknown
        return math.nan
    count = np.cumsum(2 * dirs)
    bad = np.nonzero(count > 0)[0]
    return float(Kc[bad[0]]) if bad.size else math.inf


_FIELDS = ("m1", "b1", "k", "b", "m2", "delay", "f_max", "workspace", "sample_period")


def is_stable(p: HapticParams, K: float) -> bool:
    """Whether the free closed loop at K has no root with Re s ≥ 0 (D-subdivision count).
    K = 0 is the backdriven device: marginally stable (rigid-body root at 0), reported True.
    """
    K = _check_K(K)
    _scalar(p)
    if K == 0:
        return True
    _, Kc, dirs = _crossings(p, k_stop=K)
    if np.any(np.isclose(Kc, K, rtol=1e-12)):
        return False
    return bool(np.sum(2 * dirs[Kc < K]) == 0)


def _stable_rows(p: HapticParams) -> np.ndarray:
    """``max_stable_stiffness`` of each design of a 1-D set, the scans side by side: the
    same grids (``_start_grid``, ``_chunk_grid``, ``_phase_refine_rows``), sign changes
    within a row, one Illinois call for every bracket and each row's own stop, so each
    value is the scalar call's bit for bit (tests/mrclutch/test_robust_one_answer.py); the
    numpy calls a scan makes are shared by the rows (issue 40). Rows without a delay, with
    a sample-and-hold or without the pole −k/b, and all rows where a refined grid would
    pass MAX_REFINED, run one by one."""
    n = p.m1.size
    f = {x: np.asarray(getattr(p, x), float) for x in _FIELDS}
    out = np.full(n, np.nan)
    alone = (f["sample_period"] > 0) | (f["delay"] == 0) | (f["b"] <= 0)
    rows = np.nonzero(~alone)[0]
    if rows.size:
        try:
            out[rows] = _scan_rows(HapticParams._of_checked(**{x: f[x][rows] for x in _FIELDS}))
        except StabilitySearchError:
            alone[rows] = True
    for i in np.nonzero(alone)[0]:
        out[i] = max_stable_stiffness(p.item(int(i)))
    return out


def _scan_rows(p: HapticParams) -> np.ndarray:
    """``_stable_rows`` for designs with a pure delay τ > 0 and b > 0 (``_crossings`` and
    ``_scan_imaginary_axis`` row by row: the same operations on each row's numbers)."""
    n = p.m1.size
    a = np.stack(_num_coeffs(p), axis=1)  # (n, 4), descending
    comp = np.zeros((n, 3, 3))  # np.roots' companion matrices
    comp[:, 0, :] = -a[:, 1:] / a[:, :1]
    comp[:, 1, 0] = comp[:, 2, 1] = 1.0
    roots = np.linalg.eigvals(comp).astype(complex)
    w_a, w_z = np.max(np.abs(roots), axis=1), np.min(np.abs(roots), axis=1)
    tau, k, b = p.delay, p.k, p.b
    rz = np.concatenate([roots, (-k / b)[:, None]], axis=1)  # _poles_and_zeros
    step = np.minimum(w_a / 50.0, math.pi / (16.0 * tau))
    w_lo = quiet_below(w_z, tau)

    def X(r: np.ndarray, w: np.ndarray) -> np.ndarray:  # _crossings' X of rows r at w
        s = 1j * w
        num = ((a[r, 0] * s + a[r, 1]) * s + a[r, 2]) * s + a[r, 3]
        return -s * num / ((b[r] * s + k[r]) * np.exp(-1j * w * tau[r]))

    found: list[list[np.ndarray]] = [[] for _ in range(n)]
    best = np.full(n, math.inf)
    grids = {i: _start_grid(float(w_a[i]), float(w_lo[i])) for i in range(n)}
    while grids:
        act = np.array(sorted(grids))
        row = np.repeat(act, [grids[i].size for i in act])
        grid, row = _phase_refine_rows(np.concatenate([grids[i] for i in act]), row,
                                       tau, rz)  # fmt: skip
        xi = X(row, grid).imag
        sc = np.nonzero((np.sign(xi[:-1]) * np.sign(xi[1:]) < 0) & (row[1:] == row[:-1]))[0]
        br = row[sc]
        w = illinois(lambda q, x, br=br: X(br[q], x).imag, grid[sc], grid[sc + 1], xi[sc],
                     xi[sc + 1], 1e-13)  # fmt: skip
        xv = X(br, w)
        ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
        np.minimum.at(best, br[ok], xv.real[ok])
        ends = np.nonzero(np.append(row[1:] != row[:-1], True))[0]
        grids = {}
        for i, e in zip(act, ends, strict=True):
            found[i].append(w[br == i])
            w_end = float(grid[e])
            y = 0j  # lower(w_end): np.polyval(a, jω), then its modulus over |k + jbω|
            for c in a[i]:
                y = y * (1j * w_end) + c
            low = abs(1j * w_end * y) / abs(k[i] + b[i] * 1j * w_end)
            if (w_end >= w_a[i] and low > best[i]) or w_end > 1e4 * (w_a[i] + 1 / tau[i]):
                continue
            try:
                grids[i] = _chunk_grid(w_end, float(step[i]), float(tau[i]))
            except StabilitySearchError:  # this row's limit is unknown (scalar: NaN)
                found[i] = []
                best[i] = math.nan
    out = np.full(n, math.inf)
    for i in range(n):
        if math.isnan(best[i]):
            out[i] = math.nan
            continue
        wc = np.concatenate(found[i])
        q = p.item(i)
        xv = X(np.full(wc.size, i), wc)
        ok = (xv.real > 0) & (np.abs(xv.imag) <= 1e-6 * np.abs(xv))
        wc, Kc = wc[ok], xv.real[ok]
        s, h = 1j * wc, 1e-6 * wc
        dchi = (_chi(q, Kc, s + h) - _chi(q, Kc, s - h)) / (2 * h)
        dirs = np.sign((-(_chi(q, Kc + 1.0, s) - _chi(q, Kc, s)) / dchi).real)
        order = np.argsort(Kc)
        bad = np.nonzero(np.cumsum(2 * dirs[order]) > 0)[0]
        out[i] = float(Kc[order][bad[0]]) if bad.size else math.inf
    return out
