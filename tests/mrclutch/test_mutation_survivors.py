"""Tests for the survivors of the round's mutation run (issue 46, docs/testing.md).

``python benchmarks/mutation_run.py --run round`` plants one-expression errors in the
modules of the last two rounds and runs the tests that cover them, the doc-figure check
left out. Each test here kills a survivor that changes an answer a user can get; its
verdict, under ``[round."module:index"]`` in benchmarks/data/mutation_verdicts.toml, names
it. Each was checked by planting the same mutant by hand and seeing the test fail.
"""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from mrclutch import estimates
from mrclutch.design import design_preset
from mrclutch.optimize import pareto


class _Stop(Exception):
    """Raised by a progress report to end a search after its first generation."""


def test_pareto_runs_100_generations_by_default():
    """docs/optimize.md: the Pareto search runs "200 designs a generation for 50
    generations" unless told otherwise (100 × 100 before issue 40). ``progress`` is called
    (generations done, ``generations``) after each generation, so its first call names the
    total: 50 with the default; the mutant ``generations: int = 101`` (optimize.py:574 at
    d2d4f2c; now ``DEFAULT_GENERATIONS = 51``) gives 101 (51). The search is stopped at that
    first call (a population of 4: the total does not depend on it). The name stays the
    one benchmarks/data/mutation_verdicts.toml records."""
    totals: list[int] = []

    def first(done: int, total: int) -> None:
        totals.append(total)
        raise _Stop

    with pytest.raises(_Stop):
        pareto(design_preset("paper"), drum_counts=(2,), pop_size=4, members=1, progress=first)
    assert totals == [50]


def test_sweep_rate_is_designs_timed_over_the_time_they_took(monkeypatch):
    """The sweep's speed estimate (``estimates.sweep_rate``; the announced time and the
    refusal without --yes above 10 min follow from it) on a clock that advances 0.125 s a
    call of the evaluator: the warm-up call ends at 0.125 s (t0), then chunks of 100 designs
    end at 0.25, 0.375 and 0.5 s, where 0.375 s ≥ 0.3 s stops the timing. Rate = 300
    designs / 0.375 s × 2 workers = 1600 designs/s, measured on 300. The mutant
    ``done * max(elapsed, 1e-9)`` (cli/commands/design.py:697 at d2d4f2c) gives 225."""
    clock = [0.0]

    def evaluator(fields):
        clock[0] += 0.125

    monkeypatch.setattr(estimates, "time", SimpleNamespace(perf_counter=lambda: clock[0]))
    monkeypatch.setattr(estimates, "use_compiled", lambda: None)  # no process-wide switch
    asked: list[int] = []  # the chunks whose fields are timed: the first (chunk 0)

    def fields(i):
        asked.append(i)
        return None, {"gap": np.zeros(10_000)}

    spec = SimpleNamespace(n_designs=10_000, chunk_size=100, design_fields=fields)
    rate, done = estimates.sweep_rate(spec, evaluator, 2)
    assert asked == [0]  # the mutant design_fields(1) (estimates.py:29) times chunk 1
    assert done == 300
    assert rate == pytest.approx(1600.0, rel=1e-12)


@pytest.mark.parametrize("far", [100.0, math.e])
def test_threshold_takes_the_crossing_nearest_the_value_in_p(monkeypatch, far):
    """``robust.threshold``: where the limit crosses K twice over its 10⁻³–10³ window, the
    crossing nearest the value in ``p`` (in log) is the threshold. A stand-in limit
    K·exp((u − u1)(u − u2)) of u = ln b1 crosses K at b1 = b0/2 and b1 = far·b0, with b0 =
    0.01 N·s/m; the nearer is b0/2 = 0.005 N·s/m (|ln 0.5| = 0.69 < ln far), and the limit
    falls through K there, so the verdict holds below it ("≤"). far = 100 puts the other
    crossing cells away (the mutant ``abs(best[0] + u0)`` at d2d4f2c took b1 = 1.0); far = e
    puts it in the cell beside b0's, which the outward search (c3679c9) reaches before it
    stops, so the comparison of the two roots decides: the mutant ``abs(r + u0)`` compares
    |2 ln b0 − 0.69| = 9.9 with |2 ln b0 + 1| = 8.2 and takes e·b0."""
    from mrclutch import robust
    from mrclutch.haptics.actuator import TABLE2_MR

    K, b0 = 50.0, 0.01
    u1, u2 = math.log(b0 / 2), math.log(far * b0)

    def limit(p):  # vectorised over b1 as the "stable" kernel is (robust._VECTORISED)
        u = np.log(p.b1)
        return K * np.exp((u - u1) * (u - u2))

    monkeypatch.setitem(robust._LIMITS, "stable", limit)
    t = robust.threshold(replace(TABLE2_MR, b1=b0), K, "stable", "b1")
    assert t is not None
    assert t["value"] == pytest.approx(b0 / 2, rel=1e-8)
    assert t["sense"] == "≤"


# --- the run of today's modules (--run round2, benchmarks/data/mutation_round2.json) -----


def test_every_design_file_key_is_read_in_si_by_its_units_factor():
    """A design file's keys carry their unit in the name (``delay_ms``, ``m2_g`` …); each
    is read into SI by the factor the unit states, worked here by hand: 600 rpm = 600·2π/60
    = 62.83 rad/s, 8 A/mm² = 8e6 A/m², 2 ms = 0.002 s, 110 mm²/s = 1.1e-4 m²/s, 5 mN·m =
    0.005 N·m, 0.5 mm = 5e-4 m, 20 g = 0.02 kg; a key in A, V, Hz, N, °C or s is taken as
    it is. The mutant ``"wire_temperature_limit_C": (…, 1.1)`` (design.py:203) reads
    150 °C as 165 °C; every factor of the tables is pinned the same way."""
    from mrclutch.design import design_from_mapping

    d = design_from_mapping({
        "clutch": {"base": "paper"},
        "operating": {"max_current_A": 5, "max_current_density_A_per_mm2": 8,
                      "input_speed_rpm": 600, "delay_ms": 2, "coil_temperature_C": 60,
                      "fluid_temperature_C": 45, "ambient_temperature_C": 25,
                      "wire_temperature_limit_C": 150, "peak_duration_s": 3},
        "support": {"bearings": 3, "bearing_load_N": 12, "grease_viscosity_mm2_per_s": 110,
                    "seal_torque_mN_m": 5},
        "amplifier": {"supply_voltage_V": 36, "current_bandwidth_Hz": 500},
        "laminations": {"core_mm": 0.5, "shell_mm": 0.35},
        "transmission": {"ratio": 1.5, "lever_mm": 120, "gearing": 2, "k_N_per_m": 9000,
                         "b_N_s_per_m": 3, "m2_g": 20, "workspace_mm": 40},
    })  # fmt: skip
    op, sup, amp, lam, tr = d.operating, d.support, d.amplifier, d.laminations, d.transmission
    got = [op.max_current, op.max_current_density, op.input_speed, op.delay,
           op.coil_temperature, op.fluid_temperature, op.ambient_temperature,
           op.wire_temperature_limit, op.peak_duration, sup.bearings, sup.bearing_load,
           sup.grease_viscosity, sup.seal_torque, amp.supply_voltage, amp.current_bandwidth_hz,
           lam.core, lam.shell, tr.ratio, tr.lever, tr.gearing, tr.k, tr.b, tr.m2,
           tr.workspace]  # fmt: skip
    want = [5.0, 8e6, 62.83185307179586, 0.002, 60.0, 45.0, 25.0, 150.0, 3.0, 3, 12.0,
            1.1e-4, 0.005, 36.0, 500.0, 5e-4, 3.5e-4, 1.5, 0.12, 2.0, 9000.0, 3.0, 0.02,
            0.04]  # fmt: skip
    assert got == pytest.approx(want, rel=1e-12)


def test_time_to_limits_batch_takes_its_batch_from_the_networks_capacities():
    """``time_to_limits_batch`` answers (S,) for a network of S designs even when the
    current, the slip heat and the coil's r20 are shared scalars: its batch is the
    capacities' leading shape (…, 3) less the node axis. Two copies of the paper clutch's
    network, r20 a float, give the one design's times twice. The mutant
    ``np.shape(net.capacity)[:-2]`` (thermal.py:283) takes no batch from (2, 3) and fails
    to broadcast it to one design."""
    from geometry.params import preset
    from geometry.section import build_section
    from magnetics.thermal import Network, network, time_to_limits, time_to_limits_batch

    one = network(build_section(preset("paper")).table)
    two = Network(np.stack([one.capacity] * 2), np.stack([one.conductance] * 2),
                  np.stack([np.asarray(one.to_air)] * 2), float(one.r20), one.ambient,
                  np.stack([one.inverse] * 2))  # fmt: skip
    tw, tf = time_to_limits_batch(two, 3.0, 5.0, 155.0, 130.0)
    w1, f1 = time_to_limits(one, 3.0, 5.0, 155.0, 130.0)
    assert np.shape(tw) == np.shape(tf) == (2,)
    assert tw == pytest.approx([w1, w1], rel=1e-12)
    assert tf == pytest.approx([f1, f1], rel=1e-12)


def test_null_notes_take_the_tables_note_else_the_keys_documented_meaning():
    """``pipeline.null_notes``: a null (None or NaN) under a table with a ``note`` is
    explained by that note; outside one, by the key's documented meaning (``NAN_MEANS``);
    an inf by ``INF_MEANS``. The mutant ``note and NAN_MEANS.get(…)`` (pipeline.py:241)
    gives a null outside any note no reason and one under a note the key's meaning."""
    from mrclutch.pipeline import INF_MEANS, NAN_MEANS, null_notes

    data = {
        "haptic": {"resonance_hz": None, "B_N_s_per_m": float("nan")},
        "em": {"note": "no motor of this torque", "resonance_hz": None,
               "B_N_s_per_m": float("nan")},
        "zwidth": {"mr": {"K_max_N_per_m": None}},
        "duty": {"time_to_wire_limit_s": float("inf")},
    }  # fmt: skip
    assert null_notes(data) == {
        "haptic/resonance_hz": NAN_MEANS["resonance_hz"],
        "haptic/B_N_s_per_m": NAN_MEANS["B_N_s_per_m"],
        "em/resonance_hz": "no motor of this torque",
        "em/B_N_s_per_m": "no motor of this torque",
        "zwidth/mr/K_max_N_per_m": NAN_MEANS["K_max_N_per_m"],  # the last key's, not "mr"'s
        "duty/time_to_wire_limit_s": INF_MEANS["time_to_wire_limit_s"],
    }


def test_the_delay_range_is_refused_above_one_second_and_taken_at_it():
    """``Uncertainty.delay``'s upper end is at most 1 s (a haptic loop's delay): 1.0 s is
    taken, 1.05 s refused in one line naming the delay. The mutant ``delay[1] > 1.1``
    (uncertainty.py:118) takes 1.05 s."""
    from geometry.validation import ParameterError
    from mrclutch.uncertainty import Uncertainty

    assert Uncertainty(delay=(0.001, 1.0)).delay == (0.001, 1.0)
    with pytest.raises(ParameterError, match=r"delay = \[0\.001, 1\.05\] s: must be <= 1 s"):
        Uncertainty(delay=(0.001, 1.05))


def test_the_optimisers_verified_candidates_are_numbered_from_one(monkeypatch):
    """``members.verify_candidates`` hands the FEM check its N best candidates numbered 1 … N
    (the ranks the report prints beside each re-solved torque), one fast torque and one
    error bound each. The FEM solve itself is replaced by a recorder. The mutant
    ``range(1, len(top) - 1)`` (members.py:197) numbers three candidates [1]."""
    from mrclutch import members
    from mrclutch.optimize.limits import Constraints

    seen: dict = {}

    def record(designs, ids, values, fast, bounds, fem_size, executor):
        seen.update(n=len(designs), ids=list(ids), values=list(values), fast=len(fast),
                    bounds=len(bounds))  # fmt: skip
        return []

    monkeypatch.setattr(members, "verify_designs", record)
    base = design_preset("paper")
    top = [SimpleNamespace(design=base, value=float(v)) for v in (3.0, 2.0, 1.0)]
    members.verify_candidates(top, base, Constraints(), None, None)
    assert seen == {"n": 3, "ids": [1, 2, 3], "values": [3.0, 2.0, 1.0], "fast": 3, "bounds": 3}


def test_churchill_chu_h_is_the_published_correlation_written_out():
    """``thermal.churchill_chu_h``: Nu = {0.6 + 0.387 Ra^(1/6) / [1 + (0.559/Pr)^(9/16)]^(8/27)}²
    (Churchill & Chu 1975, horizontal cylinder), Ra = g β ΔT D³/(ν α), β = 1/T_film,
    h = Nu k/D, with the module's air properties. For D = 50 mm, ΔT = 30 K, 20 °C air the
    film is at 308.15 K and h = 5.64 W/(m²·K) (Incropera's range for free convection in
    gases, 2–25). The mutant exponent 9/27 (thermal.py:106) gives 5.43 (3.7 % less)."""
    from magnetics.thermal import AIR_ALPHA, AIR_K, AIR_NU, AIR_PR, churchill_chu_h

    d, dt, ta = 0.05, 30.0, 20.0
    ra = 9.81 / (ta + 273.15 + dt / 2) * dt * d**3 / (AIR_NU * AIR_ALPHA)
    nu = (0.6 + 0.387 * ra ** (1 / 6) / (1 + (0.559 / AIR_PR) ** (9 / 16)) ** (8 / 27)) ** 2
    h = float(churchill_chu_h(d, dt, ta))
    assert h == pytest.approx(nu * AIR_K / d, rel=1e-12)
    assert 2.0 < h < 25.0


def test_only_the_side_rendered_at_the_others_k_max_says_so(capsys):
    """``compare`` renders both sides at the smaller K_max: the side whose own K_max is the
    larger (the MR pair, 343.9 against the motor's 299.2 N/m) says "the smaller K_max of the
    two" and its own; the motor, at its own K_max, and ``haptic`` of one actuator say
    "K_max … N/m `[source]`". The mutant ``… or rule is None or …`` (cli/commands/haptic.py:255)
    labels every side so."""
    from mrclutch.cli.main import main

    assert main(["haptic", "--actuator", "maxon-136209"]) == 0
    one = capsys.readouterr().out
    assert "smaller K_max" not in one
    assert "\n  K_max " in one and "[maxon-136209, Table 1 catalogue]:" in one
    assert main(["compare"]) == 0
    two = capsys.readouterr().out
    labelled = [ln for ln in two.splitlines() if "the smaller K_max of the two, [" in ln]
    assert len(labelled) == 1 and "this side's own K_max" in labelled[0]
    assert sum(ln.startswith("  K_max ") for ln in two.splitlines()) == 1


def test_the_field_map_spans_the_section_and_a_margin(monkeypatch):
    """``plot_field`` draws r from 0 to the last grid node within 1.3 × the section's outer
    radius and z over the nodes within 3 mm of the section's ends, in mm. On nodes every
    2.5 mm over r 0–50 mm and 5 mm over z −30–30 mm, a section of r ≤ 20 mm and z ±10 mm:
    r 0–25 mm (25 ≤ 1.3 × 20 = 26 < 27.5 mm), z −10–10 mm (±13 mm keeps the nodes at
    ±10). A steel region r 5–15 mm, z −5–5 mm is outlined by a 10 × 10 mm rectangle at
    (5, −5) mm; the fluid is not outlined. The mutants ``r[keep_r][1]``
    (cli/plots/magnetics.py:58) stop r at the second node, 2.5 mm; ``r_max * 1.43`` (:44)
    at 27.5 mm; ``(g.r1 - g.r0) / 1000.0`` (:56) draw the outline 10 µm wide."""
    import matplotlib.pyplot as plt

    from mrclutch.cli.plots import magnetics as magnetics_plots

    figs: list = []
    monkeypatch.setattr(magnetics_plots, "save_png", lambda fig, path, dpi=110: figs.append(fig))
    r, z = np.linspace(0, 0.05, 21), np.linspace(-0.03, 0.03, 13)
    rc, zc = np.meshgrid((r[:-1] + r[1:]) / 2, (z[:-1] + z[1:]) / 2)
    sol = SimpleNamespace(r_nodes=r, z_nodes=z, centre_r=rc.ravel(), centre_z=zc.ravel(),
                          b=np.full(rc.size, 1.0), current=2.0)  # fmt: skip
    steel = SimpleNamespace(part="steel", r0=0.005, r1=0.015, z0=-0.005, z1=0.005)
    fluid = SimpleNamespace(part="fluid", r0=0.015, r1=0.016, z0=-0.005, z1=0.005)
    section = SimpleNamespace(r_max=0.02, z_min=-0.01, z_max=0.01, regions=[steel, fluid])
    magnetics_plots.plot_field(section, sol, "unused.png")
    ax = figs[0].axes[0]
    try:
        assert ax.get_xlim() == pytest.approx((0.0, 25.0), abs=1e-9)
        assert ax.get_ylim() == pytest.approx((-10.0, 10.0), abs=1e-9)
        assert ax.get_xlabel() == "r (mm)" and ax.get_ylabel() == "z (mm)"
        assert len(ax.patches) == 1
        box = ax.patches[0]
        assert (*box.get_xy(), box.get_width(), box.get_height()) == pytest.approx(
            (5.0, -5.0, 10.0, 10.0), abs=1e-9
        )
    finally:
        plt.close(figs[0])


def test_verify_top_asks_for_yes_above_ten_thousand_fem_solves_not_at_it(monkeypatch):
    """``sweep --verify-top N``: more than MAX_FEM_UNASKED = 10⁴ FEM solves need --yes;
    10⁴ itself does not (the time estimate, put at 1 s here, still could). The mutant
    ``n >= MAX_FEM_UNASKED`` (cli/commands/sweep.py:196) refuses 10⁴."""
    import argparse

    from mrclutch.cli.commands import sweep
    from mrclutch.cli.errors import CLIError

    monkeypatch.setattr(sweep, "check_fem_size", lambda base, size: None)
    monkeypatch.setattr(sweep, "fem_solve_seconds", lambda base, size, n: 1.0)
    base = design_preset("paper")
    assert sweep.MAX_FEM_UNASKED == 10**4
    sweep._check_fem_work(argparse.Namespace(verify_top=10**4, yes=False), base, 1e-3)
    sweep._check_fem_work(argparse.Namespace(verify_top=10**4 + 1, yes=True), base, 1e-3)
    with pytest.raises(CLIError, match=r"--verify-top 10001: more than 10000 FEM solves; add"):
        sweep._check_fem_work(argparse.Namespace(verify_top=10**4 + 1, yes=False), base, 1e-3)


def test_the_fem_check_of_a_sweep_is_timed_from_its_start(tmp_path, monkeypatch, capsys):
    """``sweep --verify-top N`` prints how long the FEM re-solves took: the clock after them
    less the clock before. A clock at 100.0 s before and 102.5 s after gives 2.5 s (the
    re-solves themselves replaced by a stand-in). The mutant ``perf_counter() + t0``
    (cli/commands/sweep.py:235) gives 202.5 s."""
    from mrclutch.cli.commands import sweep
    from mrclutch.cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text('[sweep]\nmode = "random"\nsamples = 4\nseed = 3\n'
                                     'base = "paper"\n[parameters]\n'
                                     "gap_mm = {min = 0.3, max = 0.9}\n")  # fmt: skip
    ticks = iter([100.0, 102.5])
    monkeypatch.setattr(sweep, "time", SimpleNamespace(perf_counter=lambda: next(ticks)))
    monkeypatch.setattr(sweep, "verify_top", lambda *a: [])
    monkeypatch.setattr(sweep, "write_verified", lambda *a: "r.verified.csv")
    took: list[float] = []
    monkeypatch.setattr(sweep, "format_verified", lambda rows, key, size, workers, s:
                        took.append(s) or "")  # fmt: skip
    argv = ["sweep", "s.toml", "--out", "r.csv", "--no-progress", "--workers", "1",
            "--verify-top", "1", "--verify-fem-size-mm", "1"]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    assert took == [2.5]


def test_an_uncertainty_tables_refused_value_is_named_by_its_file_key():
    """``uncertainty_from_mapping``: a value the Uncertainty itself refuses (a delay range
    up to 2 s, above its 1 s cap) is named by the file's key, then the SI field's own
    message: "uncertainty.delay_ms: delay = [0.001, 2.0] s: …". The mutant
    ``str(exc).split(" ", 1)[1]`` (uncertainty.py:274) names it by the message's second
    word."""
    from geometry.validation import ParameterError
    from mrclutch.uncertainty import uncertainty_from_mapping

    with pytest.raises(ParameterError) as err:
        uncertainty_from_mapping({"delay_ms": [1, 2000]})
    assert str(err.value).startswith("uncertainty.delay_ms: delay = [0.001, 2.0] s: must be")


def test_a_design_file_without_operating_keys_gets_the_documented_operating_point():
    """A design file that gives no `[operating]` key gets the paper's bench (Fig. 2b, §IV-B)
    and the stated defaults: 7 A, 530 rpm (55.5 rad/s), 1 ms delay, coil and ambient air at
    20 °C, magnet wire of class 155 (155 °C), the peak held 1 s. The mutant ambient 22 °C
    (operating.py:41) moves every temperature rise's base."""
    from mrclutch.design import design_from_mapping

    op = design_from_mapping({"clutch": {"base": "paper"}}).operating
    got = (op.max_current, op.input_speed, op.delay, op.coil_temperature,
           op.ambient_temperature, op.wire_temperature_limit, op.peak_duration)  # fmt: skip
    assert got == pytest.approx((7.0, 530 * math.pi / 30, 1e-3, 20.0, 20.0, 155.0, 1.0))


def test_search_box_refusals_say_which_process_bound():
    """``search_box``: a process bound above a range's upper edge is refused naming the
    bound: for the gap, the process's smallest gap (runout + tolerance)/eccentricity bound;
    for a drum wall, its smallest wall. The mutant ``name != "gap"`` (optimize/box.py:40)
    gives each the other's reason."""
    from geometry.validation import ParameterError
    from mrclutch.design import design_from_mapping
    from mrclutch.optimize.box import search_box

    base = design_from_mapping({"clutch": {"base": "paper"},
                                "process": {"runout_mm": 0.05, "tolerance_mm": 0.05,
                                            "min_wall_mm": 0.8}})  # fmt: skip
    with pytest.raises(ParameterError, match=r"^gap_mm: the process's smallest gap \(runout"):
        search_box(base, {"gap": (0.1e-3, 0.3e-3)})
    with pytest.raises(ParameterError, match=r"^drum_thickness_mm: the process's smallest wall"):
        search_box(base, {"drum_thickness": (0.2e-3, 0.5e-3)})


def test_no_uncertainty_shrinks_every_range_to_the_nominal_value():
    """``no_uncertainty`` (``--no-uncertainty``): every spread 0, the torque factor (1, 1),
    the temperature and delay ranges the operating values (20 °C, 1 ms without a design),
    no bench damping. The mutants that put 0.001 in any of its zeros (uncertainty.py:445)
    leave a spread."""
    from mrclutch.uncertainty import no_uncertainty

    u = no_uncertainty()
    spreads = (u.viscosity_spread, u.gap_tolerance, u.runout, u.drum_thickness_tolerance,
               u.yield_stress_spread, u.bh_spread)  # fmt: skip
    assert spreads == (0.0,) * 6
    assert u.torque_factor == (1.0, 1.0)
    assert u.fluid_temperature == (20.0, 20.0) and u.delay == (1e-3, 1e-3)
    assert u.bench_damping == (0.0, 0.0)


def test_a_design_written_to_toml_reads_its_decimals_back_bit_for_bit():
    """``design_to_toml`` writes each SI field as the shortest decimal of its file unit
    that reads back to the same float: a gap of 0.523 mm is "gap_mm = 0.523", a delay of
    1.7 ms "delay_ms = 1.7", the paper's 530 rpm "input_speed_rpm = 530.0", and they read
    back bit for bit. The mutants ``float(to_si(m)) != si`` (design.py:448) write the first
    decimal that does not read back (0.5 mm); ``factor < 1 or inv * factor == 1`` (:436)
    writes the speed as rad/s × round(60/2π) = 10 (555 "rpm"); ``inv / factor == 1``
    (:247) reads 110 mm²/s as 110 × 1e-6, one ulp from 110e-6."""
    import tomllib

    from mrclutch.design import design_from_mapping, design_to_toml

    d = design_preset("paper")
    d = replace(d, clutch=replace(d.clutch, gap=0.523e-3),
                operating=replace(d.operating, delay=1.7e-3))  # fmt: skip
    text = design_to_toml(d)
    assert "gap_mm = 0.523\n" in text and "delay_ms = 1.7\n" in text
    assert "input_speed_rpm = 530.0\n" in text  # a factor 2π/60 that is no 1/integer
    # a decimal prefix divides: 110 / 1e6 is the float 110e-6, 110 × 1e-6 is not
    assert "grease_viscosity_mm2_per_s = 110.0\n" in text
    back = design_from_mapping(tomllib.loads(text))
    assert back.clutch.gap == d.clutch.gap and back.operating.delay == d.operating.delay
    assert back.support.grease_viscosity == d.support.grease_viscosity == 110e-6


def test_the_pareto_json_quotes_its_search_box_in_mm(monkeypatch, capsys):
    """``optimize`` (Pareto) writes the box it searched as ``box_mm``: each length's
    [low, high] of ``search_box`` (SI) × 1e3, the default box of the paper preset here,
    with where each edge came from. A short search (16 designs, 4 generations, 2 members,
    the fast path) is enough: the box does not depend on it. The mutant ``lo / 1000.0``
    (cli/commands/optimize_pareto.py:142) quotes every low edge 10⁶ times too small."""
    import json

    from mrclutch.cli.commands import optimize_pareto as pareto_cmd
    from mrclutch.cli.main import main
    from mrclutch.optimize.box import search_box

    real = pareto_cmd.pareto
    monkeypatch.setattr(pareto_cmd, "pareto", lambda *a, **k: real(
        *a, **{**k, "pop_size": 16, "generations": 4, "members": 2}))  # fmt: skip
    code = main(["optimize", "--drums", "2", "--nominal", "--no-verify", "--json",
                 "--no-progress"])  # fmt: skip
    cap = capsys.readouterr()
    assert code in (0, 3), cap.err  # 3: a requirement missed; the JSON is whole
    data = json.loads(cap.out)
    box, source = search_box(design_preset("paper"), None)
    assert data["box_mm"] == {
        f"{k}_mm": pytest.approx([lo * 1e3, hi * 1e3], rel=1e-12) for k, (lo, hi) in box.items()
    }
    assert data["box_source"] == {f"{k}_mm": v for k, v in source.items()}


def test_the_figures_frequencies_span_the_band_log_spaced():
    """``impedance.band_frequencies``: POINTS = 1500 frequencies log-spaced from the band's
    low end to its high end (BAND_HZ by default; 1–100 Hz given): constant ratio
    100^(1/1499) between neighbours. The mutant ``np.log10(band[1])`` as the start
    (impedance.py:30) gives 1500 times the top."""
    from mrclutch.haptics.model import BAND_HZ
    from mrclutch.impedance import POINTS, band_frequencies

    f = band_frequencies()
    assert f.size == POINTS == 1500
    assert (f[0], f[-1]) == pytest.approx(BAND_HZ, rel=1e-12)
    g = band_frequencies((1.0, 100.0))
    assert (g[0], g[-1]) == pytest.approx((1.0, 100.0), rel=1e-12)
    assert g[1:] / g[:-1] == pytest.approx(np.full(1499, 100 ** (1 / 1499)), rel=1e-12)


def test_optimize_refuses_a_duty_of_zero_seconds(capsys):
    """``optimize --duty NM:S``: both the torque and the time must be > 0; ``0.2:0`` is
    refused in one line, exit 2. The mutant ``duty[1] >= 0`` (cli/commands/optimize.py:247)
    takes a duty of no time."""
    from mrclutch.cli.main import main

    assert main(["optimize", "--objective", "bandwidth", "--duty", "0.2:0"]) == 2
    err = capsys.readouterr().err
    assert "--duty '0.2:0': torque and seconds must be > 0" in err
    assert len(err.strip().splitlines()) == 1


def test_optimize_objective_bar_counts_60_generations_a_drum_count(monkeypatch):
    """``optimize --objective``: its progress bar counts 60 generations (the search's
    default maxiter) for each drum count searched: 120 for --drums 1,2. The bar is stopped
    at its start. The mutant ``61 * len(drums)`` (cli/commands/optimize.py:299) counts
    122."""
    from mrclutch.cli.commands import optimize as optimize_cmd
    from mrclutch.cli.main import main

    totals: list[int] = []

    def bar(total, *a, **k):
        totals.append(total)
        raise _Stop

    monkeypatch.setattr(optimize_cmd, "progress_bar", bar)
    with pytest.raises(_Stop):
        main(["optimize", "--objective", "bandwidth", "--drums", "1,2", "--nominal"])
    assert totals == [120]


def test_pareto_refuses_a_material_axis_that_is_no_part_and_list():
    """``pareto(materials=…)``: each entry must name a part (a SLOTS key) and give a
    non-empty list of material names; an unknown part, a bare string or an empty list is
    refused before any search, naming the entry. The mutant that joins the three tests with
    ``and`` (optimize/pareto.py:108) lets each through alone."""
    from geometry.validation import ParameterError

    base = design_preset("paper")
    for bad in ({"no_such_part": ["x"]}, {"fluid": "MRF-132DG"}, {"fluid": []}):
        slot = next(iter(bad))
        with pytest.raises(ParameterError, match=rf"^materials: '{slot}': give a part"):
            pareto(base, drum_counts=(2,), pop_size=4, members=1, materials=bad)


def test_the_motor_side_takes_the_mr_designs_lever():
    """``motor_transmission``: the paper's EM bench (170 mm lever) moved to the MR design's
    lever and workspace: on a 75 mm lever its lever is 75 mm, its k scaled by
    (170/75)² (``Transmission.with_lever``); on the 170 mm lever it is the bench itself.
    The mutant ``mr_tr.lever == EM_170.lever`` (at_hand.py:54) keeps the 170 mm lever."""
    from mrclutch.at_hand import motor_transmission
    from mrclutch.haptics.actuator import EM_170, MR_170, TABLE2_MR, actuator

    motor = actuator("maxon-136206")
    short = replace(MR_170, lever=0.075)
    em = motor_transmission(TABLE2_MR, short, motor)
    assert em.lever == 0.075 and em.workspace == short.workspace
    assert em.k == pytest.approx(EM_170.k * (0.170 / 0.075) ** 2, rel=1e-12)
    same = motor_transmission(TABLE2_MR, MR_170, motor)
    assert same.lever == EM_170.lever and same.k == EM_170.k


def test_vary_refuses_a_range_outside_the_lengths_valid_range_at_either_end():
    """``parse_bounds`` (``--vary NAME_mm=LO:HI``): a range reaching below the length's
    smallest valid value or above its largest is refused naming both (the optimiser would
    only see invalid rows); one inside is read in metres. For the gap: LO at half its
    smallest, HI at twice its largest, each refused alone. The mutant ``a / 0.001 < least``
    (optimize/box.py:71) never refuses the low end."""
    from geometry.params import LENGTH_RANGES
    from geometry.validation import ParameterError
    from mrclutch.optimize.box import parse_bounds

    least, most = next((lo, hi) for f, lo, hi, _ in LENGTH_RANGES if f == "gap")
    inside = (2 * least * 1e3, most * 1e3 / 2)
    assert parse_bounds([f"gap_mm={inside[0]!r}:{inside[1]!r}"]) == {
        "gap": pytest.approx((2 * least, most / 2), rel=1e-12)
    }
    for lo, hi in ((least * 1e3 / 2, inside[1]), (inside[0], 2 * most * 1e3)):
        with pytest.raises(ParameterError, match=r"gap_mm must stay within \["):
            parse_bounds([f"gap_mm={lo!r}:{hi!r}"])


def test_optimize_reads_its_mm_and_g_limits_into_si(monkeypatch):
    """``optimize``'s limits typed in the options' units reach the search in SI:
    --max-length-mm 40 and --max-diameter-mm 50 as 0.040 and 0.050 m, --max-mass-g 150 as
    0.150 kg, --duty 0.2:60 as 0.2 N·m held 60 s (the mutant ``duty_torque=duty[1]``,
    cli/commands/optimize.py:265, asks 60 N·m). The search is
    stopped at its start (its constraints recorded). The mutant
    ``args.max_length_mm / 0.001`` (cli/commands/optimize.py:259) limits the length to
    40 km."""
    from mrclutch.cli.commands import optimize as optimize_cmd
    from mrclutch.cli.main import main

    seen: list = []

    def stop(base, **k):
        seen.append(k["constraints"])
        raise _Stop

    monkeypatch.setattr(optimize_cmd, "optimize", stop)
    with pytest.raises(_Stop):
        main(["optimize", "--objective", "bandwidth", "--drums", "2", "--nominal",
              "--no-progress", "--max-length-mm", "40", "--max-diameter-mm", "50",
              "--max-mass-g", "150", "--duty", "0.2:60",
              "--max-residual-torque-mNm", "5"])  # fmt: skip
    assert seen[0].max_length == pytest.approx(0.040, rel=1e-12)
    assert seen[0].max_diameter == pytest.approx(0.050, rel=1e-12)
    assert seen[0].max_mass == pytest.approx(0.150, rel=1e-12)
    assert (seen[0].duty_torque, seen[0].duty_time) == (0.2, 60.0)
    assert seen[0].max_residual_torque == pytest.approx(0.005, rel=1e-12)  # :270, 5 mN·m


def test_the_pareto_table_on_the_fast_path_reads_back_to_its_json(monkeypatch, capsys):
    """``optimize`` (Pareto, --no-verify): each member's row of the printed table quotes its
    fast row of the JSON of the same (seeded) run: continuous torque above drag in mN·m
    (× 1e3), mass in g (× 1e3), each within half its last printed digit. (The round2
    mutant at cli/commands/optimize_pareto.py:205 sat in a branch no member reached — every
    member is judged, with --no-verify on the fast path — and the branch is removed.)"""
    import json

    from mrclutch.cli.commands import optimize_pareto as pareto_cmd
    from mrclutch.cli.main import main

    real = pareto_cmd.pareto
    monkeypatch.setattr(pareto_cmd, "pareto", lambda *a, **k: real(
        *a, **{**k, "pop_size": 16, "generations": 4, "members": 2}))  # fmt: skip
    argv = ["optimize", "--drums", "2", "--nominal", "--no-verify", "--no-progress"]
    assert main(argv) in (0, 3)
    text = capsys.readouterr().out.splitlines()
    assert main([*argv, "--json"]) in (0, 3)
    members = json.loads(capsys.readouterr().out)["members"]
    head = next(i for i, ln in enumerate(text) if ln.lstrip().startswith("# drums"))
    # member, drums, gap, wall, d_in, zone, BW Hz, backdr N, then these two
    assert text[head].split()[10:14] == ["cont", "mNm", "mass", "g"]
    cont, mass = 8, 9
    rows = [ln.split() for ln in text[head + 1 : head + 1 + len(members)]]
    assert members and [int(r[0]) for r in rows] == [m["member"] for m in members]
    for r, m in zip(rows, members, strict=True):
        assert float(r[cont]) == pytest.approx(m["fast"]["continuous_above_drag_N_m"] * 1e3,
                                               abs=0.05)  # fmt: skip
        assert float(r[mass]) == pytest.approx(m["fast"]["clutch_mass_kg"] * 1e3, abs=0.005)


def test_every_uncertainty_key_is_read_in_si_by_its_units_factor():
    """The `[uncertainty]` table's keys carry their unit: % spreads as fractions (20 % =
    0.20), mm as m (0.03 mm = 3e-5 m), ms as s, N·s/m and °C as they are. The mutant
    ``"runout_mm": (…, 0.0011, …)`` (uncertainty.py:216) reads 0.04 mm as 4.4e-5 m."""
    from mrclutch.uncertainty import uncertainty_from_mapping

    u = uncertainty_from_mapping({
        "viscosity_spread_pct": 20, "fluid_temperature_C": [20, 50], "gap_tolerance_mm": 0.03,
        "runout_mm": 0.04, "drum_thickness_tolerance_mm": 0.05, "delay_ms": [1, 3],
        "bench_damping_N_s_per_m": [0, 0.2], "yield_stress_spread_pct": 12, "bh_spread_pct": 6,
    })  # fmt: skip
    got = (u.viscosity_spread, *u.fluid_temperature, u.gap_tolerance, u.runout,
           u.drum_thickness_tolerance, *u.delay, *u.bench_damping, u.yield_stress_spread,
           u.bh_spread)  # fmt: skip
    want = (0.20, 20.0, 50.0, 3e-5, 4e-5, 5e-5, 1e-3, 3e-3, 0.0, 0.2, 0.12, 0.06)
    assert got == pytest.approx(want, rel=1e-12)


def test_a_measured_tables_source_is_kept():
    """`[measured]` ``source``: the bench's name, kept as typed (a string). The mutant
    ``key != "source"`` (uncertainty.py:309) refuses it or takes another key for it."""
    from geometry.validation import ParameterError
    from mrclutch.uncertainty import measured_from_mapping

    assert measured_from_mapping({"source": "bench 3, 2025"}).source == "bench 3, 2025"
    with pytest.raises(ParameterError, match=r"measured\.source = 3: must be a string"):
        measured_from_mapping({"source": 3})


def test_the_slowest_input_speed_accepted_is_1e_6_rad_s():
    """``Operating.input_speed`` ≥ MIN_INPUT_SPEED = 1e-6 rad/s (a turn in 73 days; nearer
    0 the drag underflows): 1e-6 is taken, 0.9e-6 refused naming input_speed. The mutant
    1.1e-6 (operating.py:24) refuses 1e-6."""
    from geometry.validation import ParameterError
    from mrclutch.operating import MIN_INPUT_SPEED, Operating

    assert MIN_INPUT_SPEED == 1e-6
    assert Operating(input_speed=1e-6).input_speed == 1e-6
    with pytest.raises(ParameterError, match="input_speed"):
        Operating(input_speed=0.9e-6)


def test_an_operating_key_without_its_unit_is_told_the_key_with_it():
    """A design file's ``operating.delay = 1`` or ``max_current = 5`` (no unit) is refused
    with the key it means: "unknown key; write delay_ms" (… max_current_A). The mutant
    ``k.rsplit("_", 2)`` (design.py:261) strips two words: no hint for max_current."""
    from geometry.validation import ParameterError
    from mrclutch.design import design_from_mapping

    with pytest.raises(ParameterError, match=r"operating\.delay: unknown key; write delay_ms"):
        design_from_mapping({"clutch": {"base": "paper"}, "operating": {"delay": 1}})
    with pytest.raises(ParameterError, match=r"max_current: unknown key; write max_current_A"):
        design_from_mapping({"clutch": {"base": "paper"}, "operating": {"max_current": 5}})


def test_a_value_the_design_refuses_is_told_with_the_files_key_first():
    """A file value in range for the reader but refused by the design's own check (a lever
    of 1e-9 mm = 1e-12 m) is told with the file's key and value first:
    "…transmission.lever_mm = 1e-09: lever = 1e-12 m: …". The mutant ``split(" ", 1)[1]``
    (design.py:261) looks the key up by the message's second word and says only
    "lever = 1e-12 m: …"."""
    from geometry.validation import ParameterError
    from mrclutch.design import design_from_mapping

    with pytest.raises(ParameterError) as err:
        design_from_mapping({"clutch": {"base": "paper"}, "transmission": {"lever_mm": 1e-9}})
    assert "transmission.lever_mm = 1e-09: lever = 1e-12 m" in str(err.value)


def test_the_mass_and_diameter_terms_are_the_value_over_its_limit_less_one():
    """``Constraints.terms``' mass and diameter terms are x/x_max − 1: 0 for the paper
    clutch with its own mass (diameter) as the limit, 1 with half of it, −0.5 with twice
    it. The mutant ``d/d_max − 2`` (optimize/limits.py:100) puts the diameter limit at
    twice the one typed."""
    from mrclutch.optimize.limits import Constraints, evaluate_rows

    base = design_preset("paper")
    c = base.clutch
    fields = {k: np.array([getattr(c, k)]) for k in ("gap", "drum_thickness", "n_drums")}
    rows = evaluate_rows(fields, base, Constraints().resolved(base))
    for key, col in (("mass", "clutch_mass_kg"), ("diameter", "diameter_m")):
        x = float(rows[col][0])
        for limit, term in ((x, 0.0), (x / 2, 1.0), (2 * x, -0.5)):
            cons = replace(Constraints(), **{f"max_{key}": limit}).resolved(base)
            assert float(cons.terms(rows)[key][0]) == pytest.approx(term, abs=1e-12)


def test_the_optimisers_rows_quote_evaluates_coil_power_and_drag_free_torque(capsys):
    """``evaluate_rows`` (the optimiser's limit columns) on the paper preset against
    ``evaluate --json`` of the same design: the coil power at the current limit (I² R at
    the coil's temperature, R = R20 (1 + α (T − 20))) and the continuous torque above drag
    (continuous torque − off-state drag), within the fast path's own agreement (1e-9). The
    mutants ``coil_temperature + 20.0`` (optimize/limits.py:168) and ``continuous + off``
    (:182) move each."""
    import json

    from mrclutch.cli.main import main
    from mrclutch.optimize.limits import CONTINUOUS, Constraints, evaluate_rows

    assert main(["evaluate", "--preset", "paper", "--json"]) == 0
    cl = json.loads(capsys.readouterr().out)["clutch"]
    base = design_preset("paper")
    c = base.clutch
    fields = {k: np.array([getattr(c, k)]) for k in ("gap", "drum_thickness", "n_drums")}
    rows = evaluate_rows(fields, base, Constraints().resolved(base))
    assert rows["coil_power_W"][0] == pytest.approx(cl["coil_power_W"], rel=1e-9)
    above = cl["continuous_torque_N_m"] - cl["off_state_torque_N_m"]
    assert rows[CONTINUOUS][0] == pytest.approx(above, rel=1e-9)


def test_a_member_touches_a_range_edge_within_one_percent_of_the_range():
    """``range_edges``: a member touches an edge of its search range within EDGE = 1 % of
    the range's width. A gap range 0.2–0.6 mm (width 0.4 mm, so within 4 µm): 0.203 mm
    touches the lower edge, 0.597 mm the upper one, 0.207, 0.4 and 0.593 mm none. The
    mutant ``EDGE * (hi + lo)`` (optimize/box.py:91) takes 1 % of 0.8 mm = 8 µm and flags
    0.207 and 0.593 mm."""
    from mrclutch.optimize.box import EDGE, range_edges

    assert EDGE == 0.01
    base = design_preset("paper")
    box, source = {"gap": (0.2e-3, 0.6e-3)}, {"gap": "range"}

    def edges(gap: float) -> tuple[str, ...]:
        d = replace(base, clutch=replace(base.clutch, gap=gap))
        return range_edges(d, box, source, (2,))

    assert edges(0.203e-3) == ("gap at the lower edge of --vary (0.2 mm): widen the range or "
                               "relax the process limit",)  # fmt: skip
    assert edges(0.597e-3) == ("gap at the upper edge of --vary (0.6 mm): widen the range",)
    assert edges(0.207e-3) == edges(0.593e-3) == edges(0.4e-3) == ()


@pytest.mark.parametrize(("lo", "hi", "ok"), [(-40.0, 130.0, True), (-40.01, 20.0, False),
                                               (20.0, 130.01, False)])  # fmt: skip
def test_a_fluid_temperature_range_may_reach_the_fluids_own_limits(lo, hi, ok):
    """MRF-132DG's rated range is −40…130 °C ([lord-mrf132dg]): a `[uncertainty]` range that
    reaches exactly its ends is the fluid's own and is accepted; a hundredth of a degree
    past either end is refused, naming the fluid's range. Mutants ``lo <= flo`` and
    ``hi >= fhi`` (uncertainty.py:376) refuse the rated ends."""
    from geometry.validation import ParameterError
    from mrclutch.uncertainty import Uncertainty, check_consistent

    d = design_preset("paper")
    d = replace(d, uncertainty=Uncertainty(fluid_temperature=(lo, hi)))
    if ok:
        check_consistent(d)
    else:
        with pytest.raises(ParameterError, match="must lie in the fluid's range"):
            check_consistent(d)


def test_headline_names_each_verdict_by_how_it_holds():
    """``robust.headline`` on a hand-made read-out: stability holds over every value of the
    ranges, passivity depends on b1 (threshold 0.4 N·s/m inside its range 0.1–1). The
    sentence says "stable for every value", never "passive for every value", and gives
    passivity's condition with its threshold. Mutant ``holds != "always"`` (robust.py:272)
    swaps which verdict is called unconditional."""
    from mrclutch.robust import headline

    band = {"worst": 40.0, "best": 400.0}
    b1 = {"range": (0.1, 1.0), "value": 0.4, "sense": "≥"}
    r = {"K_N_per_m": 100.0, "max_stable_K_N_per_m": band, "max_passive_K_N_per_m": band,
         "verdicts": {"stable": {"holds": "always", "nominal": True, "thresholds": {}},
                      "passive": {"holds": "depends", "nominal": False,
                                  "thresholds": {"b1": b1}}}}  # fmt: skip
    text = headline(r)
    assert text.startswith("Robust verdict at K = 100 N/m: stable for every value of the "
                           "ranges; not passive at nominal values, passive only if b1 ≥ "
                           "0.4 N·s/m (its range 0.1–1 N·s/m)"), text  # fmt: skip
    assert "passive for every value" not in text and "unstable" not in text
