"""Every off-state drag term against its closed form, the fluid's viscosity law at its
data points, the carried fluid's inertia against the linear Couette integral."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from geometry.materials import DENSITY, MRF
from geometry.params import broadcast_fields, preset
from geometry.regions import evaluate as regions_of
from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.drag import (
    Support,
    bearing_moment,
    clutch_drag,
    coupled_fluid_inertia,
    drag_terms,
    taylor_ratio,
    totals,
)
from magnetics.materials import MRF_132DG

PAPER = preset("paper")
W = 530 * 2 * math.pi / 60


def test_viscosity_at_the_datasheet_point_and_the_carrier_points():
    assert MRF_132DG.viscosity_at(40.0) == pytest.approx(0.112, rel=1e-12)
    for t, nu in MRF_132DG.carrier_points:
        assert MRF_132DG.carrier_viscosity(t) == pytest.approx(nu, rel=1e-12)
    temps = np.linspace(-40, 130, 50)
    eta = MRF_132DG.viscosity_at(temps)
    assert np.all(np.diff(eta) < 0)  # thinner when hotter
    # room temperature: a hydrocarbon carrier is about twice as viscous as at 40 °C
    assert 1.8 < MRF_132DG.viscosity_at(20.0) / 0.112 < 3.0
    with pytest.raises(ParameterError, match="fluid_temperature = 150"):
        MRF_132DG.viscosity_at(150.0)


def test_couette_and_disc_terms_against_their_closed_forms():
    s = build_section(PAPER)
    eta = MRF_132DG.viscosity_at(20.0)
    d = clutch_drag(s.table, W, 20.0)
    gaps = [2 * math.pi * eta * W * g.r_mean**3 * (g.z1 - g.z0) / g.width for g in s.gaps]
    assert d.gap_torque == pytest.approx(gaps, rel=1e-12)
    assert d.terms["drum gaps"].torque == pytest.approx(sum(gaps), rel=1e-12)
    faces = []
    for f in s.table.films("face"):
        r0, r1, z0, z1 = s.table.bounds(f)
        faces.append(math.pi * eta * W * (r1**4 - r0**4) / (2 * (z1 - z0)))
    assert d.terms["end faces"].torque == pytest.approx(sum(faces), rel=1e-12)
    # films are linear in ω: damping = torque / ω
    for k in ("drum gaps", "end faces"):
        assert d.terms[k].damping == pytest.approx(d.terms[k].torque / W, rel=1e-12)
    assert d.torque == pytest.approx(sum(t.torque for t in d.terms.values()), rel=1e-12)


def test_bearing_model_by_hand_and_its_slope():
    """SKF: 618/4 on the 4 mm shaft, d_m = (4 + 7)/2 mm; M_rr = R1 d_m^1.96 F_r^0.54 (νn)^0.6,
    M_sl = μ_sl S1 d_m^−0.26 F_r^(5/3) [N·mm]; two bearings."""
    sup = Support()
    rr, sl = bearing_moment(sup, PAPER.shaft_radius, W)
    dm, fr, nu, n = 5.5, 10.0, 110.0, 530.0
    assert rr == pytest.approx(2e-3 * 4.7e-7 * dm**1.96 * fr**0.54 * (nu * n) ** 0.6, rel=1e-9)
    assert sl == pytest.approx(2e-3 * 0.05 * 6.5e-3 * dm**-0.26 * fr ** (5 / 3), rel=1e-9)
    # the reported slope is the derivative of the torque against the slip speed
    rg = build_section(PAPER).table
    h = 1e-3 * W
    tp = drag_terms(rg, W + h, support=sup)["bearings"].torque
    tm = drag_terms(rg, W - h, support=sup)["bearings"].torque
    assert drag_terms(rg, W, support=sup)["bearings"].damping == pytest.approx(
        (tp - tm) / (2 * h), rel=1e-5
    )
    none = drag_terms(rg, W, support=Support(bearing="none"))["bearings"]
    assert none.torque == 0 and none.damping == 0


def test_a_coulomb_seal_adds_torque_not_damping():
    rg = build_section(PAPER).table
    off0, c0 = totals(drag_terms(rg, W))
    off1, c1 = totals(drag_terms(rg, W, support=Support(seal_torque=5e-3)))
    assert off1 - off0 == pytest.approx(5e-3, rel=1e-12)
    assert c1 == pytest.approx(c0, rel=1e-15)


def test_carried_fluid_of_a_linear_couette_profile():
    """One design's carried fluid against an independent quadrature: ∫ρ r² s² dV over the
    cylindrical films (s linear from the input wall to the output wall) plus 1/3 of every
    other fluid region's inertia."""
    rg = build_section(PAPER).table
    rho = DENSITY[MRF]
    expect = 0.0
    for sp in rg:
        if sp.part != "fluid":
            continue
        r0, r1, z0, z1 = rg.bounds(sp)
        if sp.film == "cylinder":
            r = np.linspace(r0, r1, 20001)
            s = (r1 - r) / (r1 - r0) if sp.walls[0].startswith("out") else (r - r0) / (r1 - r0)
            expect += 2 * math.pi * rho * (z1 - z0) * np.trapezoid(r**3 * s**2, r)
        else:
            expect += rho * math.pi * (r1**4 - r0**4) * (z1 - z0) / 6
    assert coupled_fluid_inertia(rg) == pytest.approx(expect, rel=1e-7)


def test_thin_film_tends_to_a_third_of_its_inertia():
    for gap in (0.7e-3, 0.3e-3, 0.1e-3):
        rg = build_section(replace(PAPER, gap=gap)).table
        sp = rg.spec("gap1")
        r0, r1, z0, z1 = rg.bounds(sp)
        own = DENSITY[MRF] * math.pi * (r1**4 - r0**4) * (z1 - z0) / 2
        # the film's share alone: build a one-film table by difference is awkward; use
        # the closed form of ∫ r³ s² dr for s = (r − r0)/h, relative to own/3
        h = r1 - r0
        exact = (
            2
            * math.pi
            * DENSITY[MRF]
            * (z1 - z0)
            * (r0**3 * h / 3 + 3 * r0**2 * h**2 / 4 + 3 * r0 * h**3 / 5 + h**4 / 6)
        )
        assert exact / (own / 3) == pytest.approx(1.0, abs=2 * h / r0)


def test_taylor_number_is_laminar_on_the_preset_and_scales_with_speed_squared():
    rg = build_section(PAPER).table
    t1 = taylor_ratio(rg, W, 20.0)
    assert t1 < 1e-2
    assert taylor_ratio(rg, 10 * W, 20.0) == pytest.approx(100 * t1, rel=1e-12)
    d = clutch_drag(rg, 400 * W, 60.0)
    assert any("Taylor" in n for n in d.notes)


def test_slow_shear_is_flagged():
    d = clutch_drag(build_section(PAPER).table, 0.1 * W)
    assert any("shear-thins" in n for n in d.notes)


def test_batch_equals_one_design_at_a_time():
    gaps = np.array([0.3e-3, 0.5e-3, 0.9e-3])
    p = broadcast_fields({"gap": gaps}, PAPER)
    batch = totals(drag_terms(regions_of(p, 2), W, 25.0))
    for i, g in enumerate(gaps):
        one = clutch_drag(build_section(replace(PAPER, gap=float(g))).table, W, 25.0)
        assert batch[0][i] == pytest.approx(one.torque, rel=1e-12)
        assert batch[1][i] == pytest.approx(one.damping, rel=1e-12)
    # and the carried fluid
    fi = coupled_fluid_inertia(regions_of(p, 2))
    assert fi[1] == pytest.approx(
        coupled_fluid_inertia(build_section(replace(PAPER, gap=0.5e-3)).table), rel=1e-12
    )


def test_support_validation_names_the_parameter():
    with pytest.raises(ParameterError, match="bearing"):
        Support(bearing="6204")
    with pytest.raises(ParameterError, match="seal_torque"):
        Support(seal_torque=-1.0)


def test_quasi_steady_frequency_is_where_the_penetration_depth_is_the_widest_gap():
    from magnetics.drag import quasi_steady_hz

    rg = build_section(PAPER).table
    f = quasi_steady_hz(rg, 20.0)
    nu = MRF_132DG.viscosity_at(20.0) / DENSITY[MRF]
    delta = math.sqrt(2 * nu / (2 * math.pi * f))  # Stokes' penetration depth at f
    assert delta == pytest.approx(PAPER.gap, rel=1e-12)
    assert clutch_drag(rg, W, 20.0).quasi_steady_hz == pytest.approx(f, rel=1e-15)
