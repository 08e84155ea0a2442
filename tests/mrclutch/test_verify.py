"""``mrclutch sweep --verify-top N``: the N best rows re-solved by the FEM, end to end."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from magnetics.torque import torque_curve
from mrclutch.cli.main import main
from mrclutch.sweep import load_spec, read_results
from mrclutch.verify import design_of, fem_max_torque

SPEC = """
[sweep]
mode = "random"
samples = 40
seed = 3
base = "paper"
chunk_size = 16

[parameters]
gap_mm = {min = 0.3, max = 0.9}
n_drums = {min = 1, max = 3}
"""
FAST = ["--verify-fem-size-mm", "1"]  # a coarse FEM keeps the test quick


@pytest.fixture
def here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(SPEC)
    return tmp_path


def _rows(path: str) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_the_top_two_rows_are_re_solved_by_the_fem_and_written_beside_the_results(here, capsys):
    argv = ["sweep", "s.toml", "--out", "r.csv", "--no-progress", "--verify-top", "2", *FAST]
    assert main(argv) == 0
    out = capsys.readouterr().out
    res = read_results("r.csv")
    best = np.argsort(-res["max_torque_N_m"])[:2]  # the two largest torques (no ties here)
    rows = _rows("r.csv.verified.csv")
    assert [int(r["design_id"]) for r in rows] == [int(res["design_id"][i]) for i in best]
    spec, _ = load_spec("s.toml")
    for r, i in zip(rows, best, strict=True):
        assert r["fast_fidelity"].startswith("network") and r["fem_fidelity"] == "fem@1mm uniform"
        fast, fem = float(r["fast_max_torque_N_m"]), float(r["fem_max_torque_N_m"])
        assert fast == pytest.approx(res["max_torque_N_m"][i], rel=1e-9)
        assert float(r["relative_error"]) == pytest.approx(fast / fem - 1, rel=1e-12)
        assert float(r["torque_error_bound"]) == pytest.approx(res["torque_error_bound"][i])
        # the FEM number is the design's own: rebuilt from the spec and its id
        d = design_of(spec, _base(), int(r["design_id"]))
        assert d.clutch.n_drums == int(res["n_drums"][i])
        assert d.clutch.gap * 1e3 == pytest.approx(res["gap_mm"][i], rel=1e-6)
        assert fem == pytest.approx(fem_max_torque(d, 1e-3), rel=1e-9)
        # the single loop beside it, with the same drag, named as its own fidelity
        circ = float(r["circuit_max_torque_N_m"])
        assert r["circuit_fidelity"].startswith("circuit")
        op = d.operating
        assert circ == pytest.approx(
            float(
                torque_curve(
                    d.clutch,
                    [d.current_limit],
                    method="circuit",
                    speed_rpm=op.input_speed_rpm,
                    temperature=op.fluid_temperature,
                    support=d.support,
                ).torque[0]
            ),
            rel=1e-12,
        )
        assert float(r["circuit_relative_error"]) == pytest.approx(circ / fem - 1, rel=1e-12)
        from magnetics.error_map import circuit_error

        cb = circuit_error(d.clutch).bound
        assert float(r["circuit_error_bound"]) == pytest.approx(cb, rel=1e-12)
        assert r["circuit_within_bound"] == str(int(abs(circ / fem - 1) <= cb))
        assert r["design_id"] in out
    assert "network vs FEM: max |error|" in out and "r.csv.verified.csv" in out
    assert "circuit vs FEM: max |error|" in out


def _base():
    from mrclutch.design import design_preset

    return design_preset("paper")


def test_minimize_ranks_by_the_smallest_value_and_a_pool_gives_the_same_rows(here, capsys):
    base = ["sweep", "s.toml", "--no-progress", "--verify-top", "2", "--minimize",
            "--objective", "clutch_mass_kg", *FAST]  # fmt: skip
    assert main([*base, "--out", "a.csv"]) == 0
    assert main([*base, "--out", "b.csv", "--workers", "2"]) == 0
    res = read_results("a.csv")
    ids = [int(r["design_id"]) for r in _rows("a.csv.verified.csv")]
    masses = res["clutch_mass_kg"]
    assert sorted(masses[np.isin(res["design_id"], ids)]) == sorted(np.sort(masses)[:2])
    assert Path("a.csv.verified.csv").read_text() == Path("b.csv.verified.csv").read_text()
    assert all(r["objective"] == "clutch_mass_kg" for r in _rows("a.csv.verified.csv"))


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--objective", "max_torque_N_m"], "--objective: only with --verify-top N"),
        (["--verify-fem-size-mm", "1"], "--verify-fem-size-mm: only with --verify-top N"),
        (["--minimize"], "--minimize: only with --verify-top N"),
        (["--verify-top", "0"], "--verify-top = 0: must be >= 1"),
        (["--verify-top", "2", "--objective", "torque"], "--objective torque: not a column"),
        (["--verify-top", "2", "--verify-fem-size-mm", "nan"], "--verify-fem-size-mm = nan"),
        (["--verify-top", "2", "--verify-fem-size-mm", "0"], "must be in [0.02, 5] mm"),
    ],
)
def test_bad_verify_options_are_refused_before_the_sweep(here, capsys, extra, fragment):
    assert main(["sweep", "s.toml", "--out", "r.csv", "--no-progress", *extra]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err and err.count("\n") == 1, err
    assert not Path("r.csv").exists()


def test_the_default_fem_size_is_the_error_maps_reference():
    from magnetics.error_map import load

    assert math.isclose(load().reference_fem_size, 0.25e-3)
