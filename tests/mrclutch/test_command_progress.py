"""The long commands say how far they are on stderr (issue 40 item 3): ``optimize`` its
generations, then its reference checks; ``report`` each step as it starts. The progress
comes from callbacks the application layer calls; ``--json`` keeps stdout the JSON alone."""

from __future__ import annotations

import json
from types import SimpleNamespace

from mrclutch.cli.commands import optimize as optimize_cmd
from mrclutch.cli.commands import optimize_pareto as pareto_cmd
from mrclutch.cli.commands import report_command
from mrclutch.cli.main import main
from mrclutch.design import design_preset
from mrclutch.optimize import optimize


def test_optimize_reports_each_generation_and_each_drum_count():
    """Differential evolution over 2 drum counts, maxiter 3: the count rises by one a
    generation, never falls, ends at 3 × 2 = 6 (a converged search jumps to its end); the
    optimum is the same with or without a callback."""
    seen: list[tuple[int, int]] = []
    kw = dict(drum_counts=(1, 2), maxiter=3, popsize=5)
    with_cb = optimize(design_preset("paper"), **kw, progress=lambda n, t: seen.append((n, t)))
    assert {t for _, t in seen} == {6} and seen[-1] == (6, 6)
    counts = [n for n, _ in seen]
    assert counts == sorted(counts) and counts[0] == 1
    assert 3 in counts  # the first drum count's end
    plain = optimize(design_preset("paper"), **kw)
    assert (plain.value, plain.evaluations) == (with_cb.value, with_cb.evaluations)


def test_optimize_objective_progress_on_stderr_json_alone_on_stdout(capsys, monkeypatch):
    real = optimize_cmd.optimize
    monkeypatch.setattr(optimize_cmd, "optimize",
                        lambda *a, **k: real(*a, **k, maxiter=4, popsize=5))  # fmt: skip
    argv = ["optimize", "--objective", "bandwidth", "--drums", "1", "--tries", "1",
            "--no-verify", "--json"]  # fmt: skip
    assert main(argv) in (0, 3)
    cap = capsys.readouterr()
    assert "optimize: generations" in cap.err and "60/60" in cap.err  # scaled to the bar
    assert "optimize: candidates checked at fast fidelity" in cap.err and "1/1" in cap.err
    assert json.loads(cap.out)["objective"] == "bandwidth"  # nothing else on stdout
    assert main([*argv, "--no-progress"]) in (0, 3)
    cap = capsys.readouterr()
    assert cap.err == "" and json.loads(cap.out)["objective"] == "bandwidth"


def test_optimize_pareto_progress_on_stderr_json_alone_on_stdout(capsys, monkeypatch):
    real = pareto_cmd.pareto
    monkeypatch.setattr(pareto_cmd, "pareto",
                        lambda *a, **k: real(*a, **{**k, "pop_size": 24, "generations": 6,
                                                    "members": 2}))  # fmt: skip
    argv = ["optimize", "--drums", "2", "--seed", "3", "--nominal", "--no-verify", "--json"]
    assert main(argv) in (0, 3)
    cap = capsys.readouterr()
    assert "optimize: generations" in cap.err and "optimize: members checked" in cap.err
    assert json.loads(cap.out)["mode"] == "pareto"


def test_report_says_each_step_on_stderr(capsys, monkeypatch, tmp_path):
    """Each step the report writer announces is one line on stderr, numbered of 9, the bar
    beside it; stdout keeps the verdict and where the report is."""
    names = [f"step {i}" for i in range(1, 10)]

    def fake_write_report(design, out, *, fidelity, progress):
        for name in names:
            progress(name)
        return SimpleNamespace(metrics={"verdict": {"line": "VERDICT: PASS"}}, out_dir=out,
                               files=("report.html",))  # fmt: skip

    monkeypatch.setattr(report_command, "write_report", fake_write_report)
    assert main(["report", "--out", str(tmp_path / "r"), "--fidelity", "fast"]) == 0
    cap = capsys.readouterr()
    for i, name in enumerate(names, 1):
        assert f"mrclutch report: step {i}/9: {name}\n" in cap.err
    assert "9/9" in cap.err
    assert cap.out.splitlines()[0] == "VERDICT: PASS" and len(cap.out.splitlines()) == 2
    assert main(["report", "--out", str(tmp_path / "r"), "--fidelity", "fast",
                 "--no-progress"]) == 0  # fmt: skip
    assert capsys.readouterr().err == ""
