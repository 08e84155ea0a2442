"""The thermal network pinned to values worked by hand, not to itself.

Every number here is derived in the docstrings from the paper preset's dimensions as a
person would type them (mm), with the formulas of magnetics/thermal.py's docstring and the
constants of [incropera] / [churchill-chu1975] / [rayleigh1892] written out, so a wrong
term (a factor, a face counted once, a wrong radius) in ``network`` fails one of these.
The hand arithmetic uses ``math`` on typed numbers only: nothing is read back from the
region table.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from geometry.params import preset
from geometry.section import build_section
from magnetics.thermal import continuous_current, network, steady

MM = 1e-3
# constants as a person would look them up (the module cites the same tables)
K_EPOXY, K_STEEL, K_SS, K_MRF = 0.2, 60.5, 14.9, 0.65  # W/(m·K) [incropera], [lord-mrf132dg]
SIGMA, EPS = 5.670374419e-8, 0.3
AIR_NU, AIR_ALPHA, AIR_K, AIR_PR = 15.89e-6, 22.5e-6, 0.0263, 0.707  # air, 300 K [incropera]
RHO_CU20, ALPHA = 1.72e-8, 0.00393


def wall(r0: float, r1: float, k: float, length: float) -> float:
    """ln(r1/r0)/(2π k L), a cylindrical wall [incropera] Eq. 3.33."""
    return math.log(r1 / r0) / (2 * math.pi * k * length)


def hand_paper() -> dict[str, float]:
    """The paper preset by hand (all lengths in mm as typed, converted here):

    * coil window 9.0–11.5 mm radius × 8.5 mm band, 140 turns of 0.321 mm bare wire:
      copper fraction f = 140·π·0.321²/4 / (2.5·8.5) = 0.5332;
      k_w = 0.2·(1 + f)/(1 − f) = 0.6569 W/(m·K) [rayleigh1892];
    * the stack core → poles: radii 5.05, 5.75, 6.05, 6.75, 7.00, 7.70, 8.00, 8.70 mm,
      fluid (0.65) in the even layers, steel (60.5) in the odd:
      Σ ln(r_j+1/r_j)/(2π k_j) = 0.10280 K·m/W;
    * coil → core: ln(10.25/9)/(2π k_w L) + ln(9/8.7)/(2π·14.9·L) + 0.10280/L,
      L = 8.5 mm → G_cc = 0.06312 W/K;
    * coil → housing: ln(11.5/10.25)/(2π k_w L) → G_ch = 0.30486 W/K;
    * core → housing: two zones of 6 mm through the stack, 2·6 mm/0.10280 = 0.11673 W/K,
      plus the back cap: half its 0.8 mm axially over π·5.05² and radially 5.05 → 12.9 mm,
      0.4 mm/(14.9·π·5.05²) + ln(12.9/5.05)/(2π·14.9·0.8 mm) = 12.86 K/W → 0.07778 W/K;
      G_kh = 0.19451 W/K;
    * to air: D = 25.8 mm, length 24.4 mm, area π·D·24.4 + 2π·12.9² = 3.0233e-3 m²;
      film ΔT = (130 − 20)/2 = 55 K, Ra = 9.81·β·55·D³/(ν α) = 8.08e4 with
      β = 1/(293.15 + 27.5); Churchill–Chu Nu = 7.354 → h = 7.497 W/(m²·K);
      linearised radiation 0.3·σ·(T_s² + T_a²)(T_s + T_a) = 2.260 W/(m²·K) at
      T_s = 348.15 K, T_a = 293.15 K → G_air = 0.029496 W/K;
    * coil resistance at 20 °C: 1.72e-8·140·π·(9 + 11.5) mm / (π·0.321²/4 mm²) = 1.9163 Ω.
    """
    f = 140 * math.pi * 0.321**2 / 4 / (2.5 * 8.5)
    k_w = K_EPOXY * (1 + f) / (1 - f)
    band = 8.5 * MM
    radii = [5.05, 5.75, 6.05, 6.75, 7.0, 7.7, 8.0, 8.7]
    stack = sum(
        math.log(radii[j + 1] / radii[j]) / (2 * math.pi * (K_MRF if j % 2 == 0 else K_STEEL))
        for j in range(7)
    )
    r_ci, r_co = 9.0 * MM, 11.5 * MM
    r_cm = (r_ci + r_co) / 2
    g_cc = 1 / (wall(r_ci, r_cm, k_w, band) + wall(8.7 * MM, r_ci, K_SS, band) + stack / band)
    g_ch = 1 / wall(r_cm, r_co, k_w, band)
    r_cap = (0.4 * MM) / (K_SS * math.pi * (5.05 * MM) ** 2) + wall(
        5.05 * MM, 12.9 * MM, K_SS, 0.8 * MM
    )
    g_kh = 2 * 6 * MM / stack + 1 / r_cap
    d, length = 25.8 * MM, 24.4 * MM
    area = math.pi * d * length + 2 * math.pi * (12.9 * MM) ** 2
    dt = 55.0
    beta = 1 / (293.15 + dt / 2)
    ra = 9.81 * beta * dt * d**3 / (AIR_NU * AIR_ALPHA)
    nu = (0.6 + 0.387 * ra ** (1 / 6) / (1 + (0.559 / AIR_PR) ** (9 / 16)) ** (8 / 27)) ** 2
    t_s, t_a = 348.15, 293.15
    h_rad = EPS * SIGMA * (t_s**2 + t_a**2) * (t_s + t_a)
    g_air = (nu * AIR_K / d + h_rad) * area
    r20 = RHO_CU20 * 140 * math.pi * (9.0 + 11.5) * MM / (math.pi * (0.321 * MM) ** 2 / 4)
    return {"g_cc": g_cc, "g_ch": g_ch, "g_kh": g_kh, "g_air": g_air, "r20": r20,
            "area": area, "h_conv": nu * AIR_K / d, "h_rad": h_rad, "stack": stack,
            "r_cap": r_cap}  # fmt: skip


@pytest.fixture(scope="module")
def net():
    return network(build_section(preset("paper")).table)


@pytest.fixture(scope="module")
def hand():
    return hand_paper()


def test_hand_values_are_the_docstrings(hand):
    """The hand calculation itself against the figures written in its docstring, so the
    docstring a reviewer follows is the arithmetic the tests use."""
    assert hand["stack"] == pytest.approx(0.10280, rel=1e-4)
    assert hand["g_cc"] == pytest.approx(0.06312, rel=2e-4)
    assert hand["g_ch"] == pytest.approx(0.30486, rel=1e-4)
    assert hand["r_cap"] == pytest.approx(12.86, rel=1e-3)
    assert hand["g_kh"] == pytest.approx(0.19451, rel=1e-4)
    assert hand["area"] == pytest.approx(3.0233e-3, rel=1e-4)
    assert hand["h_conv"] == pytest.approx(7.497, rel=1e-3)
    assert hand["h_rad"] == pytest.approx(2.260, rel=1e-3)
    assert hand["g_air"] == pytest.approx(0.029496, rel=1e-4)
    assert hand["r20"] == pytest.approx(1.9163, rel=1e-4)


def test_conductances_of_the_paper_preset_by_hand(net, hand):
    """Each off-diagonal of G is minus one hand-worked conductance, the diagonal their
    sum, plus the loss to air on the housing's."""
    G = np.asarray(net.conductance)
    assert -G[0, 1] == pytest.approx(hand["g_cc"], rel=1e-9)
    assert -G[0, 2] == pytest.approx(hand["g_ch"], rel=1e-9)
    assert -G[1, 2] == pytest.approx(hand["g_kh"], rel=1e-9)
    np.testing.assert_allclose(G, G.T, rtol=0, atol=0)
    assert G[0, 0] == pytest.approx(hand["g_cc"] + hand["g_ch"], rel=1e-9)
    assert G[1, 1] == pytest.approx(hand["g_cc"] + hand["g_kh"], rel=1e-9)
    assert G[2, 2] == pytest.approx(hand["g_ch"] + hand["g_kh"] + hand["g_air"], rel=1e-9)
    assert float(net.to_air) == pytest.approx(hand["g_air"], rel=1e-9)
    assert float(net.r20) == pytest.approx(hand["r20"], rel=1e-9)


def test_capacities_of_the_paper_preset_by_hand(net):
    """Heat capacities from volumes × density × specific heat [incropera] Table A.1:

    * coil: π(11.5² − 9²)·8.5 mm³ = 1368.6 mm³ of f = 0.5332 copper (8960 kg/m³,
      385 J/(kg·K)) and epoxy (1200, 1100) → 3.3604 J/K;
    * housing: steel shell 8.7–12.9 mm over 0.8–8.6 and 17.1–23.6 mm, back iron
      11.5–12.9 mm over 8.6–17.1 mm (7870 kg/m³ × 434 J/(kg·K)); stainless sleeve
      8.7–9.0 mm over the 8.5 mm band, front cap 2.2–12.9 mm and back cap 0–12.9 mm, both
      0.8 mm thick (8000 × 477) → 20.723 J/K.
    """
    f = 140 * math.pi * 0.321**2 / 4 / (2.5 * 8.5)
    ring = lambda r0, r1, z0, z1: math.pi * (r1**2 - r0**2) * (z1 - z0) * MM**3  # noqa: E731
    coil = ring(9.0, 11.5, 8.6, 17.1) * (f * 8960 * 385 + (1 - f) * 1200 * 1100)
    steel = ring(8.7, 12.9, 0.8, 8.6) + ring(11.5, 12.9, 8.6, 17.1) + ring(8.7, 12.9, 17.1, 23.6)
    stainless = ring(8.7, 9.0, 8.6, 17.1) + ring(2.2, 12.9, 0.0, 0.8) + ring(0.0, 12.9, 23.6, 24.4)
    housing = steel * 7870 * 434 + stainless * 8000 * 477
    assert coil == pytest.approx(3.3604, rel=1e-4)
    assert housing == pytest.approx(20.723, rel=1e-4)
    cap = np.asarray(net.capacity)
    assert cap[0] == pytest.approx(coil, rel=1e-9)
    assert cap[2] == pytest.approx(housing, rel=1e-9)


def test_steady_temperatures_at_half_an_ampere_by_hand(net, hand):
    """0.5 A, no slip: the coil's power I²R20(1 + α(T_c − 20)) into node 0, solved by
    fixed-point iteration on the hand-built 3×3 network (an independent method from the
    module's Sherman–Morrison closed form). By hand, to first order: P ≈ 0.25·1.916 =
    0.479 W, nearly all through the air's 0.0295 W/K → the housing ≈ 20 + 0.479·1.18/0.0295
    (the resistance warmed) ≈ 39 °C, the coil ≈ 1.5 K above it."""
    g_cc, g_ch, g_kh, g_air = hand["g_cc"], hand["g_ch"], hand["g_kh"], hand["g_air"]
    G = np.array([[g_cc + g_ch, -g_cc, -g_ch],
                  [-g_cc, g_cc + g_kh, -g_kh],
                  [-g_ch, -g_kh, g_ch + g_kh + g_air]])  # fmt: skip
    t = np.full(3, 20.0)
    for _ in range(200):
        p = 0.25 * hand["r20"] * (1 + ALPHA * (t[0] - 20.0))
        t = np.linalg.solve(G, np.array([p, 0.0, g_air * 20.0]))
    assert 35.0 < t[2] < 45.0 and 0.5 < t[0] - t[2] < 3.0  # the estimate above
    np.testing.assert_allclose(steady(net, 0.5), t, rtol=1e-9)


def test_continuous_rating_of_the_paper_preset_by_hand(net, hand):
    """The largest current whose steady coil stays ≤ 155 °C and core ≤ 130 °C, found by
    bisection on the hand network (no slip). The coil, warmer than the core, reaches its
    limit first only if 155 − 20 over the coil's rise per watt is the smaller: here the
    core's 130 °C binds at I ≈ 1.2 A (a hand estimate: 110 K/(0.0295 W/K) ≈ 3.7 W at
    R(≈130 °C) ≈ 2.75 Ω → I ≈ 1.17 A)."""
    g_cc, g_ch, g_kh, g_air = hand["g_cc"], hand["g_ch"], hand["g_kh"], hand["g_air"]
    G = np.array([[g_cc + g_ch, -g_cc, -g_ch],
                  [-g_cc, g_cc + g_kh, -g_kh],
                  [-g_ch, -g_kh, g_ch + g_kh + g_air]])  # fmt: skip

    def temps(i: float) -> np.ndarray:
        t = np.full(3, 20.0)
        for _ in range(400):
            p = i**2 * hand["r20"] * (1 + ALPHA * (t[0] - 20.0))
            t = np.linalg.solve(G, np.array([p, 0.0, g_air * 20.0]))
        return t

    lo, hi = 0.0, 3.0
    for _ in range(50):
        mid = (lo + hi) / 2
        t = temps(mid)
        lo, hi = (mid, hi) if (t[0] <= 155.0 and t[1] <= 130.0) else (lo, mid)
    assert 1.0 < lo < 1.4  # the estimate in the docstring
    assert float(continuous_current(net, 155.0, 130.0)) == pytest.approx(lo, rel=1e-6)


def test_a_second_design_by_hand():
    """Three drums, 0.5 mm gaps, 0.4 mm drums on the paper base: the core → housing
    conductance by hand. The first output drum's inner radius stays 11.5/2 = 5.75 mm, so
    the core is 5.75 − 0.5 = 5.25 mm; outward: gap, out drum, gap, in drum, … for three
    output drums (0.4) and two input drums (0.25): 5.25, 5.75, 6.15, 6.65, 6.90, 7.40,
    7.80, 8.30, 8.55, 9.05, 9.45, 9.95 mm; 11 layers, fluid in the even ones."""
    from dataclasses import replace

    c = replace(preset("paper"), n_drums=3, gap=0.5 * MM, drum_thickness=0.4 * MM)
    rg = build_section(c).table
    net3 = network(rg)
    radii = [5.25]
    for j in range(11):
        if j % 2 == 0:
            step = 0.5
        else:
            step = 0.4 if (j // 2) % 2 == 0 else 0.25
        radii.append(radii[-1] + step)
    assert radii[-1] == pytest.approx(float(rg.pole_radius) / MM, rel=1e-12)
    stack = sum(
        math.log(radii[j + 1] / radii[j]) / (2 * math.pi * (K_MRF if j % 2 == 0 else K_STEEL))
        for j in range(11)
    )
    outer = float(rg.outer_radius)
    r_core = 5.25 * MM
    r_cap = (0.4 * MM) / (K_SS * math.pi * r_core**2) + wall(r_core, outer, K_SS, 0.8 * MM)
    g_kh = 2 * 6 * MM / stack + 1 / r_cap
    assert -float(np.asarray(net3.conductance)[1, 2]) == pytest.approx(g_kh, rel=1e-9)
