"""Reading the torque from the reluctance network's loop fluxes (``magnetics.network.solve``):
each film's yield torque over its walls' overlap and its fringes, and the batches built on it.

Yield torque of a sheared cylindrical interface of mid-radius r: T = 2π r² ∫ τy(H(z)) dz
(Bingham plastic at yield, [carlson-jolly2000] eq. 1); how a film reads its field across its
thickness is the convention (``CONVENTIONS``, docs/magnetics.md).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.params import broadcast_fields, valid
from geometry.regions import Regions, per_topology
from geometry.validation import ParameterError, check_choice
from magnetics.fluid import _CARLSON_K, _S_LO, _S_N, _S_STEP, MRFluid, _carlson_s_table
from magnetics.materials import FLUIDS, MATERIALS, Magnetic, magnetic
from magnetics.network.build import Network, network_from_regions
from magnetics.network.compiled import _loaded, load, numba_module, uncompiled
from magnetics.network.kernels import _tables
from magnetics.network.solve import _solve_packed, prepare, solve_network

FloatArray = NDArray[np.float64]
#: How a gap's torque reads its field across the gap's thickness (``network_film_torque``,
#: ``magnetics.torque._gap_torque``, ``FEMSolution.gap_yield_torque``): "mid-line",
#: r²·τy(H) at the gap's mid radius; "weakest-layer", min over r in [r0, r1] of
#: r²·τy(H(r)) (the fluid yields first there).
CONVENTIONS = ("mid-line", "weakest-layer")
DEFAULT_CONVENTION = "mid-line"


def network_yield_at(net: Network, materials: Mapping[str, Magnetic] | None = None,
                     fluid: MRFluid | None = None, convention: str = DEFAULT_CONVENTION,
                     seed: tuple[FloatArray, FloatArray] | None = None) -> YieldAt:  # fmt: skip
    """The yield torque (S,) of the network's S designs, each at its own current (S,) A, the
    solve to ``rtol`` (``at(current, rtol=1e-10)``): ``continuous_torque``'s ``torque_at``.
    Each call's Newton starts from the last call's loop fluxes scaled to the new current
    (``seed``: (current (S,), loop fluxes (S, 1, ·)) of a solve already done, e.g. at the
    peak), which roughly halves its steps on the chords' nearby currents; a call with
    ``gain`` starts afresh, from the linear start scaled by it (``solve_network``: the
    sweep's peak, whose loop fluxes ``at.flux`` then hands to the error bound). The network
    is packed for the kernel and its films' reading set up once for all calls (``prepare``,
    ``film_reader``): the same numbers as ``network_torque_and_flux`` at each call."""
    return YieldAt(net, MATERIALS if materials is None else materials, fluid, convention, seed)


class YieldAt:
    """``network_yield_at``'s callable: the network packed and its reading set up once."""

    def __init__(self, net: Network, mats: Mapping[str, Magnetic], fluid: MRFluid | None,
                 convention: str, seed: tuple[FloatArray, FloatArray] | None) -> None:  # fmt: skip
        self._net, self._mats, self._fluid, self._convention = net, mats, fluid, convention
        self._state = {} if seed is None else {"i": np.asarray(seed[0], dtype=float)[:, None],
                                               "x": np.asarray(seed[1], dtype=float)}  # fmt: skip
        self._packed = prepare(net, mats) if net.turns.size else None
        self._reading = film_reader(net, mats, fluid, convention)

    @property
    def flux(self) -> FloatArray:
        """The loop fluxes (S, 1, ``Network.unknowns``) of the last call (or the seed's)."""
        return self._state["x"]

    def __call__(self, current: ArrayLike, rtol: float = 1e-10,
                 gain: ArrayLike | None = None, rows: NDArray[np.bool_] | None = None
                 ) -> FloatArray:  # fmt: skip
        """The yield torque (S,) at ``current`` (S,); ``rows`` (a mask of the S designs):
        only those designs solved, ``current`` and the answer theirs (R,), each row's
        Newton and reading the same as in a call on all S."""
        if rows is not None:  # a network of those rows alone, started from their last state
            seed = (self._state["i"][rows, 0], self.flux[rows])
            sub = YieldAt(_network_rows(self._net, rows), self._mats, self._fluid,
                          self._convention, seed)  # fmt: skip
            t = sub(current, rtol, gain)
            self._state = {"i": self._state["i"].copy(), "x": self.flux.copy()}
            self._state["i"][rows], self._state["x"][rows] = sub._state["i"], sub.flux
            return t
        net, state = self._net, self._state
        cur = np.asarray(current, dtype=float)[:, None]
        start = None
        if state and gain is None:
            ratio = np.where(state["i"] != 0, cur / np.where(state["i"] != 0, state["i"], 1), 0)
            start = state["x"] * ratio[..., None]
        x = _solve_packed(net, net.turns[:, None] * cur, self._packed, self._mats, rtol,
                          start=start, gain=gain)  # fmt: skip
        state.update(i=cur, x=x)
        return self._reading(x).sum(-1)[:, 0]


#: The continuous rating on the network's curve (``slope_rating``): its solves' tolerance
#: (the rating is a model's to ~1e-3, not the solve's), the current of its slope at I → 0
#: (× I_a: B there lies in the B–H tables' first, linear segment, and τy = τmax·tanh(k·H)
#: is linear to (k·H)²/3), and how far (× I₁) the model's fixed point may lie from its
#: solved point before that row is solved again there (benchmarks/bench_chords.py: at 3e-3
#: the rating is nearer the exact fixed point than the three chords were on every drum
#: count, max and 99th percentile; at 1e-2 fewer rows are solved again, but 4-drum rows'
#: 99th percentile of the torque's error was 1.1e-5 against the chords' 2.6e-6).
_SLOPE_RTOL, _SLOPE_TINY, _SLOPE_MOVED = 1e-6, 1e-6, 3e-3


def slope_rating(
    torque_at: Callable[..., FloatArray], i_a: FloatArray, fixed_point: Callable[..., FloatArray]
) -> tuple[FloatArray, FloatArray]:
    """(current (S,), yield torque (S,) there) at the fixed point of the continuous rating
    (``magnetics.torque.continuous_torque``) on the network's curve T = ``torque_at``
    (``network_yield_at``'s; ``rows=`` solves a subset), ``fixed_point(T, rtol, rows)`` the
    rating's root on [0, I_a] of a model T(I) (S,) of the curve.

    The model is the slope s(I) = T(I)/I, a line in I through two solved points
    (secant on the slope, [numerical-recipes] §9.2): s₀ at I → 0 (the linear network's,
    ``_SLOPE_TINY``) and s₁ at the fixed point I₁ of the chord s₀·I; the model's fixed
    point I₂, where the model's torque is the answer; a row whose I₂ lies more than
    ``_SLOPE_MOVED``·I₁ from I₁ is solved at I₂ and its line taken through s₁ and s₂
    instead (most rows of 1–2 drums, fewer of 3–4, where the slip heat moves I less). Two
    solves of every row and a third of the moved ones, where three chords solved three;
    against the exact fixed point on 2000 random designs: benchmarks/bench_chords.py."""

    def slope(t: FloatArray, i: FloatArray) -> FloatArray:
        return np.where(i > 0, t / np.where(i > 0, i, 1.0), 0.0)

    def line(a: FloatArray, b: FloatArray, node: FloatArray) -> Callable[..., FloatArray]:
        return lambda x: x * (a + b * (x - node))  # T = I·s(I), s a line through (node, a)

    tiny = _SLOPE_TINY * i_a
    s0 = slope(torque_at(tiny, rtol=_SLOPE_RTOL), tiny)
    i1 = fixed_point(line(s0, np.zeros_like(s0), 0.0), 1e-4)
    s1 = slope(torque_at(i1, rtol=_SLOPE_RTOL), i1)
    model = line(s0, slope(s1 - s0, i1), 0.0)
    i2 = fixed_point(model, 1e-9)
    t = model(i2)
    moved = np.abs(i2 - i1) > _SLOPE_MOVED * i1
    if moved.any():
        s2 = s1.copy()
        s2[moved] = slope(torque_at(i2[moved], rtol=_SLOPE_RTOL, rows=moved), i2[moved])
        step = np.where(moved, i2 - i1, 1.0)
        model = line(s2, np.where(moved, (s2 - s1) / step, 0.0), np.where(moved, i2, i1))
        i3 = fixed_point(model, 1e-9, moved)
        i2, t = np.where(moved, i3, i2), np.where(moved, model(i3), t)
    return i2, np.maximum(t, 0.0)


def _network_rows(net: Network, rows: NDArray[np.bool_]) -> Network:
    """The network of the designs ``rows`` (a mask of its S) alone."""
    arrays = {f.name: getattr(net, f.name)[rows] for f in dataclasses.fields(net)
              if isinstance(getattr(net, f.name), np.ndarray)}  # fmt: skip
    return dataclasses.replace(net, **arrays)


def network_gap_torque(
    net: Network,
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    convention: str = DEFAULT_CONVENTION,
) -> FloatArray:
    """Yield torque (S, C, 2m) of every film in zone A then B at currents (S, C) A
    (``network_torque_and_flux`` without the loop fluxes)."""
    return network_torque_and_flux(net, currents, materials, fluid, convention)[0]


def network_torque_and_flux(
    net: Network,
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    convention: str = DEFAULT_CONVENTION,
    start: FloatArray | None = None,
    gain: ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray]:
    """(yield torque (S, C, 2m) of every film in zone A then B, the loop fluxes
    (S, C, ``Network.unknowns``)) at currents (S, C) A, the Newton started at ``start`` if given
    (``gain``: the linear start's scale, ``solve_network``).

    The film's flux x_k spreads over its walls' overlap L plus the fringing length
    (``Network.gap_eff``): over the overlap B = x_k·(L/L_eff)/(2π r L), and past each end,
    at a distance s into the fluid the film still holds (``Network.fringe_h``), the
    fringing tube carries the film's MMF H_e·g, and leaves H(s) = H_e·g/(g + cπs) in the
    film: the network's flush-edge tubes ([roters1941] ch. 5), whose legs round the walls'
    ends run through the laminate beside the film (c, ``Network.fringe_c``). The fringe's
    share, 2π r²·∫0^h τy(H(s)) ds, is (g/cπ)·∫0^W e^w·τy(H_e e^−w) dw in
    w = ln(1 + cπs/g), W = ln(1 + cπh/g): Carlson's law in closed form
    (``MRFluid.tau_y_decay``).
    The torque reads H_r, as the FEM's does (``magnetics.fem.post``), and the fluid is one
    isotropic material whose permeability is set by |B|: where the film's fluid also
    carries the axial flux beside the walls (its sheaths, ``Network.sheath_k``; B_z rising
    linearly along the zone to the band, ``_film_axial_b``), H_r = B_r·H(|B|)/|B| is the
    larger for the same B_r (Gauss–Legendre along the zone, ``_AXIAL_POINTS``; at the
    band's end of the overlap the fringe starts from that H_r). The network's own film
    element keeps H(B_r): the reading is the torque's only (docs/magnetics.md, "The fluid's
    axial flux").
    ``convention``: "mid-line" reads the field at the film's mid radius (B_z the mean of
    its two halves'); "weakest-layer" takes the lesser of r²·τy at the inner and the outer
    wall (B ∝ 1/r across the film: for MRF-132DG the inner wall, ``_gap_torque``; B_z of
    the half beside each wall)."""
    mats = MATERIALS if materials is None else materials
    check_choice("convention", convention, CONVENTIONS)
    fl = FLUIDS[net.fluid] if fluid is None else fluid
    cur = np.asarray(currents, dtype=float)
    cur = np.broadcast_to(cur if cur.ndim == 2 else cur.reshape(1, -1),
                          (net.turns.size, cur.shape[-1] if cur.ndim else 1))  # fmt: skip
    x = solve_network(net, net.turns[:, None] * cur, mats, start=start, gain=gain)
    return network_film_torque(net, x, mats, fl, convention), x


def network_film_torque(
    net: Network,
    x: FloatArray,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    convention: str = DEFAULT_CONVENTION,
) -> FloatArray:
    """Yield torque (S, C, 2m) of every film in zone A then B at the network's loop fluxes
    x (S, C, ``Network.unknowns``): the reading ``network_torque_and_flux`` describes."""
    return film_reader(net, materials, fluid, convention)(x)


def film_reader(
    net: Network,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    convention: str = DEFAULT_CONVENTION,
) -> Callable[[FloatArray], FloatArray]:
    """``network_film_torque`` of ``net`` as a function of the loop fluxes x alone: what
    does not depend on x (the films' geometry, the fringes, the tables) is set up once, for
    a network read at many currents (the continuous torque's chords)."""
    mats = MATERIALS if materials is None else materials
    check_choice("convention", convention, CONVENTIONS)
    fl = FLUIDS[net.fluid] if fluid is None else fluid
    bh = magnetic(net.fluid, mats)
    two = lambda a: np.concatenate([a[:, :, 0], a[:, :, 1]], axis=1)  # noqa: E731  zone A, B
    length, eff, depth = two(net.gap_len), two(net.gap_eff), two(net.fringe_h)  # (S, K[, 2])
    c = two(net.fringe_c)  # (S, K, 2)
    r0, r1 = np.tile(net.gap_r0, 2), np.tile(net.gap_r1, 2)
    ok = length > 0
    eff_ok = np.where(ok, eff, 1.0)[:, None, :]
    w_end = np.log1p(c * np.pi * depth / np.where(ok, r1 - r0, 1.0)[..., None])  # (S, K, 2)
    scale = (r1 - r0)[..., None] / (np.pi * c)  # ds = (g/cπ)·e^w dw, (S, K, 2 ends)
    t, tw = np.polynomial.legendre.leggauss(_AXIAL_POINTS)
    t, tw = 0.5 * (t + 1.0), 0.5 * tw  # along the zone, far end (0) to band (1)
    band_end = np.zeros((2 * net.m, 2))  # which end of each overlap faces the band
    band_end[: net.m, 1] = band_end[net.m :, 0] = 1.0

    tab, inv, nseg = _tables(magnetic(net.steel, mats), bh)
    q_inf, s_at, d_at = _carlson_s_table()
    law = (fl.tau_y_max, _CARLSON_K, q_inf, s_at, d_at, _S_LO, _S_STEP, float(_S_N))
    if type(fl).tau_y is not MRFluid.tau_y or type(fl).tau_y_decay is not MRFluid.tau_y_decay:
        raise ParameterError(f"fluid {fl.name!r}: the network's torque reads Carlson's law only")
    length = np.ascontiguousarray(length, dtype=float)
    mid = np.ascontiguousarray(0.5 * (r0 + r1))
    r0, r1 = np.ascontiguousarray(r0), np.ascontiguousarray(r1)
    w_end, scale = np.ascontiguousarray(w_end), np.ascontiguousarray(scale)  # one overload

    def reading(x: FloatArray) -> FloatArray:
        xl, xe = x[..., : net.m], x[..., net.leaks]
        zones = np.abs(np.concatenate([xl - xe[..., :1], xl - xe[..., 1:]], axis=-1))  # A, B
        phi = np.ascontiguousarray(zones / eff_ok)  # Φ per metre of L_eff
        # The film's fluid also carries the axial flux beside the walls (the sheaths): at
        # the band's end of the zone B_z = q/A of the sheath that holds it (the inner half
        # of film k beside wall k, the outer half beside wall k + 1; none beside the pole),
        # falling linearly to 0 at the zone's far end as the sheath's flux builds up.
        bz_in, bz_out = _film_axial_b(net, x)  # (S, C, K)
        read = _reader(phi.size)

        def per_length(r: FloatArray, b_z: FloatArray) -> FloatArray:
            """r²·(τy over the overlap · L + ∫ τy over both fringes) at radius r (S, K),
            B_z at the zone's band end ``b_z`` (S, C, K) (``_read_rows``)."""
            out = np.zeros(phi.shape)
            read(phi, np.ascontiguousarray(b_z), r, length, w_end, scale, band_end, t, tw,
                 tab, inv, nseg, *law, out)  # fmt: skip
            return out

        if convention == "mid-line":
            tau = per_length(mid, 0.5 * (bz_in + bz_out))
        else:
            tau = np.minimum(per_length(r0, bz_in), per_length(r1, bz_out))
        return np.where(ok[:, None, :], 2 * np.pi * tau, 0.0)

    return reading


def _read_rows(phi, bz, r, length, w_end, scale, band_end, gt, gw, tab, inv, nseg, tau_max,
               kc, q_inf, s_at, d_at, s_lo, s_step, s_n, out):  # type: ignore[no-untyped-def]  # fmt: skip
    """``network_film_torque``'s kernel (compiled by ``_reader``): out (S, C, K) = r²·(L·Σ_j
    w_j·τy(H_r(B_r, t_j·B_z)) + Σ_ends (g/cπ)·``tau_y_decay``(H_r at the end, W)) for the
    films with an overlap (L > 0), B_r = Φ/(2πr); H_r = B_r·H(|B|)/|B| on the fluid's
    table (``kernels._tables``, row 1); τy Carlson's, τ_max·tanh(k·|H|), and its decay's closed
    form ``MRFluid.tau_y_decay`` with S(v) from ``materials._carlson_s``'s table."""
    top = nseg[1] - 1
    for s in range(phi.shape[0]):
        for k in range(phi.shape[2]):
            if length[s, k] <= 0:
                continue
            rr = r[s, k]
            for c in range(phi.shape[1]):
                b_r = phi[s, c, k] / (2 * math.pi * rr)
                over, fringe = 0.0, 0.0
                for j in range(gt.size + 2):
                    b_z = bz[s, c, k] * (gt[j] if j < gt.size else band_end[k, j - gt.size])
                    # |B| by its squares: a quarter of the reading's time less than
                    # math.hypot, equal to 1e-15 (they overflow only past 1e154 T,
                    # where H_r below already does)
                    b = max(math.sqrt(b_r * b_r + b_z * b_z), 1e-300)
                    i = int(min(b * inv[1], top))
                    h = b_r * (tab[1, i, 1] + tab[1, i, 0] * b) / b  # H_r
                    a = kc * abs(h)
                    if j < gt.size:
                        over += gw[j] * (tau_max * math.tanh(a))
                        continue
                    # the fringe at this end: τ_max·[e^W·S(ln a − W) − S(ln a)]
                    e = j - gt.size
                    w = w_end[s, k, e]
                    if w == 0.0:  # no fringe: e^0·S(v) − S(v) = 0 exactly
                        continue
                    a = min(a, 1e200)
                    v = math.log(max(a, 1e-300))
                    f = 0.0
                    for sign, u in ((1.0, v - w), (-1.0, v)):
                        if u < s_lo:
                            sv = math.exp(u) * (q_inf - u)
                        else:
                            t = min(max((u - s_lo) / s_step, 0.0), s_n - 1.000001)
                            n = int(t)
                            t -= n
                            s0, s1 = s_at[n], s_at[n + 1]
                            d0, d1 = d_at[n] * s_step, d_at[n + 1] * s_step
                            sv = s0 + t * (d0 + t * (3 * (s1 - s0) - 2 * d0 - d1
                                                     + t * (2 * (s0 - s1) + d0 + d1)))  # fmt: skip
                        f += math.exp(w) * sv if sign > 0 else -sv
                    fringe += tau_max * (f if a > 0 else 0.0) * scale[s, k, e]
                out[s, c, k] = rr**2 * (over * length[s, k] + fringe)


#: Cells (design × current × film) a process reads with ``_read_rows``'s own Python before
#: it loads the compiled reader (``compiled.uncompiled``; a cell ≈ 40 µs in Python).
_PY_CELLS = 20_000


def _reader(cells: int = _PY_CELLS + 1):  # type: ignore[no-untyped-def]
    """``_read_rows`` to read ``cells`` cells with: its own Python while
    ``compiled.uncompiled`` allows, else compiled (numba, cached on disk as the solve's
    kernels, ``compiled.load``: compiled or loaded once a process by a call on no design)."""
    if uncompiled("reader", cells, _PY_CELLS):
        return _read_rows
    read = _compiled_reader()
    _loaded.add("reader")  # compiled from now on
    return read


@functools.cache
def _compiled_reader():  # type: ignore[no-untyped-def]
    read = numba_module().njit(cache=True, error_model="numpy")(_read_rows)
    return load(read, _READ_SIGNATURE, "the network's torque reading")


#: ``_read_rows``' one signature (``compiled.load``): its arrays C-contiguous, as ``film_reader``
#: passes them.
_READ_SIGNATURE = ("void(float64[:, :, ::1], float64[:, :, ::1], float64[:, ::1], float64[:, ::1], "
                   "float64[:, :, ::1], float64[:, :, ::1], float64[:, ::1], float64[::1], "
                   "float64[::1], float64[:, :, ::1], float64[::1], int64[::1], float64, float64, "
                   "float64, float64[::1], float64[::1], float64, float64, float64, "
                   "float64[:, :, ::1])")  # fmt: skip


_AXIAL_POINTS = 4  # Gauss–Legendre points along the zone, where the film's B_z builds up


def _film_axial_b(net: Network, x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """|B_z| (S, C, 2m; zone A's films then B's) at the band's end of each zone in the
    inner and the outer half of each film: the sheath fluxes ``x[..., net.sheaths]`` over
    their areas (``Network.sheath_k``), wall k's for film k's inner half, wall k + 1's for
    its outer half (0 for the outer film's outer half, beside the pole)."""
    m = net.m
    q = np.abs(x[..., net.sheaths][..., : 2 * m]).reshape(*x.shape[:-1], m, 2)
    wall = q * net.sheath_k[:, None, :, :, 0]  # (S, C, m walls, 2 zones)
    outer = np.concatenate([wall[:, :, 1:], np.zeros_like(wall[:, :, :1])], axis=2)
    two = lambda a: np.concatenate([a[..., 0], a[..., 1]], axis=-1)  # noqa: E731
    return two(wall), two(outer)


def network_torque_batch(
    fields: Mapping[str, ArrayLike],
    currents: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    fluid: MRFluid | None = None,
    convention: str = DEFAULT_CONVENTION,
) -> FloatArray:
    """Yield torque (S, C) of S designs at every one of C currents by the network, one
    batch per drum count; NaN rows for designs that fail DrumClutch's validation."""
    p = broadcast_fields(fields)
    cur = np.atleast_1d(np.asarray(currents, dtype=float))

    def one(rg: Regions, rows: np.ndarray) -> dict[str, FloatArray]:
        net = network_from_regions(rg, materials)
        return {"t": network_gap_torque(net, cur[None, :], materials, fluid, convention).sum(-1)}

    return per_topology(p, valid(p), one)["t"]
