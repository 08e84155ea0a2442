"""Every number a command prints as ``--json`` is finite, and every physically positive one
(a mass, inertia, stiffness, damping, frequency, time, length, power, torque) is ≥ 0,
unless a note beside it says why; every null has its reason (issue 44 item 4).

Walked on the presets, the examples/ design files and three extreme but accepted designs
(20 drums at a 0.1 mm gap and 1000 A; one 250 mm drum at 0.01 A on a 2 m lever; a hot,
slow, stiff, starved bench), through evaluate, compare, haptic, torque, inertia, device
and scale (scale, seconds, on the 20-drum design). Fast fidelity and ``--no-uncertainty``:
the uncertain path's JSON is walked once here on the paper preset, and its extremes in
tests/mrclutch/test_hardened_inputs.py. The presets' and examples' other designs run
through evaluate only (the other commands read the same figures); optimize (minutes at
full size) is walked on a tiny search in tests/mrclutch/test_optimize_json_walk.py."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from mrclutch.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: Extreme but accepted designs (each key inside its validated range).
EXTREMES = {
    "many": '[clutch]\nbase = "paper"\nn_drums = 20\ngap_mm = 0.1\ndrum_thickness_mm = 0.1\n'
    "[operating]\nmax_current_A = 1000\ninput_speed_rpm = 50000\n",
    "big": '[clutch]\nbase = "paper"\nn_drums = 1\ndrum_inner_diameter_mm = 250\n'
    "zone_length_mm = 20\ngap_mm = 2\n[operating]\ninput_speed_rpm = 0.001\n"
    "max_current_A = 0.01\n[transmission]\nlever_mm = 2000\nm2_g = 1e5\n",
    "hot": '[clutch]\nbase = "paper"\n[operating]\nfluid_temperature_C = 130\ndelay_ms = 500\n'
    "[transmission]\nlever_mm = 1\ngearing = 100\nk_N_per_m = 1e7\n"
    "[amplifier]\nsupply_voltage_V = 1\ncurrent_bandwidth_Hz = 10\n",
}

#: A key's unit suffix that makes its value physically ≥ 0 (a derivative, ``*_per_m`` other
#: than a stiffness or damping, is signed and is not in this list).
POSITIVE = re.compile(
    r"(_kg|_kg_m2|_g|_ohm|_H|_m3|_mL|_hz|_Hz|_s|_N_per_m|_N_s_per_m|_N_m_s|_W|_V|_h|_m|_mm"
    r"|_N_m|_N)$"
)
SIGNED_PER_M = re.compile(r"_per_m2?$")


def physically_positive(key: str) -> bool:
    """``felt_mass_kg`` yes, ``d_torque_d_gap_N_m_per_m`` no (a slope), ``K_N_per_m`` yes."""
    if SIGNED_PER_M.search(key) and not key.endswith(("_N_per_m", "_N_s_per_m")):
        return False
    return bool(POSITIVE.search(key))


def _explains(notes: list[str], key: str) -> bool:
    stem = POSITIVE.sub("", key).replace("_", " ").lower()
    return any(key in n or stem in n.lower() for n in notes)


def unexplained(data: Any) -> list[tuple[str, Any]]:
    """(path, value) of each number that is NaN/inf, or negative where physically positive,
    with no note beside it (a ``note`` or ``notes`` of its table or one above that names
    the key), and of each null that neither ``nulls`` (of its table or one above, keyed by
    the path below that table) nor a ``note`` explains."""
    reasons: dict[str, str] = {}
    out: list[tuple[str, Any]] = []

    def walk(v: Any, path: tuple[str, ...], notes: list[str], blanket: bool) -> None:
        if isinstance(v, dict):
            if isinstance(v.get("nulls"), dict):  # an embedded evaluation's own reasons
                prefix = "".join(f"{p}/" for p in path)
                reasons.update({prefix + k: r for k, r in v["nulls"].items()})
            if isinstance(v.get("note"), str):
                notes, blanket = [*notes, v["note"]], True
            if isinstance(v.get("notes"), list):
                notes = [*notes, *(n for n in v["notes"] if isinstance(n, str))]
            for k, x in v.items():
                if k in ("nulls", "note", "notes") or k.endswith("_note"):
                    continue
                # a sibling "<name>_note" explains "<name>_<unit>" (device's update_rate_note)
                mine = [v[n] for n in v if n.endswith("_note") and str(k).startswith(n[:-4])]
                walk(x, (*path, str(k)), [*notes, *mine], blanket or bool(mine))
        elif isinstance(v, list):
            for x in v:
                walk(x, path, notes, blanket)
        elif v is None:
            key = "/".join(path)
            if not blanket and (not reasons.get(key) or "no reason" in reasons[key]):
                out.append((key, v))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            key = "/".join(path)
            last = path[-1] if path else ""
            if reasons.get(key) or _explains(notes, last):
                return
            if v != v or v in (float("inf"), float("-inf")):
                out.append((key, v))
            elif v < 0 and physically_positive(last):
                out.append((key, v))

    walk(data, (), [], False)
    return out


def test_the_walk_finds_what_it_must_and_accepts_a_reason():
    """The checker itself: NaN, inf, a negative mass and a bare null are found; a slope may
    be negative; a note naming the key (or a ``nulls`` reason) explains it."""
    bad = {"a": {"m_kg": -1.0, "x": float("nan"), "y": float("inf"), "z": None,
                 "d_torque_d_gap_N_m_per_m": -3.0, "K_N_per_m": 5.0}}  # fmt: skip
    assert sorted(k for k, _ in unexplained(bad)) == ["a/m_kg", "a/x", "a/y", "a/z"]
    ok = {"a": {"felt_mass_kg": -1.0, "notes": ["felt mass -1 kg is negative: a spring"]},
          "r": None, "nulls": {"r": "no resonance below 1 kHz"},
          "m": [{"e": {"h": {"r": None}, "nulls": {"h/r": "overdamped"}}}]}  # fmt: skip
    assert unexplained(ok) == []
    other = {"a": {"felt_mass_kg": -1.0, "notes": ["the bound is unmeasured"]}}
    assert unexplained(other) == [("a/felt_mass_kg", -1.0)]
    assert unexplained({"rate_hz": None, "rate_note": "continuous time"}) == []
    assert unexplained({"rate_hz": None, "other_note": "continuous time"}) == [("rate_hz", None)]


def _designs(tmp_path: Path) -> dict[str, list[str]]:
    """Name -> the design arguments of a command (preset or file)."""
    out: dict[str, list[str]] = {"paper": ["--preset", "paper"],
                                 "paper-holes": ["--preset", "paper-holes"]}  # fmt: skip
    for f in sorted(EXAMPLES.glob("*.toml")):
        if "[sweep]" not in f.read_text():
            out[f.stem] = [str(f)]
    for name, text in EXTREMES.items():
        path = tmp_path / f"{name}.toml"
        path.write_text(text)
        out[name] = [str(path)]
    return out


#: The JSON commands walked on every design (argv after the design arguments).
COMMANDS = (
    ("evaluate", ["--no-uncertainty", "--json"]),
    ("compare", ["--json"]),
    ("haptic", ["--json"]),
    ("torque", ["--json"]),
    ("inertia", ["--method", "analytic", "--json"]),
)


def _json(capsys, argv: list[str]) -> Any:
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, (argv, captured.err)
    return json.loads(captured.out)


def test_every_commands_json_on_presets_examples_and_extremes(tmp_path, capsys, judged_once):
    """Each design's commands share its evaluation (``judged_once``: evaluate, compare,
    haptic and device evaluated it each, compare and haptic judged it each)."""
    designs = _designs(tmp_path)
    assert {"paper", "paper_bench", "thin_drums", "many", "big", "hot"} <= set(designs)
    found: list[tuple[str, str, str, Any]] = []
    for name, args in designs.items():
        # evaluate on every design; the other commands on the paper and the extremes
        wide = name == "paper" or name in EXTREMES
        with judged_once():
            for cmd, extra in COMMANDS if wide else COMMANDS[:1]:
                data = _json(capsys, [cmd, *args, *extra])
                found += [(name, cmd, k, v) for k, v in unexplained(data)]
            if not wide:
                continue
            out = tmp_path / f"device_{name}.json"
            assert main(["device", *args, "--out", str(out)]) == 0, capsys.readouterr().err
            capsys.readouterr()
        found += [(name, "device", k, v) for k, v in unexplained(json.loads(out.read_text()))]
    # 20 drums: the drums route cannot add one (once a refusal of the whole study)
    data = _json(capsys, ["scale", *designs["many"], "--json"])
    found += [("many", "scale", k, v) for k, v in unexplained(data)]
    for argv in (["haptic"], ["haptic", "--actuator", "maxon-118890"], ["compare"]):
        data = _json(capsys, [*argv, "--json"])  # the catalogue (no design)
        found += [("catalogue", " ".join(argv), k, v) for k, v in unexplained(data)]
    data = _json(capsys, ["evaluate", "--json"])  # the uncertain path, once
    found += [("paper", "evaluate (ranges)", k, v) for k, v in unexplained(data)]
    assert not found, found


@pytest.mark.parametrize("key", ["felt_mass_kg", "K_N_per_m", "b1_N_s_per_m", "bandwidth_hz"])
def test_physically_positive_keys(key):
    assert physically_positive(key)
