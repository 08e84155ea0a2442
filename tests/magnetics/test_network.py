"""The reluctance network (magnetics.network): closed forms in the linear limit, the
ladder's solve against an independent nodal solve, limits and robustness, refusal, and its
measured error against the stored FEM reference (benchmarks/data/fem_reference.json)."""

import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from geometry.params import broadcast_fields, preset
from geometry.regions import evaluate
from geometry.validation import ParameterError
from magnetics.circuit import path_from_regions, solve_flux
from magnetics.materials import FLUIDS, MATERIALS, MU0, linear_materials, magnetic
from magnetics.network import (
    NetworkConvergenceError,
    network_from_regions,
    solve_network,
)
from magnetics.network.torque import (
    _film_axial_b,
    network_film_torque,
    network_gap_torque,
    network_torque_and_flux,
    network_torque_batch,
    network_yield_at,
)
from magnetics.torque import torque_curve

PAPER = preset("paper")
ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "benchmarks"


def _regions(clutch=PAPER, **kw):  # type: ignore[no-untyped-def]
    c = replace(clutch, **kw)
    p = broadcast_fields({k: np.array([v], float) for k, v in vars(c).items()})
    return c, evaluate(p, c.n_drums)


def _single_loop(net):  # type: ignore[no-untyped-def]
    """The ladder with its rungs, window and outer air all but open (1e13 /H, ≥ 10⁵× the
    elements': they carry < 5e-5 of the flux; truly open paths make the system singular)
    and without the walls' fluid sheaths."""
    small = lambda a: np.full_like(a, 1e-13)  # noqa: E731  permeance, H
    rungs = np.where(np.arange(net.m + 1) % net.m == 0, 0.0, 1e-13)[None] + 0 * net.rung_perm
    return replace(net, rung_perm=rungs, rung_fluid=0 * net.rung_fluid,
                   sheath_w=0 * net.sheath_w, core_sheath_w=0 * net.core_sheath_w,
                   window_perm=small(net.window_perm), window_fluid=0 * net.window_fluid,
                   outer_air=np.full_like(net.outer_air, 1e13),
                   end_leak=np.full_like(net.end_leak, 1e13))  # fmt: skip


def _elements(rg, n, mu_s, mu_f):  # type: ignore[no-untyped-def]
    """The closed-form tests' elements from the geometry (linear materials): each film's
    series element per zone (its fluid radially, ln(r1/r0)/(2πμL) [roters1941] ch. 5, plus
    the drum wall inside it), each wall's axial steel in a zone (l/(2μA): the flux builds
    up linearly) and its fluid sheath beside it (half of each neighbouring film), the core
    over the band (steel, and half of film 0 beside it), and the shell (poles radially,
    back iron axially). Films: core|out1|in1|…|outN|shell; reluctances in 1/H."""
    a = {k: float(np.asarray(v).ravel()[0]) for k, v in rg.at.items()}
    ms, mf = MU0 * mu_s, MU0 * mu_f
    za, zb = a["zone_A1"] - a["zone_A0"], a["zone_B1"] - a["zone_B0"]
    band = a["zone_B0"] - a["zone_A1"]
    m = 2 * n
    area = lambda r0, r1: np.pi * (r1**2 - r0**2)  # noqa: E731
    film, wall, sheath = np.zeros((m, 2)), np.zeros((m, 2)), np.zeros((m, 2))
    half = np.zeros(m + 1)  # half of film k − 1 and k beside wall k
    for k in range(m):
        r0, r1 = a[f"rho{2 * k}"], a[f"rho{2 * k + 1}"]
        lens = (za + (a["zone_A0"] - a["hub_back"] if k == m - 1 else 0.0), zb)
        film[k] = [np.log(r1 / r0) / (2 * np.pi * mf * length) for length in lens]
        if k:  # the drum wall inside film k, radially
            w0, w1 = a[f"rho{2 * k - 1}"], a[f"rho{2 * k}"]
            film[k] += [np.log(w1 / w0) / (2 * np.pi * ms * length) for length in (za, zb)]
        half[k] += 0.5 * area(r0, r1)
        half[k + 1] += 0.5 * area(r0, r1)
    core = np.pi * a["rho0"] ** 2
    for k in range(m):
        steel = core if k == 0 else area(a[f"rho{2 * k - 1}"], a[f"rho{2 * k}"])
        wall[k] = [length / (2 * ms * steel) for length in (za, zb)]
        sheath[k] = [length / (2 * mf * half[k]) for length in (za, zb)]
    back = a["coil_out"]
    poles = ((a["cap_front"], a["zone_A1"]), (a["zone_B0"], a["cap_back"]))
    return {
        "film": film, "wall": wall, "sheath": sheath, "band": band,
        "core_band": band / (ms * core), "core_band_sheath": band / (mf * half[0]),
        "poles": sum(np.log(back / a[f"rho{4 * n - 1}"]) / (2 * np.pi * ms * (z1 - z0))
                     for z0, z1 in poles),
        "back_iron": (0.5 * (a["zone_B0"] + a["zone_B1"]) - 0.5 * (a["zone_A0"] + a["zone_A1"]))
        / (ms * area(back, a["outer"])),
    }  # fmt: skip


#: Linear materials over the sweep's drum counts and gaps, the steel's and the fluid's μ_r
#: and the current (the closed-form tests).
_LINEAR_CASES = given(
    n=st.integers(1, 6),
    gap_mm=st.floats(0.1, 1.0),  # the loop's reluctance ≤ 1e-4 of the nearly open paths'
    mu_s=st.floats(200, 5000),
    mu_f=st.floats(2, 10),
    i=st.floats(1e-3, 100),
)


@settings(max_examples=20, deadline=None)
@_LINEAR_CASES
# ill-conditioned by the nearly open paths: the residual's rounding floor (2.8e-10) sits
# above rtol and no step lowers it (the Newton's line-search floor, kernels._FLOOR)
@example(n=4, gap_mm=0.5, mu_s=200.0, mu_f=7.484375, i=1.0)
def test_linear_series_loop_closed_form(n, gap_mm, mu_s, mu_f, i):
    """Linear materials, no leakage: every film carries Φ = N·I/ΣR, R of each element from
    its geometry (``_elements``: the films, the core along both zones and the band, the
    shell) to 5e-5 (the leakage left through the nearly open paths, ``_single_loop``)."""
    c, rg = _regions(n_drums=n, gap=gap_mm * 1e-3)
    mats = linear_materials(mu_s, mu_f)
    net = _single_loop(network_from_regions(rg, mats, fringing=False))
    x = solve_network(net, [[c.coil_turns * i]], mats)[0, 0]
    e = _elements(rg, n, mu_s, mu_f)
    rsum = e["film"].sum() + e["wall"][0].sum() + e["core_band"] + e["poles"] + e["back_iron"]
    np.testing.assert_allclose(x[: net.m], c.coil_turns * i / rsum, rtol=5e-5)


@settings(max_examples=20, deadline=None)
@_LINEAR_CASES
def test_linear_ladder_series_parallel_closed_form(n, gap_mm, mu_s, mu_f, i):
    """Linear materials, every parallel path present but the end leaks (opened: 1e30 /H):
    the network is a series/parallel ladder, and every film's flux equals its reduction to
    1e-9. From the geometry (``_elements``): the films, each wall's steel beside its fluid
    sheath, the core over the band beside half of film 0, the shell; from the network as
    built: the drums' bands, the coil window and the outside air. Reduced from the core
    out: Z₀ = the core's rung, Z_k = rung_k ∥ (film_{k−1,A} + Z_{k−1} + film_{k−1,B}); the
    coil drives the shell (poles + back iron ∥ air) into (film_{m−1} chain) ∥ window; the
    flux then divides down the ladder in inverse proportion to each branch's reluctance."""
    c, rg = _regions(n_drums=n, gap=gap_mm * 1e-3)
    mats = linear_materials(mu_s, mu_f)
    net = network_from_regions(rg, mats, fringing=False)
    net = replace(net, end_leak=np.full_like(net.end_leak, 1e30))
    x = solve_network(net, [[c.coil_turns * i]], mats, rtol=1e-13)[0, 0]
    e = _elements(rg, n, mu_s, mu_f)
    mf, band, film, m = MU0 * mu_f, e["band"], e["film"], 2 * n
    par = lambda p, q: p * q / (p + q)  # noqa: E731
    rung = par(e["wall"], e["sheath"]).sum(axis=1)
    rung[0] += par(e["core_band"], e["core_band_sheath"])
    rung[1:] += 1.0 / (net.rung_perm[0, 1:m] + mf * net.rung_fluid[0, 1:m] / band)
    z = rung[0]
    chain = np.zeros(m)
    for k in range(1, m):
        chain[k] = film[k - 1].sum() + z
        z = par(rung[k], chain[k])
    load = film[m - 1].sum() + z
    window = 1.0 / (net.window_perm[0] + mf * net.window_fluid[0] / band)
    shell = e["poles"] + par(e["back_iron"], net.outer_air[0])
    phi = np.zeros(m)
    source = c.coil_turns * i / (shell + par(load, window))
    phi[m - 1] = source * window / (window + load)
    for k in range(m - 1, 0, -1):
        phi[k - 1] = phi[k] * rung[k] / (rung[k] + chain[k])
    np.testing.assert_allclose(np.abs(x[:m]), phi, rtol=1e-9)


def test_single_loop_limit_equals_the_old_loop():
    """Rungs, window and air open and no fringing: the ladder is the single loop of
    magnetics.circuit without its leakage, to 5e-5 (``_single_loop``), with linear
    materials: with saturating steel the two differ on purpose (the ladder's core and
    drums carry flux that builds up along each zone, the loop's core the full flux)."""
    c, rg = _regions()
    mats = linear_materials(800.0, 4.0)
    net = _single_loop(network_from_regions(rg, mats, fringing=False))
    path = path_from_regions(rg, mats)
    path = replace(path, leak_permeance=np.zeros_like(path.leak_permeance))
    for i in (0.5, 3.0, 7.0):
        ni = [[c.coil_turns * i]]
        x = solve_network(net, ni, mats)[0, 0]
        phi = solve_flux(path, ni, mats)[0, 0]
        np.testing.assert_allclose(x[: net.m], phi, rtol=5e-5)


def _nodal(net, mats, ni):  # type: ignore[no-untyped-def]
    """Independent check: the linear ladder by node potentials (dense solve). Nodes: each
    wall in zone A and B (core … pole), the back-iron end B; the coil's N·I in the poles."""
    s = 0
    m = net.m
    mu = {k: v.mu_initial for k, v in mats.items()}
    rel = lambda kk, ww, name: float(np.sum(ww * kk)) / mu[name]  # noqa: E731  Σ w k/μ
    # a build-up kernel (zone sections, Network): the mean H over a linear rise, w·k/(2μ)
    built = lambda kk, ww, name: 0.5 * rel(kk, ww, name)  # noqa: E731
    # nodes: A0..Am, B0..Bm, O (the back iron's B end; A-side end is pole A = Am)
    idx = lambda z, i: z * (m + 1) + i  # noqa: E731
    nn = 2 * (m + 1) + 1
    o = nn - 1
    g = np.zeros((nn, nn))
    rhs = np.zeros(nn)

    def branch(a, b, r):  # flux a → b = (U_a − U_b)/r
        y = 1.0 / r
        g[a, a] += y
        g[b, b] += y
        g[a, b] -= y
        g[b, a] -= y

    for k in range(m):
        for z in (0, 1):
            r = rel(net.fluid_k[s, k, z], net.fluid_w[s, k, z], net.fluid)
            r += rel(net.wall_k[s, k, z], net.wall_w[s, k, z], net.steel)
            branch(idx(z, k), idx(z, k + 1), r)

    def beside(steel, fluid):  # type: ignore[no-untyped-def]  # a wall ∥ its fluid sheath
        return steel if fluid == np.inf else 1.0 / (1.0 / steel + 1.0 / fluid)

    for i in range(m):  # every wall: its zone sections (steel ∥ sheath), then its band
        r = 0.0
        for z in (0, 1):
            wf = net.sheath_w[s, i, z]
            r += beside(
                built(net.rung_k[s, i, z], net.rung_w[s, i, z], net.steel),
                built(net.sheath_k[s, i, z], wf, net.fluid) if wf.sum() else np.inf,
            )
        if i:
            band = net.rung_perm[s, i] + net.rung_fluid[s, i] * mu[net.fluid] / net.band_len[s]
            r += 1.0 / band
        else:
            wf = net.core_sheath_w[s]
            r += beside(
                rel(net.core_k[s], net.core_w[s], net.steel),
                rel(net.core_sheath_k[s], wf, net.fluid) if wf.sum() else np.inf,
            )
        branch(idx(0, i), idx(1, i), r)
    # shell: pole A (Am) → back iron → O → poles → Bm; the outer air beside the back iron,
    # the window from pole B back to pole A; the coil's N·I drives the pole branch O → Bm
    poles = rel(net.shell_k[s], net.shell_w[s], net.steel)
    branch(idx(0, m), o, rel(net.back_k[s], net.back_w[s], net.steel))
    branch(o, idx(1, m), poles)
    window = net.window_perm[s] + net.window_fluid[s] * mu[net.fluid] / net.band_len[s]
    branch(idx(1, m), idx(0, m), 1.0 / window)
    branch(idx(0, m), o, net.outer_air[s])
    for z in (0, 1):  # the end leaks, pole to core past each zone's far end
        branch(idx(z, m), idx(z, 0), net.end_leak[s, z])
    rhs[o] += ni / poles
    rhs[idx(1, m)] -= ni / poles
    g[0, :] = 0
    g[0, 0] = 1.0
    rhs[0] = 0.0  # ground core A
    u = np.linalg.solve(g, rhs)
    return np.array([
        (u[idx(0, k)] - u[idx(0, k + 1)]) / (rel(net.fluid_k[s, k, 0], net.fluid_w[s, k, 0],
                                                  net.fluid)
                                            + rel(net.wall_k[s, k, 0], net.wall_w[s, k, 0],
                                                  net.steel))
        for k in range(m)
    ])  # fmt: skip


@pytest.mark.parametrize("n", [1, 2, 4, 7])
def test_ladder_solve_against_an_independent_nodal_solve(n):
    """Linear materials: the loop-flux ladder (Thomas + 3×3 tail, bordered by the end
    leaks) equals a dense node-potential solve of the same elements to 1e-9, with every
    leakage path present (the paper preset has a front end leak: it is exercised)."""
    c, rg = _regions(n_drums=n)
    mats = linear_materials(800.0, 4.0)
    net = network_from_regions(rg, mats)
    assert net.end_leak[0, 0] < 1e9  # the front leak is there
    ni = c.coil_turns * 3.0
    x = solve_network(net, [[ni]], mats, rtol=1e-14)[0, 0]
    # the zone-A film fluxes x_k − e_A, flowing from core to pole (potential falls)
    zone_a = x[: net.m] - x[net.leaks][0]
    np.testing.assert_allclose(np.abs(zone_a), np.abs(_nodal(net, mats, ni)), rtol=1e-9)


def test_a_saturated_wall_hands_its_flux_to_the_fluid_beside_it():
    """The sheaths (``_pair``): at the solution each wall section and its fluid sheath have
    one MMF (F_steel(y − q) = F_fluid(q) to 1e-9 of N·I); with linear materials they share
    the rung's flux as their permeances (q/(y − q) = P_fluid/P_steel); on 0.1 mm walls
    with a 6 mm bore at 7 A the drum's steel saturates and its sheaths carry more of its
    rung's flux than the steel in both zones (in the FEM's band plane of that design the
    fluid beside the walls carries 22 µWb, the drum 0.25: docs/magnetics.md)."""

    def mmf(mat, phi, k, w):  # type: ignore[no-untyped-def]
        """w·H̄(k·|Φ|)·sign(Φ): a build-up element's MMF, from the material's own H̄."""
        return np.sign(phi) * w * mat.h_mean_dh(k * np.abs(phi))[0]

    def split(c, rg, mats, cur):  # type: ignore[no-untyped-def]
        net = network_from_regions(rg, mats)
        x = solve_network(net, [[c.coil_turns * cur]], mats, rtol=1e-13)[0, 0]
        m = net.m
        y = np.concatenate([[-x[0]], x[: m - 1] - x[1:m]])  # rungs 0 … m − 1
        q = x[net.sheaths][: 2 * m].reshape(m, 2)  # each wall's sheath in zone A, B
        steel, fluid = magnetic(net.steel, mats), magnetic(net.fluid, mats)
        fs = mmf(steel, y[:, None] - q, net.rung_k[0, ..., 0], net.rung_w[0, ..., 0])
        ff = mmf(fluid, q, net.sheath_k[0, ..., 0], net.sheath_w[0, ..., 0])
        np.testing.assert_allclose(fs, ff, rtol=0, atol=1e-9 * c.coil_turns * cur)
        return net, y, q

    c, rg = _regions()
    mats = linear_materials(800.0, 4.0)
    net, y, q = split(c, rg, mats, 3.0)
    # a build-up element's reluctance is w·k/(2μ) (the mean H over a linear rise, linear)
    p_fluid = 1.0 / (net.sheath_k[0, :, :, 0] * net.sheath_w[0, :, :, 0] / (2 * MU0 * 4.0))
    r_steel = (net.rung_k[0] * net.rung_w[0]).sum(-1) / (2 * MU0 * 800.0)
    np.testing.assert_allclose(q / (y[:, None] - q), p_fluid * r_steel, rtol=1e-8)
    thin = dict(n_drums=1, drum_thickness=0.1e-3, gap=1.0e-3, drum_inner_diameter=6e-3,
                zone_length=9e-3)  # fmt: skip
    c, rg = _regions(**thin)
    net, y, q = split(c, rg, None, 7.0)
    assert np.all(np.abs(q[1]) > np.abs(y[1] - q[1]))  # the drum: more in its fluid


@given(
    y=st.floats(1e-9, 1e-3),
    perm=st.sampled_from([0.0, 1e-10, 1e-8]),
    area=st.sampled_from([0.0, 1e-7, 1e-5]),
)
@settings(max_examples=60, deadline=None)
def test_band_element_shares_its_mmf_between_steel_free_paths(y, perm, area):
    """A band element (a linear permeance in parallel with fluid over the band's length):
    its MMF F carries perm·F + A·B_fluid(F/l) = |y| to 1e-10 on the fluid's own B–H, F is
    odd in y, dF/dy matches a central difference, and a warm start from any B (the last
    Newton iterate's) finds the same F; no fluid: F = y/perm; neither: 0."""
    from magnetics.network.compiled import _kernels
    from magnetics.network.kernels import _tables

    fl = magnetic("mrf_132dg")
    length = 8e-3
    tab, inv, nseg = _tables(magnetic("steel_1018"), fl)
    kernel = _kernels()["_band"]  # the compiled element

    def _band(fl, y, perm, area, length, start=None):  # type: ignore[no-untyped-def]
        return kernel(tab, inv, nseg, y, perm, area, length, start or 0.0, start is not None)

    arr = float
    f, d, b = _band(fl, arr(y), arr(perm), arr(area), arr(length))
    fn, _, _ = _band(fl, arr(-y), arr(perm), arr(area), arr(length))
    assert fn == -f
    if area == 0.0:
        np.testing.assert_allclose(f, y / perm if perm else 0.0, rtol=1e-15)
        return
    carried = perm * f + area * fl.b_of_h(f / length)
    np.testing.assert_allclose(carried, y, rtol=1e-10)
    h = 1e-6 * y
    up, _, _ = _band(fl, arr(y + h), arr(perm), arr(area), arr(length))
    lo, _, _ = _band(fl, arr(y - h), arr(perm), arr(area), arr(length))
    np.testing.assert_allclose(d, (up - lo) / (2 * h), rtol=1e-3)
    # a warm start anywhere (the last iterate's B: below or far above) finds the same F
    for start in (0.0, 0.5 * b, 3.0 * b + 0.5):
        again, _, _ = _band(fl, arr(y), arr(perm), arr(area), arr(length), arr(start))
        np.testing.assert_allclose(again, f, rtol=1e-10)


def test_linear_in_current_below_the_knee():
    """Below the first B–H point the network is linear: flux ∝ current (to 1e-9)."""
    _, rg = _regions()
    net = network_from_regions(rg)
    x = solve_network(net, [[1e-6, 2e-6]], rtol=1e-14)[0]
    np.testing.assert_allclose(x[1], 2 * x[0], rtol=1e-9)


@settings(max_examples=15, deadline=None)
@given(
    n=st.integers(1, 8),
    gap_mm=st.floats(0.05, 2.0),
    thick_mm=st.floats(0.1, 0.8),
)
def test_finite_and_monotone_in_current_or_refused(n, gap_mm, thick_mm):
    """0 A … 1000 A, 1–8 drums, gaps 0.05–2 mm: the torque is finite and never falls with
    the current, or the design is refused (NaN: it fails validation)."""
    fields = {**vars(PAPER), "n_drums": n, "gap": gap_mm * 1e-3, "drum_thickness": thick_mm * 1e-3}
    cur = [0.0, 1e-6, 0.5, 2.0, 7.0, 100.0, 1000.0]
    t = network_torque_batch({k: np.array([v], float) for k, v in fields.items()}, cur)[0]
    if np.isnan(t).any():
        assert np.isnan(t).all()  # refused as a whole design, never a partial answer
        return
    assert np.all(np.isfinite(t)) and t[0] == 0.0
    assert np.all(np.diff(t) >= -1e-12 * t.max())


def test_no_convergence_is_refused_with_the_rows_named():
    _, rg = _regions(n_drums=6, gap=0.1e-3)
    net = network_from_regions(rg)
    with pytest.raises(NetworkConvergenceError, match="refusing their torque"):
        solve_network(net, [[net.turns[0] * 1000.0]], max_iter=1)


def test_blocks_are_invisible_and_refusals_name_global_rows(monkeypatch):
    """Designs solved in blocks (network._BLOCK) give the one-block answer, and a refused
    design is named by its row in the whole batch, not in its block."""
    import magnetics.network.solve as network

    f = {k: np.full(7, float(v)) for k, v in vars(replace(PAPER, n_drums=3)).items()}
    f["gap"] = np.linspace(0.2e-3, 0.8e-3, 7)
    net = network_from_regions(evaluate(broadcast_fields(f), 3))
    ni = net.turns[:, None] * np.array([[0.0, 2.0, 7.0]])
    whole = solve_network(net, ni)
    monkeypatch.setattr(network, "_BLOCK", 3)
    np.testing.assert_allclose(solve_network(net, ni), whole, rtol=1e-12, atol=0.0)
    start = whole.copy()
    start[5] *= 50.0  # far from the answer: one Newton step does not get back
    start[[0, 1, 2, 3, 4, 6]] = whole[[0, 1, 2, 3, 4, 6]]
    with pytest.raises(NetworkConvergenceError, match=r"rows \[5\]"):
        solve_network(net, ni, max_iter=1, start=start)


_FALLBACK = """
import json, sys
import numpy as np
from dataclasses import replace
from geometry.params import broadcast_fields, preset
from geometry.validation import ParameterError
from geometry.regions import evaluate
import magnetics.network.compiled as compiled
from magnetics.network import network_from_regions, solve_network

kernels = compiled._kernels()  # NUMBA_DISABLE_JIT=1: the kernels are the Python functions
newton, cold = kernels["_newton"], []

def warm_fails(p, off, m, npole, tab, inv, nseg, ni, start, warm, *rest):
    conv, row = newton(p, off, m, npole, tab, inv, nseg, ni, start, warm, *rest)
    if warm:  # pretend no continuation start converges
        return False, row
    cold.append(1)
    return conv, row

kernels["_newton"] = warm_fails
f = {k: np.full(5, float(v)) for k, v in vars(replace(preset("paper"), n_drums=4)).items()}
f["drum_thickness"] = np.linspace(0.1e-3, 0.6e-3, 5)
net = network_from_regions(evaluate(broadcast_fields(f), 4))
cur = np.array(json.loads(sys.argv[1]))
x = solve_network(net, net.turns[:, None] * cur[None])
print(json.dumps({"cold": len(cold), "x": x.tolist()}))
"""


def test_continuation_in_current_is_invisible_and_falls_back_to_the_linear_start():
    """solve_network takes the currents one after another, each started from the last
    one's solution: with the columns out of order the answer is each current solved alone
    from the linear start (to the Newton's tolerance); a row the continuation start does
    not bring to convergence is solved again from the linear start, not refused. The
    fallback is shown on the debug path (NUMBA_DISABLE_JIT=1: the kernel's own Python,
    with its Newton replaced by one whose warm starts fail), which also gives the compiled
    kernel's answers."""
    f = {k: np.full(5, float(v)) for k, v in vars(replace(PAPER, n_drums=4)).items()}
    f["drum_thickness"] = np.linspace(0.1e-3, 0.6e-3, 5)
    net = network_from_regions(evaluate(broadcast_fields(f), 4))
    cur = np.array([7.0, 0.0, 2.0, 100.0, 4.0])
    joint = solve_network(net, net.turns[:, None] * cur[None])
    alone = np.stack([solve_network(net, net.turns[:, None] * c)[:, 0] for c in cur], axis=1)
    tol = 1e-8 * np.abs(alone).max()
    np.testing.assert_allclose(joint, alone, rtol=0, atol=tol)
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    run = subprocess.run([sys.executable, "-c", _FALLBACK, json.dumps(cur.tolist())], env=env,
                         capture_output=True, text=True, check=True)  # fmt: skip
    out = json.loads(run.stdout)
    assert out["cold"] == 5 * 5  # each design: the first current cold, the four others again
    np.testing.assert_allclose(np.array(out["x"]), alone, rtol=0, atol=tol)


def test_the_circuits_saturation_gain_starts_the_newton_nearer(monkeypatch):
    """The sweep's peak solve (mrclutch.fast_batch): the linear start scaled by the
    circuit's Φ/Φ_linear at that current gives the loop fluxes of the plain linear start
    (to the Newton's tolerance) in fewer Newton steps (counted on the kernel's own Python:
    9.2 → 5.6 residuals a design on these 12 designs at 7 A); an absurd gain (10³) still
    converges (retried as is) to the same fluxes; a gain ≤ 0 or NaN is refused."""
    import magnetics.network.kernels as kernels
    import magnetics.network.solve as network
    from magnetics.circuit import linear_flux

    f = {k: np.full(12, float(v)) for k, v in vars(replace(PAPER, n_drums=3)).items()}
    f["gap"] = np.linspace(0.2e-3, 0.9e-3, 12)
    f["drum_thickness"] = np.linspace(0.6e-3, 0.1e-3, 12)
    rg = evaluate(broadcast_fields(f), 3)
    net, path = network_from_regions(rg), path_from_regions(rg)
    ni = net.turns[:, None] * 7.0
    gain = solve_flux(path, ni) / linear_flux(path, ni)
    assert np.all((gain > 0.05) & (gain < 1.0))  # these designs saturate at 7 A
    monkeypatch.setattr(network, "_entry", lambda name, rows: vars(kernels)[name])
    calls = []
    residual = kernels._residual
    monkeypatch.setattr(kernels, "_residual", lambda *a: calls.append(1) or residual(*a))
    plain = solve_network(net, ni)
    n_plain, calls[:] = len(calls), []
    scaled = solve_network(net, ni, gain=gain)
    n_scaled = len(calls)
    tol = 1e-8 * np.abs(plain).max()
    np.testing.assert_allclose(scaled, plain, rtol=0, atol=tol)
    assert n_scaled < 0.75 * n_plain, (n_scaled, n_plain)
    np.testing.assert_allclose(solve_network(net, ni, gain=1e3), plain, rtol=0, atol=tol)
    for bad in (0.0, -1.0, np.nan):
        with pytest.raises(ParameterError, match="gain: must be finite and > 0"):
            solve_network(net, ni, gain=bad)


def test_fringe_decay_is_the_laminate_beside_the_film():
    """Past the band-side end of each zone a film's fringing tubes run a leg round each
    wall's end through the laminate on that side: the film's fluid (g) and what lies
    within g beyond its radius (a drum's stainless band and the next film's fluid; at the
    outer film the sleeve and the coil); the core goes on as steel, so film 0 has no inner
    leg. Closed form c = Σ_sides ½·μf·2g/(μf·g + Σ_layers μ·t) at both band-side ends of
    the preset's four films, to 1e-12; with the stainless as permeable as the fluid,
    c = 1 (Roters' tubes) where fluid lies on both sides, more beside the coil; thicker
    bands make the fringe decay faster."""
    c, rg = _regions()
    net = network_from_regions(rg)
    mu_f, mu_ss, mu_coil = (magnetic(k).mu_initial for k in (net.fluid, "stainless_304", "coil"))
    rho = [float(rg.at[f"rho{j}"][0]) for j in range(8)] + [float(rg.at["coil_in"][0])]
    g = np.diff(rho)[0::2]  # films 0 … 3 (equal gaps on the preset)
    t = np.diff(rho)[1::2]  # out1, in1, out2's bands, the sleeve

    def leg(layers):  # type: ignore[no-untyped-def]  # (thickness, μ) filling g
        assert abs(sum(w for w, _ in layers) - g[0]) < 1e-12
        return 0.5 * mu_f * 2 * g[0] / (mu_f * g[0] + sum(w * m for w, m in layers))

    def band(w):  # type: ignore[no-untyped-def]  # a band, then the next film's fluid
        return leg([(w, mu_ss), (g[0] - w, mu_f)])

    expect = np.array([band(t[0]), band(t[0]) + band(t[1]), band(t[1]) + band(t[2]),
                       band(t[2]) + leg([(t[3], mu_ss), (g[0] - t[3], mu_coil)])])  # fmt: skip
    np.testing.assert_allclose(net.fringe_c[0, :, 0, 1], expect, rtol=1e-12)  # zone A, top
    np.testing.assert_allclose(net.fringe_c[0, :, 1, 0], expect, rtol=1e-12)  # zone B, bottom
    assert expect[0] < 0.7 and np.all(expect[1:] > 1.1) and expect[3] > expect[2] + 0.2
    fluid_only = network_from_regions(rg, {**MATERIALS, "stainless_304": magnetic(net.fluid)})
    np.testing.assert_allclose(fluid_only.fringe_c[0, 1:3, 0, 1], 1.0, rtol=1e-12)
    np.testing.assert_allclose(fluid_only.fringe_c[0, 0, 0, 1], 0.5, rtol=1e-12)
    beyond = 0.5 + leg([(t[3], mu_f), (g[0] - t[3], mu_coil)])  # the coil past the sleeve
    np.testing.assert_allclose(fluid_only.fringe_c[0, 3, 0, 1], beyond, rtol=1e-12)
    assert beyond > 1.1
    thick = network_from_regions(_regions(drum_thickness=2 * c.drum_thickness)[1])
    assert np.all(thick.fringe_c[0, :, 0, 1] > net.fringe_c[0, :, 0, 1])


@pytest.mark.parametrize("n", [1, 4])
def test_fringe_torque_is_the_fringe_permeance_in_the_linear_limit(n):
    """At a tiny current τy = a·H (tanh linear) and the fringe's field H_e·g/(g + cπs)
    integrates to a·H_e·(g/cπ)·ln(1 + cπh/g): each film's torque is 2π r²·τy(H_e)·(L + δ)
    with δ that fringing length over the film's own fluid (``Network.fringe_h``, c
    ``Network.fringe_c``), to 1e-9; its flux spreads over L_eff ≥ L + δ (Roters' tubes,
    c = 1, are at least as long; the pockets past the film add permeance, not torque). At 7 A
    the torque equals τy summed by quadrature along the zone, where the film's B_z builds
    up, and along each fringe, to 1e-5 (``_AXIAL_POINTS`` = 4 against 64)."""
    c, rg = _regions(n_drums=n, gap=0.4e-3)
    net = network_from_regions(rg)
    i = 1e-5  # A: αH ≈ 6e-5, tanh linear to 1e-9
    sol = solve_network(net, [[c.coil_turns * i]])[0, 0]
    t = network_gap_torque(net, [[i]])[0, 0].reshape(2, net.m)
    r = 0.5 * (net.gap_r0[0] + net.gap_r1[0])
    g = net.gap_r1[0] - net.gap_r0[0]
    for z in (0, 1):
        eff, length = net.gap_eff[0, :, z], net.gap_len[0, :, z]
        cz = net.fringe_c[0, :, z]
        own = length + sum((g / (cz[:, e] * np.pi))
                           * np.log1p(cz[:, e] * np.pi * net.fringe_h[0, :, z, e] / g)
                           for e in (0, 1))  # fmt: skip
        x = np.abs(sol[: net.m] - sol[net.leaks][z])  # the zone's film flux
        h_e = magnetic(net.fluid).h_of_b(x / (2 * np.pi * r * eff))
        expect = 2 * np.pi * r**2 * FLUIDS[net.fluid].tau_y(h_e) * own
        np.testing.assert_allclose(t[z], expect, rtol=1e-9)
        assert np.all(own > length) and np.all(eff >= own * (1 - 1e-12))
    assert net.gap_eff[0, 0, 0] > 1.01 * (
        net.gap_len[0, 0, 0] + (g[0] / np.pi) * np.log1p(np.pi * net.fringe_h[0, 0, 0, 1] / g[0])
    )  # gap 0's front pocket, before the core's face
    # saturating: the torque read independently of network_film_torque's code, each film's
    # H_r = B_r·H(|B|)/|B| with B_z from its sheaths' fluxes over their areas (half of each
    # neighbouring film's annulus; the mean of the inner and the outer half's at the
    # mid-line), 64 Gauss–Legendre points along the zone, and the fringes' τy(H_e·g/(g +
    # cπs)) summed over s by 400 points (the closed form MRFluid.tau_y_decay)
    fluid, bh, i = FLUIDS[net.fluid], magnetic(net.fluid), 7.0
    sol = solve_network(net, [[c.coil_turns * i]])[0, 0]
    hot = network_gap_torque(net, [[i]])[0, 0].reshape(2, net.m)
    half = 0.5 * np.pi * (net.gap_r1[0] ** 2 - net.gap_r0[0] ** 2)
    area = half + np.concatenate([[0.0], half[:-1]])  # wall k: films k − 1 and k
    q = np.abs(sol[net.sheaths][: 2 * net.m]).reshape(net.m, 2) / area[:, None]
    u, wt = np.polynomial.legendre.leggauss(400)
    t, tw = np.polynomial.legendre.leggauss(64)
    t, tw = 0.5 * (t + 1), 0.5 * tw

    def h_r(b_r, b_z):  # type: ignore[no-untyped-def]
        b = np.hypot(b_r, b_z)
        return b_r * bh.h_of_b(b) / b

    for z in (0, 1):
        x = np.abs(sol[: net.m] - sol[net.leaks][z])
        b_r = x / (2 * np.pi * r * net.gap_eff[0, :, z])
        b_z = 0.5 * (q[:, z] + np.concatenate([q[1:, z], [0.0]]))  # inner, outer half
        assert np.all(b_z > 0)  # ≤ 6 % of B_r here; large in the test after this one
        over = sum(w * fluid.tau_y(h_r(b_r, tk * b_z)) for tk, w in zip(t, tw, strict=True))
        fringe = 0.0
        for e in (0, 1):
            band = e == 1 if z == 0 else e == 0  # the end facing the band
            h_e = h_r(b_r, b_z if band else 0.0)
            assert np.all(6.33e-6 * h_e > 0.4)  # τy off its linear part by > 5 %: non-linear
            depth, cz = net.fringe_h[0, :, z, e], net.fringe_c[0, :, z, e]
            s = 0.5 * depth[:, None] * (u + 1)
            h = h_e[:, None] * g[:, None] / (g[:, None] + cz[:, None] * np.pi * s)
            fringe = fringe + 0.5 * depth * (fluid.tau_y(h) * wt).sum(-1)
        expect = 2 * np.pi * r**2 * (over * net.gap_len[0, :, z] + fringe)
        np.testing.assert_allclose(hot[z], expect, rtol=1e-5)


def test_film_torque_reads_the_fluids_axial_flux():
    """The film's fluid is one isotropic material: where it also carries the axial flux
    beside the walls (the sheaths), its permeability falls with |B| and H_r for the same
    B_r rises. On the design where the network was furthest below the FEM (1 drum, 6 mm
    bore, 1 mm gaps, 0.1 mm drums, 9 mm zones, 7 A: the core and the drum saturate and the
    films carry B_z ≈ B_r) that reading adds 2.9 % to the torque, and it is the torque's
    only: with the sheaths' fluxes set to 0 the reading is H(B_r), every film's torque is
    lower, and with them doubled it is higher still (H/B rises with B). network_film_torque
    reads the fluxes it is given: the solve itself does not see the coupling."""
    _, rg = _regions(n_drums=1, drum_inner_diameter=6e-3, gap=1e-3, drum_thickness=0.1e-3,
                     zone_length=9e-3)  # fmt: skip
    net = network_from_regions(rg)
    t, x = network_torque_and_flux(net, [[7.0]])
    bz_in, _ = _film_axial_b(net, x)
    ok = net.gap_len.transpose(0, 2, 1).reshape(1, -1)[0] > 0
    b_r = np.abs(x[0, 0, : net.m]) / (2 * np.pi * net.gap_r0[0] * net.gap_eff[0, :, 0])
    assert np.max(bz_in[0, 0]) > 0.5 * np.max(b_r)  # the axial flux is the radial's size
    flat, doubled = x.copy(), x.copy()
    flat[..., net.sheaths] = 0.0
    doubled[..., net.sheaths] *= 2.0
    t0, t2 = network_film_torque(net, flat), network_film_torque(net, doubled)
    assert np.all(t0[0, 0, ok] < t[0, 0, ok]) and np.all(t[0, 0, ok] < t2[0, 0, ok])
    assert 0.02 < t.sum() / t0.sum() - 1 < 0.04
    # with the sheaths at 0 (and no fringes) the reading is τy(H(B_r)) over the overlap
    bare = network_film_torque(replace(net, fringe_h=np.zeros_like(net.fringe_h)), flat)
    r = 0.5 * (net.gap_r0[0] + net.gap_r1[0])
    for z in (0, 1):
        xz = np.abs(x[0, 0, : net.m] - x[0, 0, net.leaks][z])
        h = magnetic(net.fluid).h_of_b(xz / (2 * np.pi * r * net.gap_eff[0, :, z]))
        expect = 2 * np.pi * r**2 * FLUIDS[net.fluid].tau_y(h) * net.gap_len[0, :, z]
        np.testing.assert_allclose(bare[0, 0, z * net.m : (z + 1) * net.m], expect, rtol=1e-9)


def test_torque_curve_network_is_a_batch_of_one():
    c = replace(PAPER, n_drums=4, gap=0.4e-3)
    one = torque_curve(c, [2.0, 7.0], method="network").yield_torque
    batch = network_torque_batch({k: np.array([v], float) for k, v in vars(c).items()},
                                 [2.0, 7.0])[0]  # fmt: skip
    np.testing.assert_allclose(one, batch, rtol=1e-12)


@pytest.mark.parametrize("convention", ["mid-line", "weakest-layer"])
def test_yield_at_is_the_torque_and_flux_solve_at_each_call(convention):
    """``network_yield_at`` packs the network and sets up its films' reading once for all
    its calls (the continuous torque's chords); each call is still
    ``network_torque_and_flux`` at that current, started from the last call's loop fluxes
    scaled by the current's ratio: the same torques, bit for bit, on 5 gaps of the paper
    design at a peak of 7 A and chords at 5, 2.5 and 4 A (a design at 0 A reads 0)."""
    f = {k: np.full(5, float(v)) for k, v in vars(replace(PAPER, n_drums=3)).items()}
    f["gap"] = np.linspace(0.2e-3, 0.8e-3, 5)
    net = network_from_regions(evaluate(broadcast_fields(f), 3))
    peak = np.full(5, 7.0)
    _, x = network_torque_and_flux(net, peak[:, None], convention=convention)
    at = network_yield_at(net, convention=convention, seed=(peak, x))
    last = peak[:, None]
    for amps in (5.0, 2.5, 4.0):
        cur = np.full((5, 1), amps)
        cur[4] = 0.0 if amps == 2.5 else amps
        ratio = np.where(last != 0, cur / np.where(last != 0, last, 1), 0)
        t, x = network_torque_and_flux(net, cur, convention=convention,
                                       start=x * ratio[..., None])  # fmt: skip
        got = at(cur[:, 0])
        np.testing.assert_array_equal(got, t.sum(-1)[:, 0])
        assert np.all(got[:4] > 0) and (amps != 2.5 or got[4] == 0.0)
        last = cur


def test_yield_at_solves_the_peak_afresh_with_a_gain_and_hands_its_flux_over():
    """The sweep's row (mrclutch.fast_batch) solves its peak with ``network_yield_at``'s
    first call (``gain``: from the circuit-scaled linear start) and hands ``at.flux`` to the
    error bound: the torques and loop fluxes of ``network_torque_and_flux`` with that gain,
    bit for bit; a later call with a gain starts afresh too (not from the last fluxes)."""
    f = {k: np.full(4, float(v)) for k, v in vars(replace(PAPER, n_drums=2)).items()}
    f["gap"] = np.linspace(0.2e-3, 0.8e-3, 4)
    net = network_from_regions(evaluate(broadcast_fields(f), 2))
    peak, gain = np.full(4, 7.0), np.array([[0.2], [0.3], [0.4], [0.5]])
    t, x = network_torque_and_flux(net, peak[:, None], gain=gain)
    at = network_yield_at(net)
    np.testing.assert_array_equal(at(peak, gain=gain), t.sum(-1)[:, 0])
    np.testing.assert_array_equal(at.flux, x)
    at(peak * 0.3)
    t2, x2 = network_torque_and_flux(net, peak[:, None] * 0.5, gain=gain)
    np.testing.assert_array_equal(at(peak * 0.5, gain=gain), t2.sum(-1)[:, 0])
    np.testing.assert_array_equal(at.flux, x2)


@pytest.mark.parametrize("convention", ["mid-line", "weakest-layer"])
def test_yield_at_rows_solves_those_designs_as_a_call_on_all(convention):
    """``at(current, rows=mask)`` (the continuous rating's third solve, on the rows whose
    model moved) solves only the masked designs, on a network of those rows, each started
    from its own last loop fluxes: the torques and fluxes of a call on all designs at
    those rows, bit for bit; the other rows keep their last state."""
    f = {k: np.full(5, float(v)) for k, v in vars(replace(PAPER, n_drums=3)).items()}
    f["gap"] = np.linspace(0.2e-3, 0.8e-3, 5)
    net = network_from_regions(evaluate(broadcast_fields(f), 3))
    rows = np.array([True, False, True, True, False])
    part, whole = (
        network_yield_at(net, convention=convention),
        network_yield_at(net, convention=convention),
    )
    for at in (part, whole):
        at(np.full(5, 7.0))
        at(np.linspace(1.0, 3.0, 5))
    cur = np.linspace(2.0, 4.0, 5)
    got = part(cur[rows], rows=rows)
    assert got.shape == (3,) and np.all(got > 0)
    np.testing.assert_array_equal(got, whole(cur)[rows])
    np.testing.assert_array_equal(part.flux[rows], whole.flux[rows])
    kept = network_yield_at(net, convention=convention)
    kept(np.full(5, 7.0))
    kept(np.linspace(1.0, 3.0, 5))
    np.testing.assert_array_equal(part.flux[~rows], kept.flux[~rows])


# ---- against the stored FEM reference (measured, not tuned) ------------------------------


@pytest.fixture(scope="module")
def measured():  # type: ignore[no-untyped-def]
    sys.path.insert(0, str(BENCH))
    try:
        import measure_network as mn
    finally:
        sys.path.remove(str(BENCH))
    return {m: mn.errors(m) for m in ("network", "circuit")}


def test_network_against_the_fem_reference(measured):
    """Torque at 2, 4, 7 A against the FEM (0.25 mm, mid-line) on the 648-design grid and
    200 random designs (benchmarks/measure_network.py). Measured: within ±5 % on 92.7 % of
    the grid and 98.5 % of the random designs, within ±10 % on all of both, worst −8.8 …
    +8.2 % (issue 12's goals: ≥ 90 % and all); the single loop 39 %, 38 % within ±10 %,
    worst −86 … +77 %."""
    err, rnd, _ = measured["network"]
    old, _, _ = measured["circuit"]
    within = lambda e: float(np.mean(np.abs(e) <= 0.10))  # noqa: E731
    assert float(np.mean(np.abs(err[~rnd]) <= 0.05)) >= 0.90
    assert float(np.mean(np.abs(err[rnd]) <= 0.05)) >= 0.90
    assert within(err[~rnd]) == 1.0 and within(err[rnd]) == 1.0
    assert np.abs(err).max() <= 0.09
    for sel in (~rnd, rnd):  # better than the single loop on both sets, by far
        assert within(err[sel]) >= within(old[sel]) + 0.25
        assert np.abs(err[sel]).max() < 0.5 * np.abs(old[sel]).max()


def test_network_is_better_than_the_loop_at_every_drum_count(measured):
    """Per drum count on the grid, within ±10 %: the network 100 % at every drum count,
    the loop 17–64 % (worst at 5–6 drums, 17–24 %)."""
    err, rnd, f = measured["network"]
    old, _, _ = measured["circuit"]
    for n in range(1, 7):
        sel = (f["n_drums"] == n) & ~rnd
        net, loop = (float(np.mean(np.abs(e[sel]) <= 0.1)) for e in (err, old))
        assert net == 1.0 and net >= loop + (0.6 if n >= 5 else 0.25)


def test_the_networks_error_map_is_this_measurement_and_bounds_its_checks():
    """magnetics/data/network_error_map.json is the network against the stored FEM
    reference at 7 A (re-measured here: the map is a test of the network, and stale data
    fails), and its bound — interpolation plus the measured margin — covers every one of
    the 200 off-grid random designs it was checked on."""
    sys.path.insert(0, str(BENCH))
    try:
        import measure_network_map as mm
    finally:
        sys.path.remove(str(BENCH))
    from magnetics.error_map import load, map_bound

    axes, errs, checks = mm.measure()
    stored = load("network")
    assert dict(stored.axes) == {k: tuple(v) for k, v in axes.items()}
    np.testing.assert_allclose(stored.errors, errs, atol=1e-5)  # stored to 5 decimals
    base = vars(PAPER)
    for c, e in checks:
        _, bound, off = map_bound({**base, **c}, "network")
        assert not off and abs(e) <= bound + 1e-12, (c, e, bound)
    assert 0.0 < stored.range_factor < 1.0


def test_reference_data_is_the_stored_measurement():
    data = json.loads((BENCH / "data" / "fem_reference.json").read_text())
    assert data["currents_A"] == [2.0, 4.0, 7.0] and len(data["grid"]) == 648
    assert len(data["random"]) == 200


def test_flux_linkage_is_the_coenergy_derivative_and_matches_the_fem():
    """λ = N·(x_{m−1} + x_w) is ∂W'/∂I, and L_inc = N²·sᵀJ⁻¹s its derivative: equal to a
    central difference of λ (1e-4; the B–H is piecewise linear), odd in the current. On the
    paper preset the FEM's linkage, (N/A_coil)·∫_coil 2πψ dA, is within 1.1 % of the
    network's at 0.5–7 A (measured −0.8 … −1.1 %), where the loop's is 5–10 % low."""
    from magnetics.dynamics import flux_linkage as loop_linkage
    from magnetics.fem import build_grid, solve_fem
    from magnetics.network import flux_linkage

    c, rg = _regions()
    net = network_from_regions(rg)
    cur = np.array([0.5, 2.0, 7.0])
    lam, ind = flux_linkage(net, net.turns[:, None] * cur)
    h = 1e-4
    up, _ = flux_linkage(net, net.turns[:, None] * (cur + h))
    lo, _ = flux_linkage(net, net.turns[:, None] * (cur - h))
    np.testing.assert_allclose(ind, (up - lo) / (2 * h), rtol=1e-4)
    neg, _ = flux_linkage(net, -net.turns[:, None] * cur)
    np.testing.assert_allclose(neg, -lam, rtol=1e-12)
    from geometry.section import build_section

    sec = build_section(c)
    grid = build_grid(sec, None, None)
    fem = np.array([solve_fem(sec, float(i), grid=grid).flux_linkage for i in cur])
    assert np.all(np.abs(lam[0] / fem - 1) <= 0.012)
    loop, _ = loop_linkage(path_from_regions(rg), cur[None, :])
    assert np.all(np.abs(loop[0] / fem - 1) > np.abs(lam[0] / fem - 1))


def test_fem_flux_linkage_is_linear_with_linear_materials():
    """The FEM's linkage is the coil-weighted mean of 2πψ: with linear materials it is
    proportional to the current (to 1e-9), and λ·I is the field's energy ∫ ν|B|²·2πr dA
    (twice the co-energy): read with B at the element centres the two differ by 0.66 % at
    1 mm and 0.43 % at 0.5 mm — the gap closes as the mesh is refined."""
    from geometry.section import build_section
    from magnetics.fem import build_grid, solve_fem

    c, _ = _regions()
    mats = linear_materials(800.0, 4.0)
    sec = build_section(c)
    miss = []
    for size in (1e-3, 0.5e-3):
        grid = build_grid(sec, size, mats)
        a, b = (solve_fem(sec, i, materials=mats, grid=grid) for i in (1.0, 3.0))
        assert b.flux_linkage == pytest.approx(3.0 * a.flux_linkage, rel=1e-9)
        nu = np.array([1.0 / mats[name].mu_initial for name in b.material])[b.material_index]
        p, t = grid.mesh.p, grid.mesh.t
        area = np.ptp(p[0, t], axis=0) * np.ptp(p[1, t], axis=0)
        energy = float(np.sum(nu * (b.b_r**2 + b.b_z**2) * 2 * np.pi * b.centre_r * area))
        miss.append(abs(b.flux_linkage * 3.0 / energy - 1))
    assert miss[0] < 0.01 and miss[1] < 0.8 * miss[0]
