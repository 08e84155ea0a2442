"""Fuzz the command line in process: ``mrclutch.cli.main.main([...])`` on random inputs.

    python benchmarks/fuzz_cli.py [--n 10000] [--seed 0] [--workers 2] [--mem-gb 4]
                                  [--records FILE] [--classes material,sections]

``--records`` appends each input's record as it ends (a run that is stopped early still
says how many inputs it ran and what they found); the summary prints the seconds per input
of each class. Evaluations of the ``valid`` and ``extremes`` classes run with
``--no-uncertainty`` except in a fraction ``UNCERTAIN_FRACTION`` (1/4) of draws: the
uncertain path costs about twice the nominal one and its own inputs are the ``sections``
class, which always runs it.

Input classes (``CLASSES``, drawn with their weights; each input's class is in its record):

* ``extremes``: a design file whose values are drawn from extremes (0, negative, NaN, ±inf,
  1e±300, huge integers, fractions for integer fields, strings, booleans) run through a
  fast command (``evaluate --fidelity fast``, ``torque``, rarely ``scale``: seconds), or
  random flags and values for the analytic commands;
* ``structure``: design files whose *structure* is wrong (issue 32): ``base`` as a list or
  a table, a section as a string or an array, arrays nested past the parser, names as
  tables, control characters and stray bytes, empty or truncated TOML;
* ``files``: a FIFO, a device (/dev/zero, /dev/null), a directory, a file over the size
  limit given as the design file or the sweep spec;
* ``options``: options that only the edge may refuse: ``optimize --vary`` with inf/NaN/
  reversed bounds, ``--seed`` out of 32 bits, ``sweep --connect-timeout`` non-finite,
  ``field --size-mm`` / ``--verify-fem-size-mm`` too small for memory, ``--accuracy``;
* ``valid``: a valid design (a few keys drawn inside their ranges: 1–20 drums, large
  diameters, extreme but accepted operating points and transmissions) through
  ``evaluate --json``: it must answer (exit 0) and every null must have its reason
  under ``nulls`` (or a ``note`` beside it); its design file must also round-trip
  (``design_to_toml`` → ``load_design``);
* ``spec``: a tiny sweep spec, fuzzed, with ``--out`` in a folder of its own: a refusal
  leaves no file there, an answer leaves a complete one (a row per design).

Counted, per input:

* ``traceback``: an exception escaping ``main`` (anything but SystemExit 0/2, or a return
  code other than 0, 2, 3 and 130);
* ``refused``: a valid design (``load_design`` accepts it) refused (exit 2), a design
  file that does not load back to the same design, or a plausible fluid file (the
  ``material`` class's accepted branch, ``PLAUSIBLE_FRACTION`` of its draws: a library
  fluid with fields moved inside their physical ranges) refused;
* ``nan``: ``nan`` printed (text or JSON) without any ``note`` in the output;
* ``null``: a null in ``evaluate --json`` (or ``torque --json`` of the ``material`` class)
  without a reason (``nulls`` or a ``note``);
* ``partial``: a file left behind by a refused command, or an incomplete sweep file;
* ``memory``: MemoryError, or the worker killed; each worker runs under
  ``resource.setrlimit(RLIMIT_AS)`` so a blowup fails fast instead of swapping;
* ``slow``: an input that took more than ``--timeout`` seconds (SIGALRM): a hang.

Workers are child processes (this script with ``--child``); the parent restarts a worker
after a crash at the next input and prints the counts and a few examples of each class.
``run_input`` (one input, in process) is what tests/mrclutch/test_fuzz_sample.py runs on a
small sample.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import random
import re
import resource
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]

#: Values a fuzzed field or flag takes (strings as they appear in TOML / on the command line).
EXTREMES = ["0", "-1", "-0.0", "nan", "inf", "-inf", "1e300", "-1e300", "1e-300", "1e-18",
            "1e18", "100000000000000000000000000000", "2.5", "0.5", "1", "7", "1e6", "-1e6",
            "3.0e-4", '"x"', "true", "[1, 2]", "{a = 1}"]  # fmt: skip
ARG_EXTREMES = ["0", "-1", "nan", "inf", "-inf", "1e300", "1e-300", "1e-18", "1e18", "2.5",
                "x", "", "1e999", "-0", "3", "0.001", "1000000"]  # fmt: skip
SECTIONS = ("clutch", "operating", "transmission", "amplifier", "support", "laminations")
COMMANDS = {  # command -> its flags that take a value (fuzzed) and its switches
    "evaluate": (["--accuracy"], ["--json"], ["--fidelity", "fast"]),
    "haptic": (
        ["--lever-mm", "--gearing", "--stiffness", "--delay-ms", "--workspace-mm"],
        ["--json"],
        [],
    ),
    "compare": (["--stiffness", "--delay-ms", "--workspace-mm"], ["--json"], []),
    "torque": (
        ["--current", "--speed-rpm", "--fluid-temperature-C", "--for"],
        ["--json", "--ignore-limit"],
        ["--method", "circuit"],
    ),
    "scale": (["--factor"], ["--json"], []),
}
DESIGN_COMMANDS = ("evaluate", "torque", "scale")
OK_CODES = {0, 2, 3, 130}
NAN = re.compile(r"(?<![A-Za-z_])nan(?![A-Za-z_])", re.I)


def preset_keys() -> dict[str, list[str]]:
    """Every key of the paper preset's design file, by section."""
    import tomllib

    from mrclutch.design import design_preset, design_to_toml

    doc = tomllib.loads(design_to_toml(design_preset("paper")))
    return {s: list(v) for s, v in doc.items() if isinstance(v, dict)}


def make_input(rng: random.Random, keys: dict[str, list[str]], folder: Path, k: int) -> list[str]:
    """One fuzzed argv (writes its design file into ``folder`` when it has one)."""
    cmd = rng.choice(DESIGN_COMMANDS if rng.random() < 0.6 else tuple(COMMANDS))
    valued, switches, fixed = COMMANDS[cmd]
    argv = [cmd, *fixed]
    if cmd in DESIGN_COMMANDS and rng.random() < 0.85:
        lines: dict[str, list[str]] = {}
        for _ in range(rng.randint(1, 4)):
            section = rng.choice([s for s in SECTIONS if s in keys])
            key = rng.choice(keys[section] + ["unknown_key_mm"])
            if rng.random() < 0.5:
                value = rng.choice(EXTREMES)
            else:  # a plausible number, scaled by a random factor
                value = repr(rng.choice([1.0, -1.0]) * 10 ** rng.uniform(-6, 6))
            lines.setdefault(section, []).append(f"{key} = {value}")
        text = "".join(
            f"[{s}]\n" + ('base = "paper"\n' if s == "clutch" else "") + "\n".join(v) + "\n"
            for s, v in lines.items()
        )
        path = folder / f"d{k}.toml"
        path.write_text(text)
        argv.append(str(path))
    elif rng.random() < 0.2:
        argv += ["--preset", rng.choice(["paper", "paper-holes", "nope", ""])]
    for flag in rng.sample(valued, rng.randint(0, len(valued))):
        argv += [flag, rng.choice(ARG_EXTREMES)]
    argv += [s for s in switches if rng.random() < 0.5]
    if cmd == "evaluate" and rng.random() >= UNCERTAIN_FRACTION:
        argv.append("--no-uncertainty")
    if rng.random() < 0.03:
        argv.append(rng.choice(["--bogus", "-x", "--json=1", "extra"]))
    return argv


#: Input classes and their weights (most inputs are refused in milliseconds; ``valid``
#: evaluates a design, ~0.3 s).
CLASSES = {"extremes": 0.10, "structure": 0.26, "files": 0.05, "options": 0.17,
           "valid": 0.10, "spec": 0.12, "material": 0.10, "sections": 0.10}  # fmt: skip

#: Wrong structures for a design file: (section or key, TOML text) pieces.
BAD_VALUES = ['["paper"]', '{a = 1}', "[[1], [2]]", "1", "true", '"x"', "1979-05-27",
              "[" * 40 + "]" * 40, '"\\u0000"', '"a\\nb"', "{}", "[]", "-inf", "nan"]  # fmt: skip
SECTION_NAMES = ("clutch", "operating", "transmission", "support", "amplifier",
                 "laminations", "name", "sweep", "parameters")  # fmt: skip


def make_structure(rng: random.Random, keys: dict[str, list[str]], folder: Path, k: int
                   ) -> list[str]:  # fmt: skip
    """A design file with a structural mismatch, through evaluate or torque."""
    kind = rng.randrange(7)
    if kind == 0:  # base of the wrong type
        text = f"[clutch]\nbase = {rng.choice(BAD_VALUES)}\n"
    elif kind == 1:  # a section given as a value
        sec = rng.choice(SECTION_NAMES)
        text = f'{sec} = {rng.choice(BAD_VALUES)}\n[clutch]\nbase = "paper"\n'
        if sec == "clutch":
            text = f"clutch = {rng.choice(BAD_VALUES)}\n"
    elif kind == 2:  # deep nesting (past the parser or past MAX_DEPTH)
        depth = rng.choice([9, 20, 500, 5000, 100000])
        key = rng.choice(keys["clutch"])
        text = f'[clutch]\nbase = "paper"\n{key} = ' + "[" * depth + "1" + "]" * depth + "\n"
    elif kind == 3:  # a key's value of the wrong shape
        sec = rng.choice([s for s in SECTIONS if s in keys])
        key = rng.choice(keys[sec])
        text = (
            ('[clutch]\nbase = "paper"\n' if sec != "clutch" else "")
            + f"[{sec}]\n"
            + ('base = "paper"\n' if sec == "clutch" else "")
            + f"{key} = {rng.choice(BAD_VALUES)}\n"
        )
    elif kind == 4:  # control characters, stray bytes, names
        junk = "".join(chr(rng.randrange(0, 0x80)) for _ in range(rng.randint(1, 12)))
        text = (
            f'name = {json.dumps(junk)}\n[clutch]\nbase = "paper"\n'
            if rng.random() < 0.5
            else f'[clutch]\nbase = "paper"\n{junk}\n'
        )
    elif kind == 5:  # truncated or empty
        full = '[clutch]\nbase = "paper"\ngap_mm = 0.5\n[operating]\nmax_current_A = 5\n'
        text = full[: rng.randrange(len(full))]
    else:  # tables nested as sections
        text = '[clutch]\nbase = "paper"\n[clutch.sub]\na = 1\n[operating.x.y]\nz = 2\n'
    path = folder / f"s{k}.toml"
    if rng.random() < 0.1:
        path.write_bytes(text.encode() + bytes(rng.randrange(256) for _ in range(8)))
    else:
        path.write_text(text)
    return [rng.choice(["evaluate", "torque", "evaluate"]), str(path)]


def make_files(rng: random.Random, folder: Path, k: int) -> list[str]:
    """A design file or spec that is not a small regular file."""
    kind = rng.randrange(5)
    if kind == 0:
        path = folder / f"fifo{k}"
        os.mkfifo(path)
    elif kind == 1:
        path = Path(rng.choice(["/dev/zero", "/dev/null", "/dev/urandom"]))
    elif kind == 2:
        path = folder / f"dir{k}.toml"
        path.mkdir()
    elif kind == 3:
        path = folder / f"big{k}.toml"
        with open(path, "wb") as f:  # sparse: the size without the bytes
            f.truncate((1 << 20) + rng.randrange(1, 1 << 30))
    else:
        path = folder / f"missing{k}.toml"
    if rng.random() < 0.3:
        return ["sweep", str(path), "--out", str(folder / f"out{k}" / "r.csv")]
    return [rng.choice(["evaluate", "torque", "scale"]), str(path)]


def make_options(rng: random.Random, folder: Path, k: int) -> list[str]:
    """Options only the edge may refuse (none of them may start long work)."""
    bad = ["inf", "-inf", "nan", "-1", "0", "1e999", "1e-300", "x", ""]
    kind = rng.randrange(6)
    if kind == 0:
        name = rng.choice(["gap_mm", "zone_length_mm", "n_drums", "bogus_mm", "gap"])
        lo, hi = rng.choice([*bad, "0.2", "1"]), rng.choice([*bad, "0.1"])
        return ["optimize", "--vary", f"{name}={lo}:{hi}", "--no-verify"]
    if kind == 1:
        seed = rng.choice(["-1", str(2**32), str(10**23), "1.5", "x", "-99999999999"])
        return ["optimize", "--seed", seed, "--no-verify"]
    spec = folder / f"o{k}.toml"
    spec.write_text('[sweep]\nmode = "grid"\n[parameters]\n'
                    "gap_mm = {min = 0.5, max = 0.7, count = 2}\n")  # fmt: skip
    out = str(folder / f"out{k}" / "r.csv")
    if kind == 2:
        return ["sweep", str(spec), "--out", out, "--scheduler", "tcp://127.0.0.1:9",
                "--connect-timeout", rng.choice(["inf", "nan", "-1", "0", "1e9"])]  # fmt: skip
    if kind == 3:
        size = rng.choice(["0.02", "0.021", "0.001", "1e-300", "nan", "inf", "-1", "6", "0"])
        return ["field", "--size-mm", size, "--plot", str(folder / f"out{k}" / "f.png")]
    if kind == 4:
        size = rng.choice(["0.02", "0.021", "0.01", "nan", "inf", "6", "-1"])
        return ["sweep", str(spec), "--out", out, "--verify-top", rng.choice(["1", "0", "-3"]),
                "--verify-fem-size-mm", size]  # fmt: skip
    return ["evaluate", "--accuracy", rng.choice(["0", "1", "-1", "nan", "inf", "2", "x"])]


#: Keys a valid design draws from, each with values its validation accepts.
VALID_KEYS = {
    "clutch": {"n_drums": [str(n) for n in range(1, 21)],
               "gap_mm": ["0.1", "0.3", "1", "2"], "drum_inner_diameter_mm": ["6", "30", "250"],
               "zone_length_mm": ["2", "6", "20"], "drum_thickness_mm": ["0.1", "0.3", "1"],
               "coil_turns": ["20", "140", "600"], "wire_diameter_mm": ["0.1", "0.321", "1"]},
    "operating": {"input_speed_rpm": ["0.001", "1", "530", "10000", "50000"],
                  "max_current_A": ["0.01", "1", "7", "50", "1000"],
                  "delay_ms": ["0", "0.01", "1", "10", "500"],
                  "fluid_temperature_C": ["-40", "20", "130"],
                  "max_current_density_A_per_mm2": ["1", "30", "inf"],
                  "coil_temperature_C": ["-60", "20", "200"],
                  "peak_duration_s": ["0.001", "1", "1000"]},
    "transmission": {"lever_mm": ["1", "10", "170", "2000"], "gearing": ["0.01", "1", "100"],
                     "k_N_per_m": ["1", "4000", "1e7"], "b_N_s_per_m": ["0", "20", "1e4"],
                     "m2_g": ["0.1", "14", "1e5"], "workspace_mm": ["1", "50", "2000"]},
    "amplifier": {"supply_voltage_V": ["1", "24", "1000"],
                  "current_bandwidth_Hz": ["10", "2000", "1e7"]},
}  # fmt: skip


#: The fraction of ``valid`` (and accepted ``extremes``) evaluations that run the uncertain
#: path (the verdict over the ranges, ~2x the cost of the nominal one); the rest run with
#: ``--no-uncertainty``. The ranges' own inputs are the ``sections`` class, always uncertain.
UNCERTAIN_FRACTION = 0.25


def make_valid(rng: random.Random, folder: Path, k: int) -> list[str]:
    """A design file of valid values (a few keys), through evaluate --json."""
    lines: dict[str, list[str]] = {"clutch": ['base = "paper"']}
    for _ in range(rng.randint(1, 4)):
        sec = rng.choice(list(VALID_KEYS))
        key = rng.choice(list(VALID_KEYS[sec]))
        if not any(ln.startswith(f"{key} =") for ln in lines.get(sec, [])):
            lines.setdefault(sec, []).append(f"{key} = {rng.choice(VALID_KEYS[sec][key])}")
    text = "".join(f"[{s}]\n" + "\n".join(v) + "\n" for s, v in lines.items())
    path = folder / f"v{k}.toml"
    path.write_text(text)
    argv = ["evaluate", str(path), "--json"]
    return argv if rng.random() < UNCERTAIN_FRACTION else [*argv, "--no-uncertainty"]


def make_spec(rng: random.Random, folder: Path, k: int) -> list[str]:
    """A tiny sweep spec (a few designs), fuzzed; --out in a folder of its own."""
    params = []
    for name in rng.sample(["gap_mm", "drum_thickness_mm", "n_drums", "zone_length_mm"],
                           rng.randint(1, 2)):  # fmt: skip
        lo = rng.choice(["0.2", "1", "4", "0", "-1", "nan", "inf", "1e300"])
        hi = rng.choice(["0.5", "2", "8", "inf", "0.1", "1e300"])
        count = rng.choice(["1", "2", "3", "0", "-1", "2.5", "1e9"])
        params.append(f"{name} = {{min = {lo}, max = {hi}, count = {count}}}")
    head = rng.choice(['mode = "grid"', 'mode = "random"\nsamples = 3', 'mode = "x"',
                       'mode = "grid"\nchunk_size = 0',
                       'mode = "grid"\nbase = ["paper"]'])  # fmt: skip
    spec = folder / f"p{k}.toml"
    spec.write_text(f"[sweep]\n{head}\n[parameters]\n" + "\n".join(params) + "\n")
    return ["sweep", str(spec), "--out", str(folder / f"out{k}" / "r.csv"), "--no-progress"]


#: The built-in fluid a fuzzed material file starts from (issue 44).
FLUID_FILE = ROOT / "geometry" / "data" / "materials" / "mrf_132dg.toml"
#: Keys of a fluid file whose values the fuzzer replaces.
FLUID_KEYS = ("density", "conductivity", "specific_heat", "thermal_conductivity", "phi",
              "carrier_c", "viscosity", "viscosity_temperature", "temperature_range",
              "carrier_points", "colour", "name", "kind")  # fmt: skip
#: The sections issue 44 hardened, their keys and the values drawn for them.
NEW_SECTIONS = {
    "measured": ["m1_g", "b1_N_s_per_m", "step_delay_ms", "off_state_torque_mN_m", "torque",
                 "use_in_model", "source"],
    "uncertainty": ["viscosity_spread_pct", "fluid_temperature_C", "gap_tolerance_mm",
                    "runout_mm", "drum_thickness_tolerance_mm", "delay_ms",
                    "bench_damping_N_s_per_m", "yield_stress_spread_pct", "bh_spread_pct"],
    "process": ["runout_mm", "tolerance_mm", "min_wall_mm"],
}  # fmt: skip


#: Values of those keys that a design accepts (a ``sections`` draw uses them in a fraction
#: ``PLAUSIBLE_FRACTION`` of inputs, so the accepted paths, not only the refusals, are run).
PLAUSIBLE = {
    "m1_g": ["0.01", "1", "40", "1e4"], "b1_N_s_per_m": ["1e-3", "0.5", "30"],
    "step_delay_ms": ["0", "1", "20"], "off_state_torque_mN_m": ["0", "4", "100"],
    "torque": ["[{current_A = 7.0, torque_N_m = 1.2}]",
               "[{current_A = 1, torque_N_m = 0.1}, {current_A = 7, torque_N_m = 1.5}]"],
    "use_in_model": ["true", "false"], "source": ['"bench"'],
    "viscosity_spread_pct": ["0", "10", "60"], "fluid_temperature_C": ["[20, 60]", "[-20, 80]"],
    "gap_tolerance_mm": ["0", "0.02", "0.1"], "runout_mm": ["0", "0.01", "0.05"],
    "drum_thickness_tolerance_mm": ["0", "0.01"], "delay_ms": ["[0.5, 2]", "[1, 1]"],
    "bench_damping_N_s_per_m": ["[0, 0.73]", "[0, 5]"],
    "yield_stress_spread_pct": ["0", "10", "50"], "bh_spread_pct": ["0", "5", "30"],
    "tolerance_mm": ["0", "0.01", "0.05"], "min_wall_mm": ["0.1", "0.3"],
}  # fmt: skip
PLAUSIBLE_FRACTION = 0.3


def _fuzz_number(rng: random.Random) -> str:
    if rng.random() < 0.5:
        return rng.choice(EXTREMES)
    return repr(rng.choice([1.0, 1.0, -1.0]) * 10 ** rng.uniform(-8, 8))


#: The library's fluids a plausible fluid file perturbs (geometry/data/materials).
LIBRARY_FLUIDS = tuple(FLUID_FILE.parent / f"{n}.toml" for n in ("mrf_122eg", "mrf_132dg",
                                                                   "mrf_140cg"))  # fmt: skip


def _toml_value(v: Any) -> str:
    """A value of a fluid file as TOML (numbers, strings, booleans and lists of them)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string (\uXXXX escapes) is a TOML basic string
    return "[" + ", ".join(_toml_value(x) for x in v) + "]"


def _loguniform(rng: random.Random, lo: float, hi: float) -> float:
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


#: The fields of a fluid file a plausible draw moves (``_move``).
FLUID_MOVES = ("density", "specific_heat", "thermal_conductivity", "phi", "carrier_c",
               "viscosity", "viscosity_temperature", "carrier_points", "temperature_range",
               "carrier_expansion", "lifetime_dissipated_energy", "bh", "tau_y")  # fmt: skip


def _move(rng: random.Random, rec: dict[str, Any], key: str) -> None:
    """Field ``key`` of fluid record ``rec`` moved inside its physical range (in place)."""
    uniform = {"density": (2000.0, 4500.0),  # kg/m³: MR fluids' span
               "specific_heat": (400.0, 2000.0),  # J/(kg·K)
               "thermal_conductivity": (0.1, 3.0),  # W/(m·K)
               "phi": (0.05, 0.5), "carrier_c": (0.8, 1.3),
               "viscosity_temperature": (20.0, 60.0),  # °C
               "carrier_expansion": (0.0, 2e-3)}  # 1/K  # fmt: skip
    if key in ("carrier_expansion", "lifetime_dissipated_energy") and rng.random() < 0.3:
        rec.pop(key, None)  # a user's file without ageing data (issue 41: no data)
    elif key in uniform:
        rec[key] = rng.uniform(*uniform[key])
    elif key == "viscosity":
        rec[key] = _loguniform(rng, 0.01, 3.0)  # Pa·s
    elif key == "lifetime_dissipated_energy":
        rec[key] = _loguniform(rng, 1e11, 1e14)  # J/m³
    elif key == "carrier_points":  # the Walther line moved up or down, its slope kept
        f = _loguniform(rng, 0.3, 3.0)
        rec[key] = [[t, nu * f] for t, nu in rec[key]]
    elif key == "temperature_range":
        rec[key] = [rng.uniform(-60.0, 10.0), rng.uniform(70.0, 200.0)]
    elif key == "bh" and "b" in rec["bh"] and rng.random() < 0.7:
        # the magnetisation scaled, B = μ0 (H + f M): the slope stays >= μ0 (a B scaled
        # down would fall below μ0 near saturation, which the loader rightly refuses)
        f, mu0 = rng.uniform(0.5, 1.5), 4e-7 * math.pi
        bh = zip(rec["bh"]["b"], rec["bh"]["h"], strict=True)
        rec["bh"] = {**rec["bh"], "b": [mu0 * h + f * (b - mu0 * h) for b, h in bh]}
    elif key == "bh":
        rec["bh"] = {"source": "Carlson's closed form [carlson]", "model": "carlson"}
    elif key == "tau_y" and "tau_y" in rec:  # the datasheet's τy scaled: still rising
        f = rng.uniform(0.7, 1.3)
        rec["tau_y"] = {**rec["tau_y"], "tau": [t * f for t in rec["tau_y"]["tau"]]}


def plausible_fluid(rng: random.Random, k: int) -> tuple[str, tuple[float, float]]:
    """A fluid file that loads: one of the library's fluids with one to five fields moved
    inside their physical ranges (an MR fluid's density 2–4.5 g/cm³, iron fraction 5–50 %,
    off-state viscosity 0.01–3 Pa·s, Carlson's C 0.8–1.3, the B–H and τy tables scaled,
    the Walther points scaled together, the optional ageing data dropped): its TOML text
    and its temperature range (°C)."""
    import tomllib

    rec = tomllib.loads(rng.choice(LIBRARY_FLUIDS).read_text())
    rec["name"] = f"fuzz_fluid_{k}"
    rec["label"] = f"fuzz fluid {k}"
    start = dict(rec)
    for key in rng.sample(FLUID_MOVES, rng.randint(1, 5)):
        _move(rng, rec, key)
    if rec == start:  # the keys drawn were absent (no [tau_y]): move the viscosity
        _move(rng, rec, "viscosity")
    flat = [f"{k} = {_toml_value(v)}" for k, v in rec.items() if not isinstance(v, dict)]
    tables = [f"[{k}]\n" + "\n".join(f"{a} = {_toml_value(b)}" for a, b in v.items())
              for k, v in rec.items() if isinstance(v, dict)]  # fmt: skip
    lo, hi = rec["temperature_range"]
    return "\n".join(flat) + "\n\n" + "\n\n".join(tables) + "\n", (lo, hi)


def make_plausible_material(rng: random.Random, folder: Path, k: int) -> list[str]:
    """A design on a plausible fluid file (``plausible_fluid``), at times run at another
    fluid temperature inside the file's range, through a fast command with ``--json``: it
    must answer (``check_input``: exit 0, no NaN, every null with its reason)."""
    text, (lo, hi) = plausible_fluid(rng, k)
    mat = folder / f"mp{k}.toml"
    mat.write_text(text)
    design = folder / f"mpd{k}.toml"
    body = f'[clutch]\nbase = "paper"\n[materials]\nfluid_file = "{mat}"\n'
    if rng.random() < 0.3:  # inside the file's range and the design's own [-40, 130] °C
        t = rng.uniform(max(lo, -40.0), min(hi, 130.0))
        body += f"[operating]\nfluid_temperature_C = {t:.6g}\n"
    design.write_text(body)
    if rng.random() < 0.6:
        return ["evaluate", str(design), "--fidelity", "fast", "--no-uncertainty", "--json"]
    return ["torque", str(design), "--method", "circuit", "--json"]


def make_material(rng: random.Random, folder: Path, k: int) -> list[str]:
    """A design whose ``fluid_file`` is hostile: random bytes, UTF-16, nested past the
    parser, a FIFO, a device, a directory, a huge file, or the built-in fluid with one to
    three fields replaced by extremes (viscosity 1e300 …); in a fraction
    ``PLAUSIBLE_FRACTION`` of draws a plausible fluid file that loads and must be answered
    (``make_plausible_material``)."""
    if rng.random() < PLAUSIBLE_FRACTION:
        return make_plausible_material(rng, folder, k)
    kind = rng.randrange(8)
    mat = folder / f"m{k}.toml"
    base = FLUID_FILE.read_text().replace('name = "mrf_132dg"', f'name = "fuzz_{k}"')
    if kind == 0:
        mat.write_bytes(bytes(rng.randrange(256) for _ in range(rng.randint(1, 400))))
    elif kind == 1:
        enc = rng.choice(["utf-16", "utf-16-le", "utf-32", "latin-1"])
        mat.write_bytes(base.encode(enc, errors="replace"))  # latin-1 has no τ
    elif kind == 2:
        depth = rng.choice([9, 50, 5000, 100000])
        mat.write_text(base + "deep = " + "[" * depth + "1" + "]" * depth + "\n")
    elif kind == 3:
        os.mkfifo(mat)
    elif kind == 4:
        mat = Path(rng.choice(["/dev/zero", "/dev/null", "/dev/urandom", str(folder)]))
    elif kind == 5:
        with open(mat, "wb") as f:  # sparse: the size without the bytes
            f.truncate((1 << 20) + rng.randrange(1, 1 << 30))
    else:
        lines = base.splitlines()
        for _ in range(rng.randint(1, 3)):
            key = rng.choice(FLUID_KEYS)
            value = rng.choice(['[1, 2]', '[[1, 1e-300], [2, 1e300]]', '"x"', "[]"]
                               ) if rng.random() < 0.2 else _fuzz_number(rng)  # fmt: skip
            lines = [f"{key} = {value}" if ln.startswith(f"{key} =") else ln for ln in lines]
        if rng.random() < 0.3:  # the B–H table: long, reversed or absurd
            b = rng.choice(["[" + ", ".join(["1.0"] * 5000) + "]", "[2.0, 1.0]", "[1e300, 2e300]",
                            "[0.1, 0.2]"])  # fmt: skip
            lines = [f"b = {b}" if ln.startswith("b = ") else ln for ln in lines]
        mat.write_text("\n".join(lines) + "\n")
    design = folder / f"md{k}.toml"
    design.write_text(f'[clutch]\nbase = "paper"\n[materials]\nfluid_file = "{mat}"\n')
    argv = ["evaluate", str(design), "--fidelity", "fast"]
    return argv + (["--json"] if rng.random() < 0.5 else [])


def make_sections(rng: random.Random, folder: Path, k: int) -> list[str]:
    """A design with fuzzed ``[measured]`` (used in the model or not), ``[uncertainty]`` and
    ``[process]`` tables: extremes, reversed and nominal-free ranges, runout beyond the gap,
    duplicate and non-finite bench points; in a fraction ``PLAUSIBLE_FRACTION`` of draws,
    values a design accepts (the uncertain path runs: seconds)."""
    lines = ['[clutch]\nbase = "paper"']
    if rng.random() < 0.3:
        lines.append(f"gap_mm = {rng.choice(['0.1', '0.3', '0.7', '2'])}")
    plausible = rng.random() < PLAUSIBLE_FRACTION
    for sec in rng.sample(list(NEW_SECTIONS), rng.randint(1, 3)):
        lines.append(f"[{sec}]")
        for key in rng.sample(NEW_SECTIONS[sec], rng.randint(1, 3)):
            if plausible:
                value = rng.choice(PLAUSIBLE[key])
            elif key == "torque":
                pts = [
                    f"{{current_A = {rng.choice(['7', '7.0', '1', _fuzz_number(rng)])}, "
                    f"torque_N_m = {_fuzz_number(rng)}}}"
                    for _ in range(rng.randint(0, 3))
                ]
                value = "[" + ", ".join(pts) + "]"
            elif key == "use_in_model":
                value = rng.choice(["true", "true", "false", "1"])
            elif key == "source":
                value = rng.choice(['"bench"', "1", '"\\u0000"'])
            elif key in ("fluid_temperature_C", "delay_ms", "bench_damping_N_s_per_m"):
                value = f"[{_fuzz_number(rng)}, {_fuzz_number(rng)}]"
            else:
                value = _fuzz_number(rng)
            lines.append(f"{key} = {value}")
        if sec == "measured" and rng.random() < 0.5:
            lines.append("use_in_model = true")
    path = folder / f"n{k}.toml"
    path.write_text("\n".join(dict.fromkeys(lines)) + "\n")
    argv = [rng.choice(["evaluate", "evaluate", "scale"]), str(path)]
    if argv[0] == "evaluate":
        argv += ["--fidelity", "fast"]
    return argv + (["--json"] if rng.random() < 0.5 else [])


def make_any(rng: random.Random, keys: dict[str, list[str]], folder: Path, k: int,
             classes: tuple[str, ...] | None = None) -> tuple[str, list[str]]:  # fmt: skip
    """(class, argv) of input k, drawn from ``classes`` (None: all) by their weights."""
    names = [c for c in CLASSES if classes is None or c in classes]
    cls = rng.choices(names, weights=[CLASSES[c] for c in names])[0]
    if cls == "extremes":
        return cls, make_input(rng, keys, folder, k)
    if cls == "structure":
        return cls, make_structure(rng, keys, folder, k)
    if cls == "files":
        return cls, make_files(rng, folder, k)
    if cls == "options":
        return cls, make_options(rng, folder, k)
    if cls == "valid":
        return cls, make_valid(rng, folder, k)
    if cls == "material":
        return cls, make_material(rng, folder, k)
    if cls == "sections":
        return cls, make_sections(rng, folder, k)
    return cls, make_spec(rng, folder, k)


def nulls_unexplained(data: Any) -> list[str]:
    """Paths of nulls in an evaluate JSON that neither ``nulls`` nor a ``note`` explains."""
    reasons = data.get("nulls", {}) if isinstance(data, dict) else {}
    out: list[str] = []

    def walk(v: Any, path: tuple[str, ...], noted: bool) -> None:
        if isinstance(v, dict):
            noted = noted or isinstance(v.get("note"), str)
            for key, x in v.items():
                if key not in ("nulls", "note"):
                    walk(x, (*path, str(key)), noted)
        elif isinstance(v, list):
            for x in v:
                walk(x, path, noted)
        elif v is None and not noted:
            key = "/".join(path)
            if not reasons.get(key) or "no reason" in reasons[key]:
                out.append(key)

    walk(data, (), False)
    return out


def check_input(cls: str, argv: list[str], code: int, text: str, folder: Path
                ) -> tuple[str, str] | None:  # fmt: skip
    """The issue-32 checks on one finished input: (class, detail) of a failure, or None."""
    out_dirs = [
        Path(a).parent for a in argv if "/out" in a and Path(a).parent.name.startswith("out")
    ]
    if code != 0:
        for d in out_dirs:  # a refused command leaves nothing behind
            left = [p.name for p in d.iterdir()] if d.exists() else []
            if left:
                return "partial", f"{argv[0]} exit {code} left {left[:3]}"
    elif argv[0] == "sweep" and out_dirs:
        csv = out_dirs[0] / "r.csv"
        spec_rows = _spec_designs(argv[1])
        rows = csv.read_bytes().count(b"\n") - 1 if csv.exists() else -1
        if spec_rows is not None and rows != spec_rows:
            return "partial", f"sweep wrote {rows} rows for {spec_rows} designs"
    if cls == "material" and Path(argv[1]).name.startswith("mpd") and code != 0:
        return "refused", f"plausible fluid file refused (exit {code})"  # it loads: answer
    if cls in ("material", "sections") and code == 0 and "--json" in argv:
        missing = nulls_unexplained(json.loads(text))  # issue 44: every null with a reason
        return ("null", f"null without a reason: {missing[0]}") if missing else None
    if cls != "valid":
        return None
    from geometry.validation import ParameterError
    from mrclutch.design import design_from_mapping, design_to_toml, load_design

    try:
        design = load_design(argv[1])
    except ParameterError:  # the draw crossed a rule between keys: not a valid design
        return None
    if code != 0:
        return "refused", f"valid design refused (exit {code})"
    back = design_from_mapping(__import__("tomllib").loads(design_to_toml(design)))
    if design_to_toml(back) != design_to_toml(design) or back.name != design.name:
        return "refused", "design file does not round-trip"
    missing = nulls_unexplained(json.loads(text))
    if missing:
        return "null", f"null without a reason: {missing[0]}"
    return None


def _spec_designs(path: str) -> int | None:
    from mrclutch.sweep import load_spec

    try:
        return load_spec(path)[0].n_designs
    except Exception:
        return None


def run_input(cls: str, argv: list[str], timeout: float, folder: Path) -> tuple[str, str]:
    """(class, detail) of one input: ``run_one``'s, then ``check_input``'s."""
    result = run_one(argv, timeout)
    if result[0] not in ("ok", "nan"):
        return result[:2]
    code, text = int(result[1]), result[2]
    try:
        bad = check_input(cls, argv, code, text, folder)
    except Exception as exc:  # a check that cannot even load a "valid" design
        return "refused", f"{type(exc).__name__}: {str(exc)[:120]}"
    if bad:
        return bad
    return result[:2]


def run_one(argv: list[str], timeout: float) -> tuple[str, str]:
    """(class, detail) of one call of main: ok, traceback, nan, memory or slow."""
    from mrclutch.cli.main import main

    out, err = io.StringIO(), io.StringIO()

    def alarm(signum, frame):
        raise TimeoutError(f"more than {timeout:g} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 2
        if code not in (0, 2):
            return "traceback", f"SystemExit({exc.code!r})"
        return "ok", str(code), out.getvalue()  # type: ignore[return-value]
    except MemoryError:
        return "memory", "MemoryError"
    except TimeoutError as exc:
        return "slow", f"{argv[0]}: {exc}"
    except RecursionError:
        return "traceback", "RecursionError"
    except Exception as exc:
        return "traceback", f"{type(exc).__name__}: {str(exc)[:160]}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    if code not in OK_CODES:
        return "traceback", f"exit code {code!r}"
    text = out.getvalue()
    if NAN.search(text) and "note" not in text.lower():
        line = next(ln for ln in text.splitlines() if NAN.search(ln))
        return "nan", line.strip()[:160]
    return "ok", str(code), text  # type: ignore[return-value]


def child(args: argparse.Namespace) -> None:
    """Run inputs start..stop; one JSON line per input on stdout (flushed)."""
    limit = int(args.mem_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    import warnings

    warnings.simplefilter("ignore")
    keys = preset_keys()
    # untimed warm-up: the first evaluation compiles the network's numba kernel (tens of
    # seconds on a loaded machine); a SIGALRM inside that compile leaves numba's dispatcher
    # half-built for the rest of the worker. scale compiles the batch kernels
    # (evaluate_batch): the first fuzzed scale of a fresh checkout (numba's cache is per
    # source path) once ran past a 120 s timeout compiling them at load 15, the same input
    # 5.7 s later in the run
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        from mrclutch.cli.main import main

        main(["evaluate", "--json"])
        main(["scale", "--json"])
    report = sys.stdout
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.start, args.stop):
            rng = random.Random(f"{args.seed}-{k}")
            kind, argv = make_any(rng, keys, Path(tmp), k, _classes(args.classes))
            t = time.perf_counter()
            cls, detail = run_input(kind, argv, args.timeout, Path(tmp))
            rec = {"k": k, "class": cls, "detail": detail, "argv": argv, "kind": kind,
                   "s": time.perf_counter() - t}  # fmt: skip
            files = [a for a in argv if a.endswith(".toml") and Path(a).is_file()]
            if cls != "ok" and files and Path(files[0]).stat().st_size < 4096:
                rec["design"] = Path(files[0]).read_text(errors="replace")
            report.write(json.dumps(rec) + "\n")
            report.flush()


def worker(args: argparse.Namespace, start: int, stop: int) -> subprocess.Popen:
    cmd = [sys.executable, __file__, "--child", "--start", str(start), "--stop", str(stop),
           "--seed", str(args.seed), "--mem-gb", str(args.mem_gb), "--timeout",
           str(args.timeout), "--classes", args.classes]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env=env)  # fmt: skip


_RECORDS_LOCK = threading.Lock()


def run_range(args: argparse.Namespace, start: int, stop: int) -> list[dict]:
    """Records of inputs start..stop from workers; a worker that dies (memory limit,
    segfault) is recorded as a memory failure at its input and restarted after it."""
    records: list[dict] = []
    while start < stop:
        proc = worker(args, start, stop)
        last = start - 1
        for line in proc.stdout:
            rec = json.loads(line)
            last = rec["k"]
            records.append(rec)
            if args.records:  # one line per input as it ends: a long run's progress
                with _RECORDS_LOCK, open(args.records, "a") as f:
                    f.write(line if line.endswith("\n") else line + "\n")
        proc.wait()
        if last + 1 < stop:
            records.append({"k": last + 1, "class": "memory", "argv": None,
                            "detail": f"worker died (exit {proc.returncode})"})  # fmt: skip
        start = last + 2
    return records


def cost_by_class(records: list[dict]) -> str:
    """Seconds per input, mean and total, per input class: what each class costs a run."""
    cost: dict[str, list[float]] = {}
    for r in records:
        cost.setdefault(r.get("kind", "?"), []).append(r.get("s", 0.0))
    return "seconds per input by class (mean, total): " + ", ".join(
        f"{k} {sum(v) / len(v):.2f} ({sum(v):.0f})" for k, v in sorted(cost.items())
    )


def _classes(spec: str) -> tuple[str, ...] | None:
    """``--classes material,sections`` as a tuple (None: every class)."""
    names = tuple(c.strip() for c in spec.split(",") if c.strip())
    unknown = [c for c in names if c not in CLASSES]
    if unknown:
        raise SystemExit(f"fuzz_cli: --classes {','.join(unknown)}: not one of "
                         f"{', '.join(CLASSES)}")  # fmt: skip
    return names or None


def parent(args: argparse.Namespace) -> int:
    from concurrent.futures import ThreadPoolExecutor

    t0 = time.perf_counter()
    counts = {"ok": 0, "traceback": 0, "refused": 0, "nan": 0, "null": 0, "partial": 0,
              "memory": 0, "slow": 0}  # fmt: skip
    kinds: dict[str, int] = {}
    examples: dict[str, dict[str, list]] = {c: {} for c in counts}
    step = math.ceil(args.n / args.workers)
    ranges = [(s, min(s + step, args.n)) for s in range(0, args.n, step)]
    with ThreadPoolExecutor(len(ranges)) as pool:
        parts = list(pool.map(lambda r: run_range(args, *r), ranges))
    for rec in (r for part in parts for r in part):
        counts[rec["class"]] += 1
        kinds[rec.get("kind", "?")] = kinds.get(rec.get("kind", "?"), 0) + 1
        if rec["class"] != "ok":
            ex = examples[rec["class"]].setdefault(rec["detail"][:90], [0, rec])
            ex[0] += 1
    total = sum(counts.values())
    dt = time.perf_counter() - t0
    print(f"{total} fuzzed inputs in {dt:.0f} s ({total / dt:.0f}/s), seed {args.seed}, "
          f"RLIMIT_AS {args.mem_gb:g} GiB, classes {args.classes or 'all'}")  # fmt: skip
    print("  inputs by class: " + ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())))
    print("  " + cost_by_class([r for part in parts for r in part]))
    for c, n in counts.items():
        print(f"  {c:<10} {n}")
    for c, exs in examples.items():
        for detail, (n, rec) in sorted(exs.items(), key=lambda t: -t[1][0])[: args.show]:
            print(f"{c}: {n}× {detail}\n    e.g. mrclutch {' '.join(rec.get('argv') or [])}")
            if rec.get("design"):
                print("    with " + rec["design"].strip().replace("\n", "\n         "))
    slowest = sorted((r for part in parts for r in part), key=lambda r: -r.get("s", 0))[:3]
    for r in slowest:
        print(f"slowest: {r.get('s', 0):.1f} s  mrclutch {' '.join(r.get('argv') or [])}")
    bad = sum(n for c, n in counts.items() if c not in ("ok", "slow")) + counts["slow"]
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000, help="inputs (default 10 000)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--mem-gb", type=float, default=4.0, help="RLIMIT_AS per worker, GiB")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds per input")
    ap.add_argument("--show", type=int, default=5, help="examples per class")
    ap.add_argument(
        "--classes",
        default="",
        help="comma-separated input classes to draw (default: all, by weight)",
    )
    ap.add_argument("--records", help="append each input's record (a JSON line) to this file")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--start", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--stop", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    _classes(args.classes)  # an unknown class refused before any worker starts
    if args.child:
        child(args)
        return 0
    return parent(args)


if __name__ == "__main__":
    sys.exit(main())
