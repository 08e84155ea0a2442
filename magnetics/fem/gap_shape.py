"""The FEM's torque derivatives over the gap, dT/dg and d²T/dg², on grids that move with the
geometry (a shape derivative by mesh morphing), the check of ``magnetics.ripple``'s network
derivatives (issue 41, item 2).

A central difference of the FEM's torque over grids built afresh at g ± h is noise: a cell
count flips wherever an interval between region edges crosses a multiple of the element
size, and the discretisation error jumps with it (on the paper preset at 0.35 mm the r
lines go from 52 to 56 between g − 7 µm and g + 7 µm, and the 7 A dT/dg moves by 10 %).
Here the nominal design's grid (``build_grid`` at g) is carried to g ± h by moving every
line piecewise linearly between the region edges it lies between (each edge goes to its
moved place, ``moved_lines``): the same cells, the same topology, so the difference of
the discrete torques is the derivative of one discretisation, which converges with the
element size like the torque itself (a shape derivative by mesh perturbation). Each
design is rebuilt at g ± h as ``magnetics.ripple.gap_derivatives`` rebuilds it (the
drums re-stacked), so the two answer the same question.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from geometry.params import DrumClutch
from geometry.section import Section, build_section
from geometry.validation import ParameterError, check_positive
from magnetics.fem import solve_fem
from magnetics.fem.grid import _lines, build_grid
from magnetics.materials import FLUIDS, Magnetic

FloatArray = NDArray[np.float64]


def _knots(section: Section) -> tuple[FloatArray, FloatArray]:
    """The region edges and the air box's ends in r and z, as ``magnetics.fem.grid._lines``
    places them (every one of them is a grid line)."""
    R, z0, z1 = section.r_max, section.z_min, section.z_max
    pad = 2.0 * max(R, z1 - z0)
    r = [0.0, R + pad, *(x for g in section.regions for x in (g.r0, g.r1))]
    z = [z0 - pad, z1 + pad, *(x for g in section.regions for x in (g.z0, g.z1))]
    return np.unique(np.round(r, 12)), np.unique(np.round(z, 12))


def moved_lines(
    nominal: Section, moved: Section, size: float, mesh: str = "uniform"
) -> tuple[FloatArray, FloatArray]:
    """The grid lines of ``nominal`` at ``size``, each moved piecewise linearly from the
    region edges of ``nominal`` to those of ``moved`` (the same number of edges, in the
    same order: the same design with its dimensions changed a little)."""
    lines = _lines(nominal, size, mesh)
    out = []
    for axis, a, b, ln in zip("rz", _knots(nominal), _knots(moved), lines, strict=True):
        if a.size != b.size or np.any(np.diff(b) <= 0):
            raise ParameterError(f"moved section: its {axis} edges do not match the nominal's "
                                 f"({a.size} against {b.size}); take a smaller step")  # fmt: skip
        out.append(np.interp(ln, a, b))
    return out[0], out[1]


@dataclass(frozen=True)
class FEMGapDerivatives:
    """The FEM's yield torque and its gap derivatives at each current."""

    currents: FloatArray  # A
    torque: FloatArray  # N·m at the nominal gap
    first: FloatArray  # dT/dg, N·m/m (central difference, O(h²))
    second: FloatArray  # d²T/dg², N·m/m² (central second difference, O(h²))
    size: float  # m, element size
    step: float  # m, h


def _torques(section: Section, grid: Any, currents: FloatArray,
             materials: Mapping[str, Magnetic] | None) -> FloatArray:  # fmt: skip
    """The FEM's yield torque at each current on one grid (currents in increasing |I|,
    each Newton started from the last field)."""
    fluid = FLUIDS[section.region(f"gap{section.gaps[0].index}").material]
    out = np.empty(currents.size)
    psi = None
    for k in np.argsort(np.abs(currents), kind="stable"):
        sol = solve_fem(section, float(currents[k]), materials=materials, grid=grid, psi0=psi)
        out[k], psi = float(np.sum(sol.gap_yield_torque(fluid, materials))), sol.psi
    return out


def fem_gap_derivatives(
    clutch: DrumClutch,
    currents: Sequence[float],
    materials: Any = None,
    size: float = 0.5e-3,
    step: float = 7e-6,
    magnetic_table: Mapping[str, Magnetic] | None = None,
) -> FEMGapDerivatives:
    """T, dT/dg and d²T/dg² of the FEM's yield torque at ``currents`` (A), every film's gap
    moved by ±``step`` (m) on the nominal grid of element ``size`` (m) moved with it
    (module docstring). ``materials``: the design's MaterialChoice (None: the defaults)."""
    check_positive("size", size, " m")
    check_positive("step", step, " m")
    if step >= clutch.gap / 2:
        raise ParameterError(f"step = {step:g} m: not below half the gap ({clutch.gap:g} m)")
    cur = np.asarray(currents, dtype=float)

    def section(g: float) -> Section:
        c = replace(clutch, gap=g)
        return build_section(c) if materials is None else build_section(c, materials)

    nominal = section(clutch.gap)
    t = []
    for g in (clutch.gap - step, clutch.gap, clutch.gap + step):
        s = nominal if g == clutch.gap else section(g)
        grid = build_grid(s, size, magnetic_table, lines=moved_lines(nominal, s, size))
        t.append(_torques(s, grid, cur, magnetic_table))
    tm, t0, tp = t
    first = (tp - tm) / (2 * step)  # central difference, O(h²)
    second = (tp - 2 * t0 + tm) / step**2  # central second difference, O(h²)
    return FEMGapDerivatives(cur, t0, first, second, float(size), float(step))
