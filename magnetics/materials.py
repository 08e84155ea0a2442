"""Magnetic and rheological material data, each table next to its source.

Every magnetic material offers ``h_of_b(b)``, ``b_of_h(h)`` and ``dh_db(b)`` on floats or
arrays (SI: T and A/m). Non-linear materials are B–H tables interpolated with a monotone
cubic (PCHIP, [fritsch-carlson1980]) of H(B) through the origin, pre-sampled on a dense grid so
that evaluation is a vectorised ``np.interp``; beyond the last point the curve continues
with slope μ0 (the material's polarisation is saturated: dB/dH → μ0). The registry
``MATERIALS`` is keyed by the material names that ``geometry.section`` writes on its
regions; add a material by adding an entry (and a test of its table). A fluid's rheology
(``MRFluid``: τy(H), viscosity) is ``magnetics.fluid``; its record here gives its numbers.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from geometry.materials import COIL, KIND, MRF, RECORDS, STAINLESS, STEEL, check_record, register
from geometry.reading import read_toml
from geometry.validation import ParameterError, check_positive
from magnetics.fluid import MRFluid

MU0 = 4e-7 * math.pi  # vacuum permeability, H/m (pre-2019 SI value; differs by 5e-10)
FloatArray = NDArray[np.float64]
_DENSE = 4096  # samples of the PCHIP curve used by np.interp
_FAR_B = 1e6  # T: the μ0 extension point (no clutch field comes near)
#: (S, C) elements from which ``BHCurve.h_dh_sum`` works in blocks of j's, and a block's
#: elements (each of its buffers stays in cache). Measured on the sweep's calls (one run,
#: interleaved): at S = 5000, C = 1 the plain expression is as fast, at C = 2 the blocks
#: take 0.72–0.92 of its time, at C = 8 (the current's rise) 0.22–0.37.
_ROW_LOOP, _BLOCK = 8192, 65536


def _weighted_sums(
    mat: LinearMaterial | BHCurve, k: FloatArray, phi: FloatArray, w: FloatArray, wk: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``h_dh_sum`` as one expression: ``h_dh`` at B = k·Φ, weighted, summed over j."""
    h, dh = mat.h_dh(k * phi)
    h *= w
    dh *= wk
    return h.sum(0), dh.sum(0)


def pchip(x: FloatArray, y: FloatArray, xq: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Monotone piecewise-cubic Hermite interpolant through (x, y) and its derivative at xq.

    Slopes as scipy's PchipInterpolator: [fritsch-butland1984] weighted harmonic mean
    inside, the shape-preserving three-point formula at the ends ([moler2004] §3.4). Written
    in numpy so importing the materials does not import scipy (≈ 0.4 s).
    """
    hk = np.diff(x)
    mk = np.diff(y) / hk
    d = np.zeros_like(y)
    w1, w2 = 2 * hk[1:] + hk[:-1], hk[1:] + 2 * hk[:-1]
    same = (np.sign(mk[1:]) == np.sign(mk[:-1])) & (mk[1:] != 0) & (mk[:-1] != 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        harm = (w1 + w2) / (w1 / mk[:-1] + w2 / mk[1:])  # [fritsch-butland1984]
    d[1:-1] = np.where(same, harm, 0.0)
    for end, (h0, h1, m0, m1) in ((0, (hk[0], hk[1], mk[0], mk[1])),
                                  (-1, (hk[-1], hk[-2], mk[-1], mk[-2]))):  # fmt: skip
        e = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)  # three-point end slope
        if np.sign(e) != np.sign(m0):
            e = 0.0
        elif np.sign(m0) != np.sign(m1) and abs(e) > abs(3 * m0):
            e = 3 * m0
        d[end] = e
    i = np.clip(np.searchsorted(x, xq, side="right") - 1, 0, hk.size - 1)
    h, t = hk[i], (xq - x[i]) / hk[i]
    y0, y1, d0, d1 = y[i], y[i + 1], d[i], d[i + 1]
    # cubic Hermite basis on [x_i, x_i+1]
    val = (y0 * (2 * t**3 - 3 * t**2 + 1) + h * d0 * (t**3 - 2 * t**2 + t)
           + y1 * (-2 * t**3 + 3 * t**2) + h * d1 * (t**3 - t**2))  # fmt: skip
    der = (y0 * (6 * t**2 - 6 * t) + h * d0 * (3 * t**2 - 4 * t + 1)
           + y1 * (-6 * t**2 + 6 * t) + h * d1 * (3 * t**2 - 2 * t)) / h  # fmt: skip
    return val, der


@dataclass(frozen=True)
class LinearMaterial:
    """Constant relative permeability (air, copper, austenitic stainless; test materials)."""

    name: str
    mu_r: float
    source: str = ""

    def __post_init__(self) -> None:
        check_positive(f"{self.name}.mu_r", self.mu_r)

    def h_of_b(self, b: ArrayLike) -> FloatArray:
        return np.asarray(b, dtype=float) / (MU0 * self.mu_r)  # H = B/(μ0 μr)

    def b_of_h(self, h: ArrayLike) -> FloatArray:
        return np.asarray(h, dtype=float) * (MU0 * self.mu_r)

    def dh_db(self, b: ArrayLike) -> FloatArray:
        return np.full_like(np.asarray(b, dtype=float), 1.0 / (MU0 * self.mu_r))

    def h_dh(self, b: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(H, dH/dB) at B ≥ 0 (the circuit's fast path)."""
        nu = 1.0 / (MU0 * self.mu_r)
        return b * nu, np.full_like(b, nu)

    def h_dh_sum(
        self, k: FloatArray, phi: FloatArray, w: FloatArray, wk: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """``BHCurve.h_dh_sum`` as the plain weighted sums (a linear H is cheap)."""
        return _weighted_sums(self, k, phi, w, wk)

    def h_mean_dh(self, b: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(H̄, dH̄/dB) at B ≥ 0, H̄ = (1/B)·∫0^B H = B/(2μ) (``BHCurve.h_mean_dh``)."""
        nu = 0.5 / (MU0 * self.mu_r)
        return b * nu, np.full_like(b, nu)

    @property
    def mu_initial(self) -> float:
        return MU0 * self.mu_r


@dataclass(frozen=True)
class BHCurve:
    """A non-linear soft-magnetic material from a B–H table (B in T, H in A/m).

    H(B) is PCHIP through (0, 0) and the table points, monotone by construction; beyond
    the last point H grows with slope 1/μ0. Below the first point the PCHIP runs from the
    origin (initial permeability ≈ B1/H1).
    """

    name: str
    b_table: tuple[float, ...]
    h_table: tuple[float, ...]
    source: str
    # The dense tables below are built on first use (``__getattr__``), not at construction:
    # the registry's nine curves cost ~20–40 ms of every command's import, and a command
    # that reads no B–H curve (haptic, compare, inertia) never pays it (issue 40).
    _b: FloatArray = field(init=False, repr=False, compare=False)
    _h: FloatArray = field(init=False, repr=False, compare=False)
    _dhdb: FloatArray = field(init=False, repr=False, compare=False)
    _inv_step: float = field(init=False, repr=False, compare=False)
    _hu: FloatArray = field(init=False, repr=False, compare=False)
    _slope: FloatArray = field(init=False, repr=False, compare=False)
    _icpt: FloatArray = field(init=False, repr=False, compare=False)
    _gcpt: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        b = np.asarray(self.b_table, dtype=float)
        h = np.asarray(self.h_table, dtype=float)
        if b.shape != h.shape or b.size < 2:
            raise ParameterError(f"{self.name}: B and H tables need the same length ≥ 2")
        if np.any(np.diff(b) <= 0) or np.any(np.diff(h) <= 0) or b[0] <= 0 or h[0] <= 0:
            raise ParameterError(f"{self.name}: B–H table must be positive, strictly increasing")
        if np.any(np.diff(b) / np.diff(h) < MU0 * (1 - 1e-9)):
            raise ParameterError(f"{self.name}: B–H table has a slope below μ0 (unphysical)")

    def __getattr__(self, name: str) -> Any:
        """Builds the dense tables the first time one is read (only then is an attribute
        missing: once set they are plain instance attributes, so the hot paths pay no more
        than an eager build)."""
        if name not in _TABLES or name in self.__dict__:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        self._build()
        return self.__dict__[name]

    def _build(self) -> None:
        """The dense PCHIP table, its μ0 extension and the uniform-grid copy."""
        b = np.asarray(self.b_table, dtype=float)
        h = np.asarray(self.h_table, dtype=float)
        bb = np.concatenate([[0.0], b])
        hh = np.concatenate([[0.0], h])
        grid = np.linspace(0.0, b[-1], _DENSE)
        hp, dp = pchip(bb, hh, grid)  # monotone cubic of H(B) [fritsch-carlson1980]
        hs = np.maximum.accumulate(hp)
        dh = np.maximum(dp, 0.0)
        # One far point continues the curve with slope 1/μ0, so a single np.interp
        # evaluates table and extrapolation alike (exact: the extension is linear).
        object.__setattr__(self, "_b", np.append(grid, b[-1] + _FAR_B))
        object.__setattr__(self, "_h", np.append(hs, hs[-1] + _FAR_B / MU0))
        object.__setattr__(self, "_dhdb", np.append(dh, 1.0 / MU0))
        # Uniform-grid copy for O(1) lookup (the circuit's hot loop): the same nodes plus
        # one step beyond the table with slope exactly 1/μ0, so clamping the index to the
        # last segment extrapolates the μ0 extension exactly.
        step = grid[1] - grid[0]
        hu = np.append(hs, hs[-1] + step / MU0)
        object.__setattr__(self, "_inv_step", 1.0 / step)
        object.__setattr__(self, "_hu", hu)
        slope = np.diff(hu) / step
        object.__setattr__(self, "_slope", slope)
        icpt = hu[:-1] - slope * grid
        object.__setattr__(self, "_icpt", icpt)  # H = icpt + slope·B
        # ∫0^B H db on the same segments: G(B) = gcpt + icpt·B + slope·B²/2, gcpt chosen
        # so G is continuous from G(0) = 0 (trapezoids are exact on linear segments)
        g = np.concatenate([[0.0], np.cumsum(0.5 * step * (hu[:-2] + hu[1:-1]))])
        object.__setattr__(self, "_gcpt", g - icpt * grid - 0.5 * slope * grid**2)

    def h_of_b(self, b: ArrayLike) -> FloatArray:
        """H(|B|)·sign(B), A/m; slope 1/μ0 beyond the table."""
        b = np.asarray(b, dtype=float)
        h = np.interp(np.abs(b), self._b, self._h, right=np.inf)
        return h if b.size and b.min(initial=0.0) >= 0 else np.copysign(h, b)

    def dh_db(self, b: ArrayLike) -> FloatArray:
        a = np.abs(np.asarray(b, dtype=float))
        return np.where(a <= self._b[-2], np.interp(a, self._b, self._dhdb), 1.0 / MU0)

    def h_dh(self, b: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(H, dH/dB) at B ≥ 0 by direct index into the uniform table (no search).

        The same piecewise-linear H(B) as ``h_of_b``; dH/dB is its exact (segment) slope,
        so Newton on a sum of these sees a consistent derivative.
        """
        t = b * self._inv_step
        n = t.shape  # C order, as take allocates (a sum's order follows the layout)
        h, s, i = np.empty(n), np.empty(n), np.empty(n, np.intp)
        self._h_dh_into(b, t, i, h, s)
        return h, s

    def _h_dh_into(self, b: FloatArray, t: FloatArray, i: NDArray[np.intp], h: FloatArray,
                   s: FloatArray) -> None:  # fmt: skip
        """``h_dh`` into buffers: t = B/step on entry (scratch after), (h, s) = (H, dH/dB)."""
        np.minimum(t, self._slope.size - 1, out=t)
        np.copyto(i, t, casting="unsafe")  # = astype(intp): truncation
        # mode "wrap": the same element as "raise" wherever that does not raise, unbuffered
        self._slope.take(i, out=s, mode="wrap")
        self._icpt.take(i, out=h, mode="wrap")
        np.multiply(s, b, out=t)
        h += t

    def h_dh_sum(
        self, k: FloatArray, phi: FloatArray, w: FloatArray, wk: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """(Σ_j w_j·H(k_j·Φ), Σ_j wk_j·H'(k_j·Φ)) over the first axis of k, w, wk (J, S, 1)
        at Φ ≥ 0 (S, C): the circuit's element sums, ``h_dh`` at B = k·Φ weighted and added.

        Bit-identical to ``h, dh = h_dh(k·Φ); (h·w).sum(0), (dh·wk).sum(0)``: a large
        (S, C) is done a block of j's at a time in reused buffers (each stays in cache; the
        (J, S, C) temporaries of C = 8 cost ~4 ns an element a pass), added in numpy's order
        for an outer axis (j = 0, 1, …); a small one, where numpy may add pairwise (S·C = 1),
        as that expression.
        """
        shape = np.broadcast_shapes(k.shape[1:], phi.shape)
        n = k.shape[0]
        if n < 2 or math.prod(shape) < _ROW_LOOP:
            return _weighted_sums(self, k, phi, w, wk)
        rows = max(1, _BLOCK // math.prod(shape))  # j's a block: ~_BLOCK elements
        hs, ds = np.empty(shape), np.empty(shape)
        h, s, b, t = (np.empty((rows, *shape)) for _ in range(4))
        i = np.empty((rows, *shape), np.intp)
        for j0 in range(0, n, rows):
            m = min(rows, n - j0)
            bj, tj, ij, hj, sj = b[:m], t[:m], i[:m], h[:m], s[:m]
            np.multiply(k[j0 : j0 + m], phi, out=bj)
            np.multiply(bj, self._inv_step, out=tj)
            self._h_dh_into(bj, tj, ij, hj, sj)
            hj *= w[j0 : j0 + m]
            sj *= wk[j0 : j0 + m]
            for r in range(m):  # in order of j, as numpy's sum over an outer axis
                if j0 + r == 0:
                    hs[...], ds[...] = hj[0], sj[0]
                else:
                    hs += hj[r]
                    ds += sj[r]
        return hs, ds

    def h_mean_dh(self, b: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(H̄, dH̄/dB) at B ≥ 0, H̄(B) = (1/B)·∫0^B H: the mean H of a section whose flux
        density rises linearly from 0 to B along it (∫0^L H(z·B/L) dz = L·H̄(B)). Exact for
        the same piecewise-linear H(B) as ``h_dh``: H̄ = gcpt/B + icpt + slope·B/2, and
        dH̄/dB = slope/2 − gcpt/B² (gcpt = 0 on the first segment, so B = 0 is regular).
        """
        t = b * self._inv_step
        np.minimum(t, self._slope.size - 1, out=t)
        i = t.astype(np.intp)
        s = np.take(self._slope, i)
        g = np.take(self._gcpt, i)
        g /= np.maximum(b, 1e-300)
        h = np.take(self._icpt, i)
        h += g
        s *= 0.5
        h += s * b
        g /= np.maximum(b, 1e-300)
        return h, s - g

    def b_of_h(self, h: ArrayLike) -> FloatArray:
        """Inverse of ``h_of_b`` (same dense table, so the pair is consistent)."""
        h = np.asarray(h, dtype=float)
        b = np.interp(np.abs(h), self._h, self._b, right=np.inf)
        return b if h.size and h.min(initial=0.0) >= 0 else np.copysign(b, h)

    @property
    def mu_initial(self) -> float:
        """Secant permeability at the first table point, H/m."""
        return self.b_table[0] / self.h_table[0]

    def mu_r_differential(self, b: ArrayLike) -> FloatArray:
        """dB/dH / μ0 at |B| (≥ 1); ``< 100`` is what the circuit calls saturated."""
        return 1.0 / (MU0 * np.maximum(self.dh_db(b), 1e-30))


Magnetic = LinearMaterial | BHCurve
#: The tables ``BHCurve._build`` sets on first use.
_TABLES = frozenset(("_b", "_h", "_dhdb", "_inv_step", "_hu", "_slope", "_icpt", "_gcpt"))

# ---- the registry: one data file per material (geometry/data/materials, sources there) ----
_CARLSON_BH_H = np.geomspace(2e3, 4e5, 40)  # A/m: where Carlson's B(H) is tabulated


def carlson_b(phi: float, h: ArrayLike) -> FloatArray:
    """Carlson's fluid B–H, B = 1.91·φ^1.133·(1 − e^(−10.97·μ0·H)) + μ0·H [T] [carlson]."""
    h = np.asarray(h, dtype=float)
    return 1.91 * phi**1.133 * -np.expm1(-10.97 * MU0 * h) + MU0 * h  # [carlson]


def _bh_of(rec: Mapping[str, Any], where: str) -> BHCurve:
    """The B–H curve of a record's ``[bh]`` table: points ``b``, ``h`` or ``model =
    "carlson"`` (a fluid's closed form at its ``phi``)."""
    bh = rec.get("bh")
    if not isinstance(bh, Mapping):
        raise ParameterError(f"{where}: [bh]: missing (a table with b and h, or model)")
    src = str(bh.get("source", ""))
    if bh.get("model") == "carlson":
        h = _CARLSON_BH_H
        return BHCurve(rec["name"], tuple(carlson_b(float(rec["phi"]), h)), tuple(h), src)
    if "model" in bh:
        raise ParameterError(f"{where}: [bh].model = {bh['model']!r}: only 'carlson' is known")
    b, h = bh.get("b"), bh.get("h")
    for key, v in (("b", b), ("h", h)):
        if not isinstance(v, list) or not all(
            isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in v
        ):
            raise ParameterError(f"{where}: [bh].{key}: must be a list of finite numbers")
        if len(v) > MAX_BH_POINTS:
            raise ParameterError(f"{where}: [bh].{key}: {len(v)} points: at most {MAX_BH_POINTS}")
        top = BH_RANGE[key]
        if v and max(v) > top:
            raise ParameterError(f"{where}: [bh].{key}: {max(v):g}: must be <= {top:g} "
                                 f"{'T' if key == 'b' else 'A/m'}")  # fmt: skip
    try:
        return BHCurve(rec["name"], tuple(map(float, b)), tuple(map(float, h)), src)
    except ParameterError as e:
        raise ParameterError(f"{where}: [bh]: {e}") from None


#: Pa·s a fluid's off-state viscosity may take: our plausibility bound, a decade and more
#: around MRF-132DG's 0.112 Pa·s [lord-mrf132dg]; a fluid outside it is refused.
VISCOSITY_RANGE = (1e-3, 10.0)
#: The least iron volume fraction a fluid file may give: our plausibility bound (below 1 %
#: the fluid is no MR fluid; a phi of 1e-300 gave a yield torque of 0 and a division by
#: zero in the feel figures, found by benchmarks/fuzz_cli.py seed 45, input 980).
PHI_MIN = 0.01
#: °C any temperature of a material file may name (absolute zero to 1000 °C).
TEMPERATURE_RANGE = (-273.15, 1000.0)
#: Most points of a B–H table, and the largest B [T] and H [A/m] in one (our bounds: the
#: registry's steels saturate near 2.4 T and their tables end below 1e6 A/m).
MAX_BH_POINTS = 1000
BH_RANGE = {"b": 100.0, "h": 1e9}


def _fluid_of(rec: Mapping[str, Any], where: str) -> MRFluid:
    """The rheology of a fluid record (``MRFluid``), every field checked."""
    name = rec["name"]

    def num(key: str) -> float:
        v = rec.get(key)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ParameterError(f"{where}: {key} = {v!r}: must be a finite number")
        return float(v)

    phi = num("phi")
    lo_phi = PHI_MIN
    if not lo_phi <= phi < 0.64:  # random close packing of spheres bounds it
        raise ParameterError(
            f"{where}: phi = {phi:g}: the iron volume fraction must be in [{lo_phi:g}, 0.64)"
        )
    visc = num("viscosity")
    lo_v, hi_v = VISCOSITY_RANGE
    if not lo_v <= visc <= hi_v:
        raise ParameterError(f"{where}: viscosity = {visc:g} Pa·s: must be in [{lo_v:g}, "
                             f"{hi_v:g}] Pa·s")  # fmt: skip
    c = num("carrier_c")
    if not 0.1 <= c <= 10.0:  # Carlson's C is 0.95–1.16 for the carriers he lists [carlson]
        raise ParameterError(f"{where}: carrier_c = {c:g}: must be in [0.1, 10]")
    pts = rec.get("carrier_points")
    tr = rec.get("temperature_range")
    try:
        cp = tuple((float(t), float(nu)) for t, nu in pts)
        lo, hi = (float(t) for t in tr)
    except (TypeError, ValueError):
        raise ParameterError(
            f"{where}: carrier_points and temperature_range: need [[°C, m²/s], [°C, m²/s]] "
            "and [lo, hi] °C"
        ) from None
    if len(cp) != 2 or not lo < hi:
        raise ParameterError(f"{where}: carrier_points: two points; temperature_range: lo < hi")
    for key, ts in (("temperature_range", (lo, hi)), ("carrier_points", (cp[0][0], cp[1][0])),
                    ("viscosity_temperature", (num("viscosity_temperature"),))):  # fmt: skip
        t_lo, t_hi = TEMPERATURE_RANGE
        if not all(t_lo <= t <= t_hi for t in ts):
            raise ParameterError(f"{where}: {key}: {', '.join(f'{t:g}' for t in ts)} °C: must "
                                 f"be in [{t_lo:g}, {t_hi:g}] °C")  # fmt: skip
    if not all(0.0 < nu <= 1.0 for _, nu in cp):  # m²/s: above any oil's
        raise ParameterError(f"{where}: carrier_points: kinematic viscosities "
                             f"{cp[0][1]:g}, {cp[1][1]:g} m²/s: must be in (0, 1]")  # fmt: skip

    def optional(key: str) -> float | None:  # issue 41: absent in a user's file = no data
        return num(key) if key in rec else None

    try:
        return MRFluid(name, phi, num("carrier_c"), visc, str(rec.get("rheology_source", "")),
                       num("viscosity_temperature"), (cp[0], cp[1]), str(rec.get("carrier", "")),
                       (lo, hi), num("thermal_conductivity"), num("specific_heat"),
                       optional("carrier_expansion"),
                       optional("lifetime_dissipated_energy"))  # fmt: skip
    except ParameterError as e:
        raise ParameterError(f"{where}: {e}") from None


_MATERIALS: dict[str, Magnetic] = {}
_FLUIDS: dict[str, MRFluid] = {}


def _add(rec: Mapping[str, Any], where: str) -> None:
    name, kind = rec["name"], rec["kind"]
    if kind == "nonmagnetic":
        _MATERIALS[name] = LinearMaterial(name, 1.0, "non-magnetic, μr = 1")
        return
    _MATERIALS[name] = _bh_of(rec, where)
    if kind == "fluid":
        _FLUIDS[name] = _fluid_of(rec, where)


for _name, _rec in RECORDS.items():
    _add(_rec, f"{_name}.toml")

AIR = LinearMaterial("air", 1.0, "vacuum")
COIL_MATERIAL = LinearMaterial(COIL, 1.0, "copper + epoxy, μr≈1 [materials]")
_MATERIALS[COIL] = COIL_MATERIAL
_MATERIALS["air"] = AIR

#: Magnetic materials keyed by the section's material names (the whole registry).
MATERIALS: Mapping[str, Magnetic] = MappingProxyType(_MATERIALS)
#: MR fluids' rheology keyed by the section's fluid material names.
FLUIDS: Mapping[str, MRFluid] = MappingProxyType(_FLUIDS)

# The defaults every figure before the library was measured with, by their old names.
STEEL_1018 = _MATERIALS[STEEL]
MRF_132DG_BH = _MATERIALS[MRF]
STAINLESS_304 = _MATERIALS[STAINLESS]
MRF_132DG = _FLUIDS[MRF]
#: Datasheet yield stress of MRF-132DG [lord-mrf132dg] (H in A/m, τy in Pa), comparison only.
MRF_132DG_DATASHEET_TAU = tuple(zip(RECORDS[MRF]["tau_y"]["h"], RECORDS[MRF]["tau_y"]["tau"],
                                    strict=True))  # fmt: skip


def load_fluid(path: str | Path) -> str:
    """Read a user's fluid from a TOML file with the fields of a built-in fluid's data file
    (geometry/data/materials/mrf_132dg.toml), check every field (a B–H table that is not
    increasing, a viscosity ≤ 0 … end in a ParameterError naming it) and add it to the
    registry under its ``name``. Returns the name."""
    p = Path(path)
    where = p.name
    rec = read_toml(p, "fluid file")  # regular, bounded, UTF-8, nesting (geometry.reading)
    rec = {"kind": "fluid", "conductivity": 0.0, **rec}
    if rec["kind"] != "fluid":
        raise ParameterError(f"{where}: kind = {rec['kind']!r}: a fluid file must be a fluid")
    checked = check_record(rec, where)
    name = checked["name"]
    if name in _MATERIALS and name not in RECORDS:
        raise ParameterError(f"{where}: name = {name!r}: taken")
    bh, fluid = _bh_of(checked, where), _fluid_of(checked, where)  # all checks before adding
    register(checked, where)
    _MATERIALS[name], _FLUIDS[name] = bh, fluid
    return name


def magnetic(name: str, materials: Mapping[str, Magnetic] | None = None) -> Magnetic:
    """Magnetic material by section name; ParameterError lists the known ones."""
    table = MATERIALS if materials is None else materials
    try:
        return table[name]
    except KeyError:
        raise ParameterError(
            f"material = {name!r}: no magnetic data; known: {', '.join(sorted(table))}"
        ) from None


def linear_materials(steel_mu_r: float, fluid_mu_r: float) -> Mapping[str, Magnetic]:
    """The registry with every steel and fluid linear (for closed-form tests)."""
    d = dict(MATERIALS)
    for name, kind in KIND.items():
        if kind == "steel":
            d[name] = LinearMaterial(name, steel_mu_r, "linear test steel")
        elif kind == "fluid":
            d[name] = LinearMaterial(name, fluid_mu_r, "linear test fluid")
    return MappingProxyType(d)
