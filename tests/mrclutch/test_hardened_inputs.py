"""Issue 44: the inputs added last round hardened like the old ones — a test per class:
material file kinds, bench extremes, inconsistent ranges, non-finite readouts, long-job
estimates. Every refusal is one line on stderr, exit 2, no traceback."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from geometry.reading import MAX_INPUT_BYTES, check_regular, read_json, read_toml
from geometry.validation import ParameterError
from mrclutch.cli.main import main

FLUID = Path(__file__).resolve().parents[2] / "geometry" / "data" / "materials" / "mrf_132dg.toml"


def _fails(capsys, argv: list[str], fragment: str) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert fragment in err, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    return err


def _fluid_design(tmp_path: Path, fluid: Path | str) -> Path:
    d = tmp_path / "d.toml"
    d.write_text(f'[clutch]\nbase = "paper"\n[materials]\nfluid_file = "{fluid}"\n')
    return d


def _fluid_text(name: str = "my_fluid") -> str:
    return FLUID.read_text().replace('name = "mrf_132dg"', f'name = "{name}"')


# ---- material file kinds ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kind", "fragment"),
    [
        ("random", "not UTF-8 text"),
        ("utf16", "saved as UTF-16? save it as UTF-8"),
        ("deep", "nested too deeply to parse"),
        ("fifo", "is a FIFO (named pipe), not a regular file"),
        ("zero", "/dev/zero: is a character device, not a regular file"),
        ("dir", "is a directory"),
        ("huge", "fluid files are read up to"),
    ],
)
def test_a_hostile_material_file_is_one_line_naming_it(tmp_path, capsys, kind, fragment):
    """Each kind once ended in a traceback (UnicodeDecodeError, RecursionError), a hang
    (FIFO) or a memory kill (/dev/zero); now 'fluid file PATH: why', exit 2."""
    f = tmp_path / "f.toml"
    if kind == "random":
        f.write_bytes(bytes([0xDE, 0xAD, 0xBE, 0xEF, 0xFF, 0x00]) * 50)
    elif kind == "utf16":
        f.write_bytes(_fluid_text().encode("utf-16"))
    elif kind == "deep":
        f.write_text("a = " + "[" * 100_000 + "]" * 100_000 + "\n")
    elif kind == "fifo":
        os.mkfifo(f)
    elif kind == "zero":
        f = Path("/dev/zero")
    elif kind == "dir":
        f = tmp_path
    else:
        with open(f, "wb") as h:  # sparse: 1 byte over the cap
            h.truncate(MAX_INPUT_BYTES + 1)
    err = _fails(capsys, ["evaluate", str(_fluid_design(tmp_path, f))], fragment)
    assert "fluid file" in err


@pytest.mark.parametrize(
    ("field", "value", "fragment"),
    [
        ("viscosity = 0.112", "viscosity = 1e300",
         "viscosity = 1e+300 Pa·s: must be in [0.001, 10]"),
        ("viscosity = 0.112", "viscosity = 0.0", "viscosity = 0 Pa·s: must be in"),
        ("density = 3050.0", "density = 1e308", "density = 1e+308: must be in [1, 30000]"),
        ("carrier_c = 1.0", "carrier_c = 1e9", "carrier_c = 1e+09: must be in [0.1, 10]"),
        ("temperature_range = [-40.0, 130.0]", "temperature_range = [-400.0, 130.0]",
         "temperature_range: -400, 130 °C: must be in [-273.15, 1000]"),
        ("carrier_points = [[40.0, 19.0e-6], [100.0, 4.1e-6]]",
         "carrier_points = [[40.0, 19.0], [100.0, 4.1]]", "kinematic viscosities 19, 4.1"),
    ],
)  # fmt: skip
def test_a_material_property_outside_its_physical_range_is_refused(
    tmp_path, capsys, field, value, fragment
):
    f = tmp_path / "f.toml"
    text = _fluid_text(f"fluid_{abs(hash(value)) % 10**6}")
    assert field in text
    f.write_text(text.replace(field, value))
    _fails(capsys, ["evaluate", str(_fluid_design(tmp_path, f))], fragment)


def test_a_long_bh_table_is_refused(tmp_path, capsys):
    f = tmp_path / "f.toml"
    b = ", ".join(str(0.001 * (i + 1)) for i in range(1001))
    text = _fluid_text("long_bh").split("b = [")[0] + f"b = [{b}]\nh = [{b}]\n"
    f.write_text(text)
    _fails(
        capsys, ["evaluate", str(_fluid_design(tmp_path, f))], "[bh].b: 1001 points: at most 1000"
    )


def test_the_reader_refuses_by_name_and_reads_a_good_file(tmp_path):
    """The one reader (geometry.reading) on a regular file, a FIFO, a device, JSON with NaN
    and a JSON nested past MAX_DEPTH."""
    good = tmp_path / "g.toml"
    good.write_text('a = 1\n[b]\nc = "x"\n')
    assert read_toml(good, "x") == {"a": 1, "b": {"c": "x"}}
    fifo = tmp_path / "p"
    os.mkfifo(fifo)
    with pytest.raises(ParameterError, match=r"CAD file .*p: is a FIFO"):
        check_regular(fifo, "CAD file")
    with pytest.raises(ParameterError, match="character device"):
        check_regular("/dev/null", "CAD file")
    j = tmp_path / "s.json"
    j.write_text('{"solids": [{"density_kg_m3": NaN}]}')
    with pytest.raises(ParameterError, match="NaN is not a number JSON allows"):
        read_json(j, "materials sidecar")
    j.write_text("[" * 20 + "]" * 20)
    with pytest.raises(ParameterError, match="nested more than 8 levels"):
        read_json(j, "materials sidecar")


def test_a_sidecar_density_of_1e308_is_refused_not_printed_as_inf(tmp_path):
    from geometry.export import read_materials, sidecar_path

    step = tmp_path / "c.step"
    side = sidecar_path(step)
    side.write_text(json.dumps({"solids": [{"name": "hub", "density_kg_m3": 1e308,
                                            "volume_mm3": 10.0}]}))  # fmt: skip
    with pytest.raises(ParameterError, match=r"density_kg_m3 = 1e\+308: must be in \[1, 30000\]"):
        read_materials(step)
    side.unlink()
    os.mkfifo(side)  # a FIFO sidecar: refused by name, not read (it would hang)
    with pytest.raises(ParameterError, match="is a FIFO"):
        read_materials(step)


def test_density_option_of_1e308_is_refused(tmp_path, capsys):
    stl = tmp_path / "p.stl"
    stl.write_text("solid p\nendsolid p\n")
    _fails(capsys, ["inertia", str(stl), "--density", "1e308"],
           "--density = 1e+308 kg/m³: must be in [1, 30000] kg/m³")  # fmt: skip


# ---- bench extremes -----------------------------------------------------------------------

BENCH = '[clutch]\nbase = "paper"\n[measured]\nuse_in_model = true\n'


@pytest.mark.parametrize(
    ("table", "fragment"),
    [
        ("m1_g = 1e-300", "measured.m1_g = 1e-300: m1 = 1e-303 kg: must be in [1e-06, 100] kg"),
        ("m1_g = 1e300", "m1 = 1e+297 kg: must be in [1e-06, 100] kg"),
        ("b1_N_s_per_m = 5e-324", "b1 = 4.94066e-324 N·s/m: must be in [1e-06, 10000]"),
        ("b1_N_s_per_m = 1e300", "b1 = 1e+300 N·s/m: must be in [1e-06, 10000]"),
        ("torque = [{current_A = 7.0, torque_N_m = 1e300}]",
         "torque[0].torque = 1e+300 N·m: must be in (0, 1000] N·m"),
        ("torque = [{current_A = 7.0, torque_N_m = inf}]", "torque[0].torque = inf N·m"),
        ("torque = [{current_A = nan, torque_N_m = 0.4}]", "torque[0].current = nan A"),
        ("torque = [{current_A = 7.0, torque_N_m = 0.4}, {current_A = 7.0, torque_N_m = 0.8}]",
         "torque[1].current = 7 A: torque[0] is at the same current (0.4 and 0.8 N·m)"),
        ("off_state_torque_mN_m = 1e300", "off_state_torque = 1e+297 N·m: must be in (0, 1000]"),
    ],
)  # fmt: skip
def test_bench_extremes_are_refused_before_any_model_runs(tmp_path, capsys, table, fragment):
    """Each once ran until killed for memory (m1, b1 tiny or huge), gave +inf % and NaN
    (b1 = 5e-324, a 1e300 N·m torque), used one of two torques at one current silently, or
    ended in LinAlgError (a non-finite value)."""
    f = tmp_path / "b.toml"
    f.write_text(BENCH + table + "\n")
    _fails(capsys, ["evaluate", str(f), "--fidelity", "fast"], fragment)


def test_the_bandwidth_search_is_bounded_in_memory(monkeypatch):
    """The guard behind the input bounds: a design whose live intervals pass MAX_BRACKETS is
    left unresolved (NaN) instead of bisected on (a 1e-300 kg m1 once doubled its intervals
    until killed). With the cap at 0 every design that needs bisection is NaN and no other
    answer changes: the guard drops work, it never returns a wrong crossing."""
    import numpy as np

    from mrclutch.haptics import bandwidth as model
    from mrclutch.haptics.actuator import HapticParams

    rng = np.random.default_rng(0)
    n = 200
    p = HapticParams(m1=10 ** rng.uniform(-4, -1, n), b1=10 ** rng.uniform(-2, 2, n),
                     k=10 ** rng.uniform(2, 5, n), b=10 ** rng.uniform(-1, 1, n), m2=0.014,
                     delay=10 ** rng.uniform(-4, -2, n))  # fmt: skip
    free = model.bandwidth(p, 500.0)
    assert np.all(np.isfinite(free))
    monkeypatch.setattr(model, "MAX_BRACKETS", 0)
    capped = model.bandwidth(p, 500.0)
    assert 0 < np.isnan(capped).sum() < n
    assert np.all(np.isnan(capped) | (capped == free))


# ---- inconsistent ranges ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("table", "fragment"),
    [
        ("[uncertainty]\nrunout_mm = 5",
         "uncertainty.runout_mm + gap_tolerance_mm = 5 + 0.02 mm: must be less than the gap "
         "(0.7 mm)"),
        ("[uncertainty]\ngap_tolerance_mm = 5", "= 0.02 + 5 mm: must be less than the gap"),
        ("[uncertainty]\ndrum_thickness_tolerance_mm = 5", "must be less than the drum wall"),
        ("[uncertainty]\nfluid_temperature_C = [60, 80]",
         "must contain the operating temperature (20 °C), where the nominal verdict is "
         "computed; widen it to [20, 80]"),
        ("[uncertainty]\nfluid_temperature_C = [20, 500]", "must lie in the fluid's range"),
        ("[uncertainty]\ndelay_ms = [3, 4]", "must contain the typed delay (1 ms)"),
        ("[process]\nruntout_mm = 1", "process.runtout_mm: unknown key"),
        ("[process]\nrunout_mm = 0.5\ntolerance_mm = 0.5", "process.runout_mm + process.tol"),
    ],
)  # fmt: skip
def test_inconsistent_ranges_are_refused_naming_keys_and_rule(tmp_path, capsys, table, fragment):
    """A runout beyond the gap (once a 2.3e11 N·s/m "range"), a tolerance that voided every
    corner, a range leaving out its nominal (a robust verdict contradicting the nominal)."""
    f = tmp_path / "u.toml"
    f.write_text(f'[clutch]\nbase = "paper"\ngap_mm = 0.7\n{table}\n')
    _fails(capsys, ["evaluate", str(f), "--fidelity", "fast"], fragment)


def test_a_range_with_its_nominal_is_accepted():
    """The boundary: [20, 40] °C contains 20 °C, runout + tolerance 0.04 mm < 0.7 mm."""
    from mrclutch.design import design_from_mapping

    unc = {"fluid_temperature_C": [20, 40], "delay_ms": [1, 2], "runout_mm": 0.02,
           "gap_tolerance_mm": 0.02}  # fmt: skip
    d = design_from_mapping({"clutch": {"base": "paper", "gap_mm": 0.7}, "uncertainty": unc})
    assert d.uncertainty.fluid_temperature == (20.0, 40.0)
    assert math.isclose(d.uncertainty.runout + d.uncertainty.gap_tolerance, 0.04e-3)


# ---- non-finite readouts ------------------------------------------------------------------


def _walk(v, path=""):
    if isinstance(v, dict):
        for k, x in v.items():
            yield from _walk(x, f"{path}/{k}")
    elif isinstance(v, list):
        for i, x in enumerate(v):
            yield from _walk(x, f"{path}[{i}]")
    else:
        yield path, v


def test_a_loop_the_stability_scan_cannot_resolve_prints_no_nan(tmp_path, capsys):
    """At the edges of the accepted bench ranges (m1 = 1 mg, b1 = 10⁴ N·s/m: a mode at
    b1/m1 = 10¹⁰ rad/s behind the 1 ms delay) the scan would need more than MAX_GRID
    frequencies: the largest stable K is unknown. The text says so with "—" in every table
    (the robust block, the torque response's line), never "nan"; the verdict says the
    stability is unknown (not "unstable", nor a pass); the JSON explains the robust
    block's nulls with the same reason as haptic's."""
    import re

    f = tmp_path / "x.toml"
    f.write_text('[clutch]\nbase = "paper"\n[measured]\nuse_in_model = true\n'
                 "m1_g = 1e-3\nb1_N_s_per_m = 1e4\n")  # fmt: skip
    assert main(["evaluate", str(f), "--fidelity", "fast"]) == 0
    text = capsys.readouterr().out
    assert not re.search(r"\bnan\b", text), [ln for ln in text.splitlines() if "nan" in ln]
    rows = [ln for ln in text.splitlines() if ln.strip().startswith("largest stable K (N/m)")]
    assert any(ln.count("—") == 3 for ln in rows), rows  # the robust block: nominal, worst, best
    verdict = next(ln for ln in text.splitlines() if ln.startswith("VERDICT:"))
    assert "stability unknown" in verdict and "unstable" not in verdict, verdict
    assert not verdict.startswith("VERDICT: PASS"), verdict  # unknown is not taken as stable
    assert main(["evaluate", str(f), "--fidelity", "fast", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    why = data["nulls"]["haptic/max_stable_K_N_per_m"]
    assert why.startswith("unknown: the stability scan cannot resolve")
    assert all(data["nulls"][f"robust/max_stable_K_N_per_m/{end}"] == why
               for end in ("nominal", "worst", "best"))  # fmt: skip
    head = data["robust"]["headline"]
    assert "stability unknown" in head and "unstable" not in head and "nan" not in head, head


@pytest.mark.parametrize(
    "extra",
    ["",
     "[measured]\nuse_in_model = true\nm1_g = 1e-3\nb1_N_s_per_m = 1e4\n",
     "[measured]\nuse_in_model = true\ntorque = [{current_A = 7.0, torque_N_m = 1000}]\n"],
)  # fmt: skip
def test_accepted_extremes_print_no_nan_and_explain_every_null(tmp_path, capsys, extra):
    """At the edges of the accepted bench ranges the JSON has no NaN/inf and every null
    has its reason (``nulls`` or a ``note``), as the fuzzer checks."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "fuzz_cli", Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_cli.py"
    )
    fuzz = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fuzz)
    f = tmp_path / "x.toml"
    f.write_text(f'[clutch]\nbase = "paper"\n{extra}')
    assert main(["evaluate", str(f), "--fidelity", "fast", "--json"]) == 0
    text = capsys.readouterr().out
    data = json.loads(text)  # JSON has no NaN: json.loads would accept it, so check the text
    assert "NaN" not in text and "Infinity" not in text
    assert all(not (isinstance(v, float) and not math.isfinite(v)) for _, v in _walk(data))
    assert fuzz.nulls_unexplained(data) == []


# ---- long-job estimates -------------------------------------------------------------------


def test_long_jobs_say_their_estimate_and_the_longest_ask_for_yes(capsys):
    from mrclutch.cli.errors import CLIError
    from mrclutch.cli.longjobs import ANNOUNCE_AFTER_S, ASK_AFTER_S, announce

    assert not announce("x", "5 things", ANNOUNCE_AFTER_S / 2, "a rate", yes=False)
    assert capsys.readouterr().err == ""
    assert announce("x", "5 things", 45.0, "a rate", yes=False)
    assert "mrclutch x: 5 things, about 45 s (a rate); going on" in capsys.readouterr().err
    with pytest.raises(CLIError, match=r"5 things, about 20 min \(a rate\), more than 10 min; "
                                       "add --yes"):  # fmt: skip
        announce("x", "5 things", 1200.0, "a rate", yes=False)
    assert announce("x", "5 things", 1200.0, "a rate", yes=True)
    assert ASK_AFTER_S == 600.0


def test_fem_torque_over_thousands_of_currents_asks_for_yes(capsys):
    """10 000 FEM solves (~hours at the FEM's measured rate per node) are refused without
    --yes before any solve starts, the estimate in the message."""
    _fails(capsys, ["torque", "--method", "fem", "--current", "0:1:0.0001", "--ignore-limit"],
           "FEM solves at")  # fmt: skip


def test_a_sweep_of_many_tiny_chunks_says_its_estimate(tmp_path):
    """Chunks of one design: the per-chunk write is in the estimate, which the CLI says
    (announce) when above 30 s; 101 chunks are timed even under 1000 designs."""
    from mrclutch.cli.commands.sweep import _say_estimate
    from mrclutch.design import design_preset
    from mrclutch.pipeline import BatchEvaluator
    from mrclutch.sweep import load_spec

    spec = tmp_path / "s.toml"
    spec.write_text('[sweep]\nmode = "grid"\nchunk_size = 1\n[parameters]\n'
                    "gap_mm = {min = 0.5, max = 0.7, count = 101}\n")  # fmt: skip
    sp, _ = load_spec(spec)
    assert sp.n_chunks == 101
    seconds = _say_estimate(sp, BatchEvaluator(design_preset("paper")), 1, True,
                            str(tmp_path / "r.csv"))  # fmt: skip
    assert seconds is not None and seconds > 0 and math.isfinite(seconds)
