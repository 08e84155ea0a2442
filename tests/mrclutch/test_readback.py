"""What a person reads, read back: each text table of ``evaluate``, ``compare`` and
``haptic`` parsed and compared, value and unit, with the ``--json`` of the same run
(issue 46).

Rows are found by their labels, never by line numbers; each printed number is converted
to SI with this file's own table of units (``UNITS``), not the formatter's, and must equal
the JSON value to within half a unit of its last printed digit. A figure printed at the
wrong scale (41.64 mN printed as 0.04164 under "mN") or under the wrong unit fails here
even when the JSON is right.
"""

from __future__ import annotations

import contextlib
import io
import json
import re

import pytest

from mrclutch.cli.main import main
from mrclutch.outputs import CLUTCH_ROWS, HAND_ROWS, output, row_label

#: SI value of one printed unit (this test's own table, not mrclutch.outputs').
UNITS: dict[str, float] = {
    "N·m": 1.0, "mN·m": 1e-3, "µN·m": 1e-6, "A": 1.0, "mA": 1e-3, "kg·m²": 1.0,
    "g·cm²": 1e-7, "g·mm²": 1e-9, "kg": 1.0, "g": 1e-3, "N·m·s": 1.0, "mN·m·s": 1e-3,
    "µN·m·s": 1e-6, "dB": 1.0, "N·m/(kg·m²)": 1.0, "Ω": 1.0, "mΩ": 1e-3, "W": 1.0,
    "mW": 1e-3, "s": 1.0, "ms": 1e-3, "N/m": 1.0, "N·s/m": 1.0, "Hz": 1.0, "N": 1.0,
    "mN": 1e-3, "dB·decade": 1.0, "N²·s/m²": 1.0, "mm": 1e-3, "m": 1.0, "%": 1e-2,
    "": 1.0,  # a plain ratio
}  # fmt: skip
_NUM = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def _half_ulp(text: str) -> float:
    """Half a unit of the last digit printed: "0.4272" → 5e-5, "1.652e+06" → 500,
    "4000" → 0.5."""
    mant, _, exp = text.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (-decimals + (int(exp) if exp else 0))


def agrees(text: str, unit: str, si: float) -> bool:
    """The printed ``text`` in ``unit`` is the SI value ``si`` rounded for print."""
    assert _NUM.match(text), f"not a number: {text!r}"
    scale = UNITS[unit]  # an unknown unit fails here, naming it
    return abs(float(text) - si / scale) <= _half_ulp(text) * (1 + 1e-9) + 1e-12 * abs(si / scale)


def row(text: str, label: str) -> list[str]:
    """The cells after ``label`` on the one line of ``text`` that starts with it (after
    indentation) and is followed by two spaces or more."""
    pat = re.compile(r"^\s*" + re.escape(label) + r"\s{2,}(\S.*)$")
    hits = [m.group(1) for ln in text.splitlines() if (m := pat.match(ln))]
    assert len(hits) == 1, f"{label!r}: {len(hits)} rows in the text"
    return hits[0].split()


def section(text: str, header: str) -> str:
    """The lines from the one starting with ``header`` to the next blank line."""
    lines = text.splitlines()
    start = [i for i, ln in enumerate(lines) if ln.startswith(header)]
    assert len(start) == 1, f"{header!r}: {len(start)} sections"
    end = next((j for j in range(start[0] + 1, len(lines)) if not lines[j].strip()), len(lines))
    return "\n".join(lines[start[0] : end])


def label_unit(label: str) -> str | None:
    m = re.search(r"\(([^()]*(?:\([^()]*\))?[^()]*)\)$", label)
    return m.group(1) if m else None


def check_cells(cells: list[str], unit: str, values: list[float | None], where: str) -> None:
    """Each of ``values`` (SI; None printed as —) against the leading ``cells``."""
    for i, v in enumerate(values):
        if v is None:
            assert cells[i] in ("—", "none"), f"{where}: {cells[i]!r} for a null"
        elif isinstance(v, bool):
            assert cells[i] == ("yes" if v else "no"), f"{where}: {cells[i]!r} for {v}"
        else:
            assert agrees(cells[i], unit, v), f"{where}: printed {cells[i]} {unit}, JSON {v}"


def _run(capsys, *argv: str) -> tuple[str, dict]:
    assert main([*argv]) == 0
    text = capsys.readouterr().out
    assert main([*argv, "--json"]) == 0
    return text, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def evaluated():
    """``evaluate --preset paper``, text and JSON (a module fixture: capsys is per test)."""
    out = []
    for extra in ((), ("--json",)):
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            assert main(["evaluate", "--preset", "paper", *extra]) == 0
        out.append(buf.getvalue())
    return out[0], json.loads(out[1])


def test_parser_reads_what_it_should():
    """The read-back's own arithmetic: 41.64 mN is 0.04164 N to half a unit of 0.01 mN;
    the same digits under N are 1000× off."""
    assert _half_ulp("0.4272") == pytest.approx(5e-5)
    assert _half_ulp("1.652e+06") == pytest.approx(500.0)
    assert _half_ulp("4000") == pytest.approx(0.5)
    assert agrees("41.64", "mN", 0.041638)
    assert not agrees("0.04164", "mN", 0.041638)
    assert not agrees("41.64", "N", 0.041638)
    assert row("  max torque          0.4272 N·m\n", "max torque") == ["0.4272", "N·m"]
    assert label_unit("torque / inertia (N·m/(kg·m²))") == "N·m/(kg·m²)"


def test_evaluate_clutch_rows_read_back_to_the_json(evaluated):
    """Every clutch row (value and the unit after it) against clutch.<key> of the JSON."""
    text, js = evaluated
    c = js["clutch"]
    for key in CLUTCH_ROWS:
        cells = row(text, output(key).label)
        check_cells(cells, cells[1], [c[key]], key)
    d, length = c["envelope_m"]
    env = " ".join(row(text, "envelope"))
    m = re.match(r"Ø(\S+) × (\S+) (\S+)$", env)
    assert m and agrees(m.group(1), m.group(3), d) and agrees(m.group(2), m.group(3), length)


def test_evaluate_hand_rows_read_back_for_both_sides(evaluated):
    """The MR pair's and the motor's columns (unit in the label) against haptic/motor."""
    text, js = evaluated
    text = section(text, "at the hand")
    for key in HAND_ROWS:
        label = row_label(key)
        cells = row(text, label)
        unit = label_unit(label) or ""
        vals = [js["haptic"][key], js["motor"][key]]
        if unit:
            check_cells(cells, unit, vals, key)
        else:
            check_cells(cells, "", vals, key)  # yes/no rows


#: format_hand's rows: label → hand/<side>/<key> (the unit is printed after the columns).
HAND_BLOCK = (
    ("backdrive force (K = 0)", "backdrive_force_N"),
    ("felt mass (K = 0)", "felt_mass_kg"),
    ("felt damping (K = 0)", "felt_damping_N_s_per_m"),
    ("largest K stable, any hand", "max_stable_K_all_hands_N_per_m"),
    ("largest K stable, hands off", "max_stable_K_hands_off_N_per_m"),
)


def test_evaluate_hand_block_backdrive_and_felt_rows_read_back(evaluated):
    """With a hand on the lever: the backdrive force (41.64 mN on the paper pair), felt
    mass and damping, the stiffness limits: value, unit after the two columns, JSON."""
    text, js = evaluated
    mr, em = js["hand"]["mr"], js["hand"]["motor"]
    for label, key in HAND_BLOCK:
        cells = row(text, label)
        unit = cells[2].rstrip(",")
        check_cells(cells, unit, [mr[key], em[key]], label)
    cells = row(text, "backdrive force (K = 0)")
    assert cells[2] == "mN" and cells[1].startswith("139.")  # the motor's, as worked: 139.7
    rest = " ".join(cells[3:])
    m = re.match(r"at ±(\S+) (\S+), (\S+) (\S+)$", rest)
    assert m, rest
    assert agrees(m.group(1), m.group(2), mr["motion"]["amplitude_m"])
    assert agrees(m.group(3), m.group(4), mr["motion"]["frequency_hz"])


def test_evaluate_zwidth_rows_read_back(evaluated):
    text, js = evaluated
    zw = js["zwidth"]
    for label, key in (("largest K at B = 0 (N/m)", "K_max_at_B0_N_per_m"),
                       ("largest B at K = 0 (N·s/m)", "B_max_at_K0_N_s_per_m"),
                       ("area ∫ΔK dB (N²·s/m²)", "zwidth_area_N2_s_per_m2")):  # fmt: skip
        check_cells(row(text, label), label_unit(label), [zw["mr"][key], zw["motor"][key]], key)


def test_evaluate_robust_table_and_ranges_read_back(evaluated):
    """Nominal, worst and best of each verdict, and the box's ranges line (m1 in g, b1 in
    N·s/m, the delay in ms, K_max in N/m) against robust/… of the JSON."""
    text, js = evaluated
    r = js["robust"]
    for label, key in (("largest stable K (N/m)", "max_stable_K_N_per_m"),
                       ("largest passive K (N/m)", "max_passive_K_N_per_m"),
                       ("bandwidth at K_max (Hz)", "bandwidth_hz"),
                       ("rendering area (dB·decade)", "rendering_area_dB_decade"),
                       ("Z-width area (N²·s/m²)", "zwidth_area_N2_s_per_m2")):  # fmt: skip
        hits = [ln for ln in text.splitlines() if ln.strip().startswith(label)]
        cells = [c for ln in hits for c in [ln.split(label, 1)[1].split()] if len(c) == 3]
        assert len(cells) == 1, f"{label}: {len(cells)} three-column rows"
        check_cells(cells[0], label_unit(label), [r[key][c] for c in ("nominal", "worst",
                                                                      "best")], key)  # fmt: skip
    line = next(ln for ln in text.splitlines() if ln.strip().startswith("ranges:"))
    got = {m.group(1): m.groups()[1:] for m in
           re.finditer(r"(m1|b1|delay|K_max) (\S+)–(\S+) ([^\s,(]+)", line)}  # fmt: skip
    assert set(got) == {"m1", "b1", "delay", "K_max"}, line
    for name, key in (("m1", "m1_kg"), ("b1", "b1_N_s_per_m"), ("delay", "delay_s"),
                      ("K_max", "K_max_N_per_m")):  # fmt: skip
        lo, hi, unit = got[name]
        assert agrees(lo, unit, r["ranges"][key][0]), (name, lo, unit)
        assert agrees(hi, unit, r["ranges"][key][1]), (name, hi, unit)


def test_evaluate_measured_rows_read_back(evaluated):
    """Model against the bench: model, measured (unit in the label) and the error in %."""
    text, js = evaluated
    assert js["measured"], "the paper preset carries the paper's bench"
    for m in js["measured"]:
        hits = [ln for ln in text.splitlines() if ln.strip().startswith(m["quantity"] + " (")]
        assert len(hits) == 1, m["quantity"]
        label, rest = hits[0].strip().split(") ", 1)
        unit = label.rsplit("(", 1)[1]
        cells = rest.split()
        check_cells(cells, unit, [m["model"], m["measured"]], m["quantity"])
        assert cells[3] == "%" and agrees(cells[2], "%", m["error"]), m["quantity"]


def test_evaluate_budget_rows_read_back(evaluated):
    """b1 and m1 of the MR pair as terms: each term's value (unit in the block's title) and
    share, the total, Table 2's value and what is unexplained."""
    text, js = evaluated
    lines = text.splitlines()
    for key, title in (("b1_N_s_per_m", "b1 of the MR pair at the hand"),
                       ("m1_kg", "m1 of the MR pair at the hand")):  # fmt: skip
        b = js["budget"][key]
        start = next(i for i, ln in enumerate(lines) if ln.startswith(title))
        unit = label_unit(lines[start])
        block = "\n".join(lines[start + 1 : start + 3 + len(b["terms"]) + 3])
        for t in b["terms"]:
            cells = row(block, t["name"])
            check_cells(cells, unit, [t["value"]], t["name"])
            assert cells[2] == "%" and agrees(cells[1], "%", t["share"]), t["name"]
        for label, v in (("total", b["total"]), ("paper, Table 2", b["paper_table2"]),
                         ("unexplained", b["unexplained"])):  # fmt: skip
            check_cells(row(block, label), unit, [v], label)


def test_evaluate_response_rows_read_back(evaluated):
    text, js = evaluated
    r = js["response"]
    for label, key in (("electrical (10–90 % / ln 9)", "electrical_time_constant_s"),
                       ("eddy currents", "eddy_time_constant_s"),
                       ("fluid (assumed)", "fluid_time_constant_s"),
                       ("equivalent delay Σ T", "torque_delay_s")):  # fmt: skip
        cells = row(text, label)
        check_cells(cells, cells[1], [r[key]], key)
    for part, e in r["eddy"].items():
        cells = row(text, part)
        check_cells(cells, cells[1], [e["contribution_s"]], part)


# ---- compare and haptic: "name value unit" runs on a line -------------------------------

_PAIRS = (("m1", "m1_kg"), ("m2", "m2_kg"), ("b1", "b1_N_s_per_m"), ("k", "k_N_per_m"),
          ("b", "b_N_s_per_m"), ("delay", "delay_s"), ("bandwidth", "bandwidth_hz"),
          ("lumped", "bandwidth_lumped_hz"), ("resonance", "resonance_hz"),
          ("rendering area", "rendering_area_dB_decade"))  # fmt: skip


def check_metrics(block: str, m: dict, where: str) -> None:
    """``_print_metrics``' three lines: each "name value unit" against the side's JSON;
    "up to X N/m" (passive) and "stable up to X N/m"."""
    for name, key in _PAIRS:
        hit = re.search(r"(?:^|[\s(])" + re.escape(name) + r" (\S+)(?: ([^\s,)\[]+))?", block)
        assert hit, f"{where}: no {name!r}"
        value, unit = hit.group(1), hit.group(2) or ""
        if m[key] is None:
            assert value.rstrip(",") == "none", f"{where}: {name} {value} for a null"
            continue
        assert agrees(value, unit, m[key]), f"{where}: {name} {value} {unit}, JSON {m[key]}"
    hit = re.search(r"\(up to (\S+) (\S+)\), stable up to (\S+) (\S+)$", block, re.M)
    assert hit, f"{where}: no limits line"
    assert agrees(hit.group(1), hit.group(2).rstrip(")"), m["max_passive_K_N_per_m"])
    assert agrees(hit.group(3), hit.group(4), m["max_stable_K_N_per_m"])
    assert ("NOT passive" not in block) == m["passive"]
    k = re.search(r"\bK(?:_max)? (\S+) N/m", block)
    assert k and agrees(k.group(1), "N/m", m["K_N_per_m"]), where


def test_compare_text_reads_back_to_its_json(capsys):
    """Both sides of ``compare`` (the paper's Table 2 MR pair and the Maxon 136206), then
    the gains of the closing sentence (52.4 % lumped, 50.4 % full on the paper pair)."""
    text, js = _run(capsys, "compare")
    lines = text.splitlines()
    i_mr = next(i for i, ln in enumerate(lines) if ln.startswith("MR pair"))
    i_em = next(i for i, ln in enumerate(lines) if ln.startswith("Maxon 136206"))
    check_metrics("\n".join(lines[i_mr + 1 : i_em]), js["mr"], "compare MR")
    check_metrics("\n".join(lines[i_em + 1 : i_em + 4]), js["em"], "compare EM")
    tail = lines[i_em + 4]
    m = re.search(r"renders (\S+) % more lumped bandwidth.*?, (\S+) % on the full model.*?"
                  r"\((\S+) % without\)", tail)  # fmt: skip
    assert m, tail
    assert agrees(m.group(1), "%", js["bandwidth_gain_lumped"])
    assert agrees(m.group(2), "%", js["bandwidth_gain"])
    assert agrees(m.group(3), "%", js["bandwidth_gain_mr_without_delay"])
    d = re.search(r"damping b1 is (\S+)× the motor's", tail)
    assert d and agrees(d.group(1), "", js["damping_ratio_mr_over_em"])


@pytest.mark.parametrize("argv", [("haptic",), ("haptic", "--actuator", "maxon-136206",
                                                "--stiffness", "500")])  # fmt: skip
def test_haptic_text_reads_back_to_its_json(capsys, argv):
    text, js = _run(capsys, *argv)
    lines = text.splitlines()
    check_metrics("\n".join(lines[1:4]), js, " ".join(argv))


# ---- optimize: the printed optimum against the data its --json prints ---------------------


@pytest.fixture(scope="module")
def optimized():
    """``optimize --objective bandwidth --drums 1``, text, and the dict the same run hands
    to both the printer and ``--json`` (caught on its way to the printer, then printed
    as ``--json`` prints it: one optimisation, not two)."""
    from mrclutch.cli.commands import _common
    from mrclutch.cli.commands import optimize as cmd

    seen: list[dict] = []
    original = cmd._print_optimum

    def spy(*args, **kwargs):
        seen.extend(a for a in (*args, *kwargs.values())
                    if isinstance(a, dict) and "objective_column" in a)  # fmt: skip
        return original(*args, **kwargs)

    mp = pytest.MonkeyPatch()
    mp.setattr(cmd, "_print_optimum", spy)
    try:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            assert main(["optimize", "--objective", "bandwidth", "--drums", "1"]) == 0
    finally:
        mp.undo()
    assert len(seen) == 1
    js = io.StringIO()
    with contextlib.redirect_stdout(js):
        _common.print_json(seen[0])
    return buf.getvalue(), json.loads(js.getvalue())


def _between(text: str, start: str, stop: str) -> str:
    """The lines after the line ``start`` up to the first line starting with ``stop``."""
    lines = text.splitlines()
    i = lines.index(start)
    j = next((k for k in range(i + 1, len(lines)) if lines[k].startswith(stop)), len(lines))
    return "\n".join(lines[i + 1 : j])


def test_optimize_objective_and_per_drum_count_read_back(optimized):
    text, js = optimized
    key = js["objective_column"]
    m = re.search(r"^objective \S+ \(" + re.escape(key) + r", \w+\): (\S+) on the fast path",
                  text, re.M)  # fmt: skip
    assert m and agrees(m.group(1), "", js["objective_value"])
    for k, v in js["best_per_drum_count"].items():
        m = re.search(rf"best with {k} drum\(s\): {re.escape(key)} (\S+)$", text, re.M)
        assert m and agrees(m.group(1), "", v), k


def test_optimize_evaluations_read_back(optimized):
    """The fast path's and the reference fidelity's clutch and hand rows, as evaluate's."""
    text, js = optimized
    for header, side in (("fast path:", "fast"), ("reference fidelity:", "reference")):
        block = _between(text, header, "reference fidelity:" if side == "fast" else "bandwidth,")
        ev = js[side]
        for key in CLUTCH_ROWS:
            cells = row(block, output(key).label)
            check_cells(cells, cells[1], [ev["clutch"][key]], f"{side} {key}")
        hand = section(block, "at the hand")
        for key in HAND_ROWS:
            label = row_label(key)
            check_cells(row(hand, label), label_unit(label) or "",
                        [ev["haptic"][key], ev["motor"][key]], f"{side} {key}")  # fmt: skip


def test_optimize_verdict_reads_back(optimized):
    text, js = optimized
    v = js["verdict"]
    m = re.search(r"haptic verdict \((\w+) fidelity\) at K = (\S+) N/m", text)
    assert m and m.group(1) == v["fidelity"] and agrees(m.group(2), "N/m", v["K_N_per_m"])
    h = (js.get("reference") or js["fast"])["haptic"]  # the limits printed beside it
    for word, key in (("stable", "max_stable_K_N_per_m"), ("passive", "max_passive_K_N_per_m")):
        m = re.search(rf"largest {word} K (\S+) N/m", text.split("haptic verdict", 1)[1])
        assert m and agrees(m.group(1), "N/m", h[key]), word
    m = re.search(r"bandwidth, reference vs fast: (\S+) %", text)
    assert m and agrees(m.group(1), "%", js["bandwidth_change_reference_vs_fast"])
