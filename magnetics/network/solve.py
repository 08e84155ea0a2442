"""Solving the reluctance network (``magnetics.network.build``'s ladder) for its loop fluxes.

Every steel and fluid element has its material's non-linear B–H (MMF = Σ w·H(k·Φ) at Gauss
points, exact for a linear material; along a zone, where the axial flux builds up linearly,
the exact mean of H over the build-up, ``BHCurve.h_mean_dh``). Unknowns: the loop fluxes x_k
(the ladder's loops), the window's x_w, the outer air's, the end leaks' e_A, e_B, and the
sheaths' q (2m + 1). The equations are the loop MMF balances — the gradient of the network's
(convex) magnetic co-energy — so the Jacobian is symmetric positive definite: each sheath
couples to its own rung only and is condensed out element by element, leaving a tridiagonal
chain with a 3 × 3 tail, bordered by the two end leaks. Damped Newton with a backtracking
line search on the residual, each step one Thomas solve and a 2 × 2 Schur complement. A row
that does not converge is refused (``NetworkConvergenceError``, the rows named), never
returned.

The kernels are ``magnetics.network.kernels`` (plain Python: the residual, its Jacobian,
the Newton step, the Newton), compiled by ``magnetics.network.compiled`` (the one compiled
kernel, its cache and the small-call budget); the network's arrays travel to them packed one
row per design (``_pack``), each material as its piecewise-linear H(B) on a uniform grid
(``_tables``: the tables ``BHCurve.h_dh`` and ``h_mean_dh`` index).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.validation import ParameterError
from magnetics.materials import MATERIALS, Magnetic, magnetic
from magnetics.network.build import Network
from magnetics.network.compiled import _entry
from magnetics.network.kernels import _pack, _tables, _workspace

FloatArray = NDArray[np.float64]


class NetworkConvergenceError(ParameterError):
    """The network's Newton did not converge for some designs (they are named)."""


_BLOCK = 2048  # designs whose currents' order of continuation is read from their median


def prepare(net: Network, mats: Mapping[str, Magnetic]) -> Any:
    """The network's arrays packed one row per design and its materials' tables, as the
    kernel reads them (``_pack``, ``_materials``)."""
    return _pack(net), _materials(net, mats)


def _materials(net: Network, mats: Mapping[str, Magnetic]):  # type: ignore[no-untyped-def]
    return _tables(magnetic(net.steel, mats), magnetic(net.fluid, mats),
                   magnetic(net.core_steel, mats), magnetic(net.shell_steel, mats))  # fmt: skip


def _median_rows(a: FloatArray) -> FloatArray:
    """``np.median(a, axis=0)`` of finite ``a``, bit for bit (the middle row of the sorted
    rows, or the two middle ones' sum halved, as np.median's mean of them), without the
    NaN check that imports numpy.ma (≈ 20 ms of a single design's answer, issue 40)."""
    s = np.sort(a, axis=0)
    h = s.shape[0] // 2
    return s[h] if s.shape[0] % 2 else (s[h - 1] + s[h]) / 2.0


def solve_network(
    net: Network,
    ampere_turns: ArrayLike,
    materials: Mapping[str, Magnetic] | None = None,
    rtol: float = 1e-10,
    max_iter: int = 60,
    start: FloatArray | None = None,
    gain: ArrayLike | None = None,
) -> FloatArray:
    """Loop fluxes (S, C, ``Network.unknowns``) (films, the window, the outer air, the end
    leaks, the sheaths) at ampere-turns (S, C).

    Damped Newton: the full step, halved until the residual's norm falls (Armijo,
    [nocedal-wright] §3.1); the Jacobian is SPD tridiagonal (co-energy Hessian). Started at
    ``start`` or by continuation in the current: the currents one after another, the
    weakest (on the median of each block of ``_BLOCK`` designs) from the linear network's
    solution (initial permeabilities), each next one from the last one's solution, so each
    (design, current) iterates only as long as it needs (a joint solve of all currents
    iterates every current until the design's slowest settles: 1.6× the Newton work,
    docs/magnetics.md); a row that does not converge from the continuation start is retried
    from the linear one. ``gain`` (broadcast to (S, C)): the linear start scaled by it, e.g.
    the magnetic circuit's saturation Φ/Φ_linear at that current (``circuit.solve_flux``:
    a saturated design's start then lies near its answer, ~40 % fewer Newton steps; retried
    unscaled if it fails to converge). Designs that do not converge are refused together."""
    mats = MATERIALS if materials is None else materials
    return _solve_packed(net, ampere_turns, None, mats, rtol, max_iter, start, gain)


def _solve_packed(net: Network, ampere_turns: ArrayLike, packed: Any, mats: Mapping[str, Magnetic],
                  rtol: float = 1e-10, max_iter: int = 60, start: FloatArray | None = None,
                  gain: ArrayLike | None = None) -> FloatArray:  # fmt: skip
    """``solve_network`` with the network's arrays packed for the kernel (``packed``: the
    ``prepare`` of ``net`` and ``mats``; None: packed here): repeated solves of one network
    (the continuous torque's chords) pack it once."""
    ni = np.atleast_2d(np.asarray(ampere_turns, dtype=float))
    # writable C arrays, always: a read-only view would be a second overload to compile
    ni = np.array(np.broadcast_to(ni, (net.turns.size, ni.shape[-1])), order="C")
    if not np.all(np.isfinite(ni)):
        raise ParameterError("current: must be finite")
    shape = (*ni.shape, net.unknowns)
    has_start = start is not None
    x0 = (np.array(np.broadcast_to(np.asarray(start, dtype=float), shape), order="C")
          if has_start else np.zeros((0, 1, 1)))  # fmt: skip
    # a writable C array, always (one overload of the kernel); empty: no gain
    gains = (np.array(np.broadcast_to(np.asarray(gain, dtype=float), ni.shape), order="C")
             if gain is not None else np.zeros((0, 1)))  # fmt: skip
    if not np.all(np.isfinite(gains)) or np.any(gains <= 0):
        raise ParameterError("gain: must be finite and > 0")
    order = np.empty(ni.shape, np.int64)
    for lo in range(0, shape[0], _BLOCK):
        blk = slice(lo, lo + _BLOCK)
        order[blk] = np.argsort(_median_rows(np.abs(ni[blk])), kind="stable")
    out = np.zeros(shape)
    ok = np.ones(shape[0], np.bool_)
    if out.size:
        (pk, off), (tab, inv, nseg) = prepare(net, mats) if packed is None else packed
        kernel = _entry("_solve_rows", out.shape[0] * out.shape[1])
        kernel(pk, off, net.m, net.shell_k.shape[1], tab, inv, nseg, ni, order, x0, has_start,
               gains, float(rtol), int(max_iter), out, ok, _workspace(net.m))  # fmt: skip
    if not ok.all():
        rows = np.flatnonzero(~ok).tolist()
        raise NetworkConvergenceError(
            f"network: no convergence in {max_iter} Newton steps for {len(rows)} design(s) "
            f"(rows {rows[:5]}…); refusing their torque"
        )
    return out


def flux_linkage(
    net: Network, ampere_turns: ArrayLike, materials: Mapping[str, Magnetic] | None = None
) -> tuple[FloatArray, FloatArray]:
    """(λ [Wb], L_inc = dλ/dI [H]) of the coil at ampere-turns (S, C).

    The coil's N·I drives the loops through the shell (loop m − 1 and the window), so the
    co-energy's derivative is λ = ∂W'/∂I = N·(x_{m−1} + x_w) (the network's loop fluxes at
    the solution). Its derivative follows from the solution's tangent: J·dx/dI = N·s with
    s the loops' source pattern, so L_inc = N²·sᵀJ⁻¹s, one more solve with the Jacobian
    at the solution (SPD, so L_inc > 0)."""
    mats = MATERIALS if materials is None else materials
    x = solve_network(net, ampere_turns, mats)
    ni = np.array(
        np.broadcast_to(np.atleast_2d(np.asarray(ampere_turns, dtype=float)), x.shape[:-1]),
        order="C",
    )
    m = net.m
    n = net.turns[:, None]
    source = np.zeros(net.unknowns)
    source[m - 1] = source[m] = 1.0
    v = np.zeros(x.shape)
    if x.size:
        pk, off = _pack(net)
        tab, inv, nseg = _materials(net, mats)
        kernel = _entry("_tangent_rows", x.shape[0] * x.shape[1])
        kernel(pk, off, m, net.shell_k.shape[1], tab, inv, nseg, x, ni, source, v, _workspace(m))
    lam = n * (x[..., m - 1] + x[..., m])
    ind = n**2 * (v[..., m - 1] + v[..., m])
    return lam, ind
