"""Issue 39: one design, one answer. A design file holds how it renders (`[render]`) and every
command that judges it — evaluate, report, compare, haptic, optimize — gives the same K,
K_max and verdict at one fidelity, leading with one verdict line."""

import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from geometry.params import PRESETS
from geometry.validation import ParameterError
from mrclutch.cli.commands import optimize as optimize_cmd
from mrclutch.cli.commands import optimize_pareto as pareto_cmd
from mrclutch.cli.main import main
from mrclutch.design import design_from_mapping, design_preset, design_to_toml, load_design
from mrclutch.hot_range import resolved_ranges
from mrclutch.render import Render
from mrclutch.verdict import inside, judge, verdict_of

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
QUICK = dict(pop_size=24, generations=6, members=3)


def _run(capsys, argv):
    code = main(argv)
    return code, capsys.readouterr()


def _json(capsys, argv):
    code, cap = _run(capsys, [*argv, "--json"])
    assert code == 0, cap.err
    return json.loads(cap.out)


def _triple(data):
    """(status, K, K_max) of a judged design's JSON."""
    v = data["verdict"]
    return v["status"], v["K_N_per_m"], v["K_max_N_per_m"]


# ---- `[render]` in the design file ---------------------------------------------------------


@pytest.mark.parametrize("render", [Render(), Render("worst_case"), Render("typed", 123.4),
                                    Render("K_max", verdict="nominal")])  # fmt: skip
def test_render_table_reads_back(render, tmp_path):
    d = replace(design_preset("paper"), render=render)
    p = tmp_path / "d.toml"
    p.write_text(design_to_toml(d))
    assert load_design(p).render == render


@pytest.mark.parametrize(("table", "phrase"), [
    ({"rule": "loudest"}, "render.rule = 'loudest': must be one of K_max, worst_case, typed"),
    ({"rule": "typed"}, "give render.K_N_per_m"),
    ({"rule": "K_max", "K_N_per_m": 100}, "only with rule = 'typed'"),
    ({"K_N_per_m": -3}, "render.K_N_per_m = -3"),
    ({"K_N_per_m": "stiff"}, "must be a number"),
    ({"verdict": "optimistic"}, "must be one of robust, nominal"),
    ({"colour": "red"}, "render.colour: unknown key"),
])  # fmt: skip
def test_bad_render_tables_are_refused_naming_the_key(table, phrase, tmp_path, capsys):
    with pytest.raises(ParameterError, match=re.escape(phrase)):
        design_from_mapping({"clutch": {"base": "paper"}, "render": table}, "d.toml")
    p = tmp_path / "d.toml"
    lines = [f"{k} = {json.dumps(v)}" for k, v in table.items()]
    p.write_text('[clutch]\nbase = "paper"\n[render]\n' + "\n".join(lines) + "\n")
    code, cap = _run(capsys, ["evaluate", str(p)])
    assert code == 2 and cap.err.count("\n") == 1 and "render" in cap.err


def test_a_typed_K_is_rendered_and_judged_there():
    """K typed in `[render]` is the K every figure at the hand is taken at; K_max is still
    F_max/d; the verdict's K is the typed one."""
    d = replace(design_preset("paper"), render=Render("typed", 100.0))
    data = judge(d, robust=False)
    assert data["haptic"]["K_N_per_m"] == data["motor"]["K_N_per_m"] == 100.0
    plain = judge(design_preset("paper"), robust=False)
    assert data["haptic"]["K_max_N_per_m"] == plain["haptic"]["K_max_N_per_m"]
    assert plain["haptic"]["K_N_per_m"] == plain["haptic"]["K_max_N_per_m"]
    # below the nominal largest stable and passive K (≈ 251 N/m) the nominal verdict passes
    assert data["verdict"]["status"] == "pass" and plain["verdict"]["status"] == "fail"


def test_worst_case_rule_renders_the_largest_K_that_holds_over_the_ranges():
    d = replace(design_preset("paper"), render=Render("worst_case"))
    data = judge(d)
    r = data["robust"]
    cap = min(r["max_stable_K_N_per_m"]["worst"], r["max_passive_K_N_per_m"]["worst"])
    assert data["haptic"]["K_N_per_m"] == pytest.approx(cap, rel=2e-6)
    assert data["haptic"]["K_N_per_m"] <= cap
    assert data["verdict"]["status"] == "pass"
    assert data["verdict"]["stable"]["holds"] == data["verdict"]["passive"]["holds"] == "always"


# ---- the one verdict ---------------------------------------------------------------------


def _data(stable, passive, thresholds=None):
    """A judged design's minimal JSON: verdicts as robust_verdicts gives them."""
    th = thresholds or {}
    return {
        "haptic": {"K_N_per_m": 300.0, "K_max_N_per_m": 300.0, "delay_s": 1e-3,
                   "max_stable_K_N_per_m": 250.0, "passive": False},
        "robust": {"verdicts": {
            "stable": {"nominal": False, "holds": stable, "thresholds": th},
            "passive": {"nominal": False, "holds": passive, "thresholds": {}}}},
        "fidelity": "fast", "source": "fast model", "response": {"delay_source": "fixed"},
        "hand": {"mr": {"note": "not computed here"}},
    }  # fmt: skip


def test_status_is_pass_only_when_both_hold_everywhere_and_fail_when_one_never_does():
    assert verdict_of(_data("always", "always"))["status"] == "pass"
    assert verdict_of(_data("never", "always"))["status"] == "fail"
    assert verdict_of(_data("always", "never"))["status"] == "fail"
    assert verdict_of(_data("depends", "always"))["status"] == "depends"
    assert verdict_of(_data("depends", "never"))["status"] == "fail"


def test_a_threshold_outside_its_range_is_not_named_as_deciding():
    """Issue 39: "stable only if b1 ≥ 9.18 N·s/m (outside its range 11.5–41.8)" named an
    input that every value of its range satisfies."""
    out = {"b1": {"value": 9.18, "sense": "≥", "range": [11.5, 41.8]}}
    inn = {"b1": {"value": 20.0, "sense": "≥", "range": [11.5, 41.8]}}
    assert not inside(out["b1"]) and inside(inn["b1"])
    v_out = verdict_of(_data("depends", "always", out))
    assert "9.18" not in v_out["line"] and "no one input decides it" in v_out["line"]
    assert v_out["stable"]["thresholds"] == {}
    v_in = verdict_of(_data("depends", "always", inn))
    assert "b1 ≥ 20 N·s/m (its range 11.5–41.8 N·s/m)" in v_in["line"]


def _verdict_lines(text):
    return [ln for ln in text.splitlines() if ln.startswith("VERDICT:")]


#: Every preset and every example design file (not the sweep specs): what a user runs first.
TARGETS = [f"--preset={n}" for n in PRESETS] + sorted(
    p.name for p in EXAMPLES.glob("*.toml") if "[sweep]" not in p.read_text()
)


def test_the_targets_are_every_preset_and_example():
    assert {"--preset=paper", "--preset=paper-holes", "thin_drums.toml",
            "paper_bench.toml"} <= set(TARGETS)  # fmt: skip


@pytest.mark.parametrize("target", TARGETS)
def test_commands_lead_with_one_verdict_and_agree(target, capsys, judged_once):
    """evaluate, compare and haptic on one design at one fidelity: the first line is the
    verdict, said once, the same line in each; their JSON gives the same K, K_max, status
    and gearing."""
    args = [target] if target.startswith("--") else [str(EXAMPLES / target)]
    texts, triples, gearing = _every_command(capsys, judged_once, args)
    assert len(set(texts)) == 1 and len(set(triples)) == 1 and len(set(gearing)) == 1


def _every_command(capsys, judged_once, args, report_dir=None):
    """The verdict line, (status, K, K_max) and the motor's gearing of one design from
    evaluate, compare, haptic (no motor) and, with ``report_dir``, report: each text leads
    with its one verdict line and prints the gearing its JSON gives. The three commands
    judge the design once (``judged_once``, tests/conftest.py), the report on its own."""
    texts, triples, gearing = [], [], []
    with judged_once():
        for cmd in ("evaluate", "compare", "haptic"):
            code, cap = _run(capsys, [cmd, *args])
            assert code == 0, cap.err
            lines = _verdict_lines(cap.out)
            assert len(lines) == 1 and cap.out.startswith("VERDICT:"), cap.out[:300]
            texts.append(lines[0])
            data = _json(capsys, [cmd, *args])
            triples.append(_triple(data))
            if cmd != "haptic":
                g = (data["motor"] if cmd == "evaluate" else data["em"])["gearing"]
                assert f"geared ×{g:.3g} to the MR pair's force" in cap.out, cmd
                gearing.append(g)
    if report_dir is not None:
        code, cap = _run(capsys, ["report", *args, "--out", str(report_dir), "--no-progress"])
        assert code == 0, cap.err
        metrics = json.loads((report_dir / "metrics.json").read_text())
        html = (report_dir / "report.html").read_text()
        texts += _verdict_lines(cap.out)
        triples.append(_triple(metrics))
        g = metrics["motor"]["gearing"]
        assert f"Motor geared ×{g:.3g} so both render" in html and 'id="verdict"' in html
        gearing.append(g)
    return texts, triples, gearing


@pytest.mark.slow
def test_paper_preset_one_K_max_and_gearing_per_fidelity_in_every_command(capsys, tmp_path,
                                                                          judged_once):  # fmt: skip
    """Issue 39: K_max was 367.3 N/m in evaluate, 361.7 in the report and 299.2 in compare,
    the motor geared ×1.23 in one and ×1.21 in another. At reference fidelity (the report's)
    evaluate, compare, haptic and report now give one verdict line, one (status, K, K_max)
    and one gearing; the fast path its own K_max (the network's torque), again one in all."""
    ref = _every_command(capsys, judged_once, ["--preset", "paper", "--fidelity", "reference"],
                         tmp_path / "rep")  # fmt: skip
    fast = _every_command(capsys, judged_once, ["--preset", "paper", "--fidelity", "fast"])
    for texts, triples, gearing in (ref, fast):
        assert len(texts) == len(triples) and len(set(texts)) == 1
        assert len(set(triples)) == 1 and len(set(gearing)) == 1
    assert len(ref[1]) == 4 and len(ref[2]) == 3  # the four commands; three with a motor
    assert ref[1][0][2] != fast[1][0][2]  # one K_max per fidelity: FEM against network
    assert "reference model" in ref[0][0] and "fast model" in fast[0][0]


def test_evaluate_no_uncertainty_is_nominal_and_says_so(capsys):
    data = _json(capsys, ["evaluate", "--preset", "paper", "--no-uncertainty"])
    assert data["verdict"]["over"] == "nominal" and data["robust"] is None
    assert "not asked" in data["nulls"]["robust"]


# ---- the user's path: optimize → files → every command ----------------------------------


@pytest.fixture(scope="module")
def members(tmp_path_factory):
    """A small seeded Pareto run at reference fidelity writing its members."""
    folder = tmp_path_factory.mktemp("members")
    mp = pytest.MonkeyPatch()
    real = pareto_cmd.pareto
    mp.setattr(pareto_cmd, "pareto", lambda *a, **k: real(*a, **{**k, **QUICK}))
    try:
        import io
        from contextlib import redirect_stdout

        buf = io.StringIO()
        with redirect_stdout(buf):
            code = main(["optimize", "--preset", "paper", "--drums", "2", "--seed", "3",
                         "--designs", str(folder), "--json"])  # fmt: skip
    finally:
        mp.undo()
    assert code == 0
    return folder, json.loads(buf.getvalue())


@pytest.mark.slow
def test_members_get_the_optimisers_verdict_K_and_K_max_from_every_command(
    members, capsys, tmp_path, judged_once
):
    """Every member's file through evaluate, compare and haptic at reference fidelity, and
    the first member's through the report too (the report of each further member, ~20 s of
    CPU, ran the same code on another design of the same rule and status: pass, worst
    case), gives the optimiser's (status, K, K_max)."""
    folder, opt = members
    files = sorted(folder.glob("member_*.toml"))
    assert len(files) >= 2 and len(files) == len(opt["designs_written"])  # two members or more
    by_member = {r["member"]: r for r in opt["members"]}
    for f in files:
        d = load_design(f)
        assert d.measured is None and d.render.rule == "worst_case"  # no inherited bench
        row = by_member[int(f.stem.split("_")[1])]["reference"]
        want = _triple(row)
        assert want[0] == "pass"  # kept members hold over the ranges
        report = tmp_path / f.stem if f == files[0] else None
        texts, triples, gearing = _every_command(capsys, judged_once,
                                                 [str(f), "--fidelity", "reference"],
                                                 report)  # fmt: skip
        n = 4 if report else 3  # the four commands (three without the report)
        assert set(triples) == {want} and len(triples) == n, f.name
        assert len(set(texts)) == 1 and len(set(gearing)) == 1, f.name
        if report is None:
            continue
        metrics = json.loads((report / "metrics.json").read_text())
        html = (report / "report.html").read_text()
        assert html.count('id="verdict"') == 1 and "Verdict: PASS" in html
        assert texts[0] == metrics["verdict"]["line"]
    assert opt["notes"] and "[measured]" in opt["notes"][0]


def test_designs_folder_of_an_earlier_run_needs_overwrite(members, capsys, monkeypatch):
    folder, _ = members
    (folder / "member_99.toml").write_text("stale")
    code, cap = _run(capsys, ["optimize", "--preset", "paper", "--designs", str(folder)])
    assert code == 2 and "--overwrite" in cap.err and cap.err.count("\n") == 1
    real = pareto_cmd.pareto
    monkeypatch.setattr(pareto_cmd, "pareto", lambda *a, **k: real(*a, **{**k, **QUICK}))
    code, cap = _run(capsys, ["optimize", "--preset", "paper", "--drums", "2", "--seed", "3",
                              "--designs", str(folder), "--overwrite", "--no-verify"])  # fmt: skip
    assert code == 0, cap.err
    assert not (folder / "member_99.toml").exists()


@pytest.mark.slow
def test_objective_out_file_gets_the_optimisers_verdict(tmp_path, capsys, monkeypatch):
    real = optimize_cmd.optimize
    monkeypatch.setattr(optimize_cmd, "optimize",
                        lambda *a, **k: real(*a, **k, maxiter=6, popsize=6))  # fmt: skip
    out = tmp_path / "best.toml"
    data = _json(capsys, ["optimize", "--objective", "bandwidth", "--drums", "2", "--tries",
                          "1", "--out", str(out)])  # fmt: skip
    d = load_design(out)
    assert d.render.rule == "worst_case" and d.measured is None
    assert design_preset("paper").measured is not None  # the base had a bench: said dropped
    assert [n for n in data["notes"] if "[measured] bench table was dropped" in n]
    want = _triple(data["reference"])
    assert data["verdict"]["status"] == want[0]
    for cmd in ("evaluate", "compare"):
        assert _triple(_json(capsys, [cmd, str(out), "--fidelity", "reference"])) == want


def test_optimize_help_states_the_rule_its_files_carry(capsys):
    """Issue 39: "two optimiser modes, two rules": the optimiser's own help said every design
    is held stable and passive "at K = K_max" while both modes render (and write into
    [render]) the worst case over the ranges; --nominal is the K_max mode."""
    with pytest.raises(SystemExit):
        main(["optimize", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "K = K_max (Eq. 4). Each" not in text and "at K_max (required" not in text
    assert "at the K each design renders: by default the largest K that stays so over the " \
           "uncertainty ranges" in text  # fmt: skip
    assert "bandwidth (rendering bandwidth at the K the design renders, Hz)" in text


def test_the_paper_beside_a_member_says_which_rule_renders_its_K():
    """Beside a member the optimiser judges the paper preset by the members' rule (42.9 N/m,
    the worst case over the ranges), not the K_max evaluate prints for it (361.7 N/m at
    reference): the column says so, with the K_max its own file renders."""
    from mrclutch.cli.formatting import explain
    from mrclutch.verdict import for_workshop

    base = design_preset("paper")
    plain = judge(base)
    paper = judge(for_workshop(base, resolved_ranges(base))[0])
    k_max = plain["haptic"]["K_max_N_per_m"]
    assert paper["haptic"]["K_N_per_m"] < 0.5 * k_max == 0.5 * paper["haptic"]["K_max_N_per_m"]
    text = explain(plain, paper, "member #1")
    assert (f"(both by the optimiser's rule: the largest K stable and passive over the ranges; "
            f"the paper preset's own rule, K_max = F_max/d, renders {k_max:.4g} N/m, as "
            "evaluate --preset paper --fidelity fast prints)") in text  # fmt: skip
    assert "optimiser's rule" not in explain(plain, plain, "member #1")


# ---- numbers that look odd say why --------------------------------------------------------

#: Four drums on a Ø32.7 mm envelope with 0.2 mm gaps (issue 39's "Ø40 mm, 4-drum" case):
#: slipping unenergised at 530 rpm its films alone heat the fluid past 130 °C (zero
#: continuous rating), and the Maxon geared ×7.2 to its force has a bandwidth equal to its
#: transmission resonance (103.8 Hz against 104.8 Hz, lumped 6.9 Hz).
FOUR_DRUMS = """name = "four-drums"
[clutch]
base = "paper"
n_drums = 4
drum_inner_diameter_mm = 18
gap_mm = 0.2
drum_thickness_mm = 0.25
"""


def test_a_zero_continuous_rating_and_a_bandwidth_at_a_resonance_say_why(tmp_path, capsys):
    f = tmp_path / "four.toml"
    f.write_text(FOUR_DRUMS)
    data = _json(capsys, ["evaluate", str(f), "--no-uncertainty"])
    c, m = data["clutch"], data["motor"]
    assert c["continuous_current_A"] == 0.0 and c["continuous_torque_N_m"] == 0.0
    (zero,) = [n for n in c["notes"] if n.startswith("continuous rating 0")]
    assert c["idle_fluid_temperature_C"] > 130.0  # the limit the note names, exceeded
    assert (
        f"the fluid would settle at {c['idle_fluid_temperature_C']:.4g} °C, above its 130" in zero
    )
    assert abs(m["bandwidth_hz"] / m["resonance_hz"] - 1) <= 0.05
    assert m["bandwidth_hz"] > 10 * m["bandwidth_lumped_hz"]
    (res,) = [n for n in c["notes"] if "transmission resonance" in n]
    assert res.startswith("the Maxon 136206's full-response bandwidth 103.8 Hz")
    # compare prints it beside the gain it explains; the text of evaluate says both
    code, cap = _run(capsys, ["compare", str(f)])
    assert code == 0 and f"note: {res}" in cap.out.splitlines()
    assert _json(capsys, ["compare", str(f)])["notes"] == [res]
    code, cap = _run(capsys, ["evaluate", str(f), "--no-uncertainty"])
    assert f"note: {zero}" in cap.out.splitlines() and f"note: {res}" in cap.out.splitlines()
    # the paper preset has neither, and says neither
    paper = _json(capsys, ["evaluate", "--preset", "paper", "--no-uncertainty"])
    assert paper["clutch"]["continuous_current_A"] > 0
    assert not [n for n in paper["clutch"]["notes"] if "rating 0" in n or "resonance (" in n]
    assert _json(capsys, ["compare", "--preset", "paper"])["notes"] == []


def test_a_motor_that_cannot_be_geared_says_why_in_every_command(tmp_path, capsys):
    """A 250 mm drum needs the Maxon geared ×230 (its range: 0.01–100): evaluate and compare
    say which gearing it would need, and the MR pair is still judged."""
    f = tmp_path / "big.toml"
    f.write_text('name = "big"\n[clutch]\nbase = "paper"\ndrum_inner_diameter_mm = 250\n')
    code, cap = _run(capsys, ["evaluate", str(f), "--no-uncertainty"])
    assert code == 0 and "would need gearing = 230" in cap.out and "[0.01, 100]" in cap.out
    code, cap = _run(capsys, ["compare", str(f)])
    assert code == 0 and cap.out.startswith("VERDICT:")
    assert "Maxon 136206: unavailable: the equal-force maxon-136206 is left out" in cap.out
    assert "would need gearing = 230" in cap.out


# ---- torque: the current limit and --for -------------------------------------------------


def test_torque_for_finds_the_current_of_a_torque(capsys):
    """The network's current for 0.3 N·m on the paper preset gives 0.3 N·m back (Brent to
    1e-4 A; the curve's slope near 3 A is ~0.07 N·m/A, so within ~1e-5 N·m)."""
    from magnetics.torque import torque_curve

    data = _json(capsys, ["torque", "--preset", "paper", "--for", "0.3"])
    (row,) = data["methods"]
    i = row["current_A"]
    assert 0 < i < 7
    back = torque_curve(design_preset("paper").clutch, [i], method="network").torque[0]
    assert back == pytest.approx(0.3, abs=1e-4)
    # out of reach: the most, at the limit; below the drag: 0 A
    far = _json(capsys, ["torque", "--preset", "paper", "--for", "5"])["methods"][0]
    assert far["current_A"] is None and far["torque_at_limit_N_m"] < 5
    code, cap = _run(capsys, ["torque", "--preset", "paper", "--for", "5"])
    assert code == 0 and "out of reach: the most is" in cap.out and "at 7 A" in cap.out
    low = _json(capsys, ["torque", "--preset", "paper", "--for", "1e-6"])["methods"][0]
    assert low["current_A"] == 0.0


@pytest.mark.slow
def test_torque_for_answers_at_each_fidelity(capsys):
    """--method both: the fast path's (network) and the reference's (FEM) current for
    0.3 N·m on the paper preset, each giving 0.3 N·m back by its own method (Brent to 1e-4
    A at ~0.07 N·m/A), and each at the design's current limit the max torque evaluate
    prints at that fidelity."""
    from magnetics.torque import torque_curve

    rows = _json(capsys, ["torque", "--preset", "paper", "--for", "0.3", "--method", "both"])
    rows = {r["method"]: r for r in rows["methods"]}
    assert set(rows) == {"network", "fem"}
    clutch = design_preset("paper").clutch
    for method, fidelity in (("network", "fast"), ("fem", "reference")):
        i = rows[method]["current_A"]
        back = torque_curve(clutch, [i], method=method).torque[0]
        assert back == pytest.approx(0.3, abs=1e-4), method
        ev = _json(capsys, ["evaluate", "--preset", "paper", "--fidelity", fidelity,
                            "--no-uncertainty"])  # fmt: skip
        assert rows[method]["torque_at_limit_N_m"] == pytest.approx(
            ev["clutch"]["max_torque_N_m"], rel=1e-6), method  # fmt: skip
    assert rows["network"]["current_A"] != rows["fem"]["current_A"]


@pytest.mark.parametrize("argv", [
    ["--for", "-1"], ["--for", "0.3", "--current", "2"], ["--for", "nan"], ["--for", "abc"],
    ["--for", "0"], ["--for", "inf"], ["--for", "0.3", "--plot", "t.png"],
    ["--for", "0.3", "--method", "bogus"], ["--current", "-1"], ["--current", "20"],
])  # fmt: skip
def test_torque_bad_input_is_one_line_exit_2(argv, capsys):
    code, cap = _run(capsys, ["torque", "--preset", "paper", *argv])
    assert code == 2 and cap.err.count("\n") == 1 and cap.out == ""


def test_torque_applies_the_designs_current_limit(capsys):
    """thin_drums asks for 7 A but its wire allows 4.856 A: the default curve stops at the
    cap with evaluate's note; 7 A is refused unless --ignore-limit."""
    f = str(EXAMPLES / "thin_drums.toml")
    data = _json(capsys, ["torque", f])
    cap_a = load_design(f).current_limit
    assert data["points"][-1]["current_A"] == pytest.approx(cap_a)
    assert max(p["current_A"] for p in data["points"]) <= cap_a
    assert any("caps the current" in n for n in data["notes"])
    code, cap = _run(capsys, ["torque", f, "--current", "7"])
    assert code == 2 and "current limit" in cap.err and "--ignore-limit" in cap.err
    assert _json(capsys, ["torque", f, "--current", "7", "--ignore-limit"])["points"]


OFF_PAPER = """name = "off-paper"
[clutch]
base = "paper"
[operating]
input_speed_rpm = 1500
fluid_temperature_C = 60
[support]
seal_torque_mN_m = 5
"""


def test_torque_is_the_designs_at_its_own_speed_temperature_and_support(tmp_path, capsys):
    """One design, one torque: `torque` at the current limit is `evaluate`'s max torque (fast:
    the network) and its 0 A torque the off-state torque, at the design's input speed, fluid
    temperature and `[support]` drag. It was taken at 530 rpm, 20 °C and the default bearings
    whatever the file said (0.4272 against evaluate's 0.4309 N·m on this design)."""
    f = tmp_path / "d.toml"
    f.write_text(OFF_PAPER)
    clutch = _json(capsys, ["evaluate", str(f), "--no-uncertainty"])["clutch"]
    data = _json(capsys, ["torque", str(f), "--current", "0,7"])
    t0, t7 = (p["torque_N_m"] for p in data["points"])
    assert data["speed_rpm"] == 1500 and data["drag"]["fluid_temperature_C"] == 60
    assert t7 == pytest.approx(clutch["max_torque_N_m"], rel=1e-9)
    assert t0 == pytest.approx(clutch["off_state_torque_N_m"], rel=1e-9)
    row = _json(capsys, ["torque", str(f), "--for", "0.3"])["methods"][0]
    assert row["torque_at_limit_N_m"] == pytest.approx(clutch["max_torque_N_m"], rel=1e-9)
    # the options still override it, and then the torque differs
    other = _json(capsys, ["torque", str(f), "--current", "0", "--speed-rpm", "530",
                           "--fluid-temperature-C", "20"])["points"][0]["torque_N_m"]  # fmt: skip
    assert abs(other / t0 - 1) > 0.05


def test_torque_past_the_limit_says_so_when_asked_for(capsys):
    """--ignore-limit computes what is asked, and says it lies past the design's limit;
    --for's search then ends at 10× the limit, not called "the current limit"."""
    f = str(EXAMPLES / "thin_drums.toml")
    code, cap = _run(capsys, ["torque", f, "--current", "7", "--ignore-limit"])
    assert code == 0 and "7 A outside the design's current range [0, 4.856] A" in cap.out
    assert "--ignore-limit" in cap.out.splitlines()[0]
    assert _json(capsys, ["torque", f, "--current", "2", "--ignore-limit"])["notes"] == []
    code, cap = _run(capsys, ["torque", "--preset", "paper", "--for", "5", "--ignore-limit"])
    assert code == 0
    assert "at 70 A (the search's end, past the design's current limit 7 A)" in cap.out
    code, cap = _run(capsys, ["torque", "--preset", "paper", "--for", "5"])
    assert "at 7 A (the current limit)" in cap.out


@pytest.mark.parametrize("argv", [
    ["compare", "--preset", "paper", "--fidelity", "bogus"],
    ["compare", "--preset", "paper", "--stiffness", "100"],
    ["haptic", "--preset", "paper", "--actuator", "maxon-136206"],
    ["haptic", "--preset", "paper", "--delay-ms", "2"],
    ["compare", "/no/such/design.toml"],
])  # fmt: skip
def test_design_options_of_compare_and_haptic_refuse_bad_input_in_one_line(argv, capsys):
    code, cap = _run(capsys, argv)
    assert code == 2 and cap.err.count("\n") == 1 and cap.out == ""
