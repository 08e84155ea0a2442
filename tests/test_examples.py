"""The examples a user starts from run, on tiny grids, and say something true."""

import runpy
from pathlib import Path

import numpy as np

from mrclutch.cli.main import main
from mrclutch.sweep import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _load(name):
    return runpy.run_path(str(EXAMPLES / name), run_name="example")


def test_gap_vs_thickness(tmp_path):
    r = _load("gap_vs_thickness.py")["main"](str(tmp_path), tiny=True)
    assert (tmp_path / "gap_vs_thickness.png").stat().st_size > 1000
    b1 = r["b1_N_s_per_m"].reshape(4, 4)
    assert np.all(np.diff(b1, axis=0) < 0)  # a wider gap drags less (Couette ∝ 1/g)


def test_drums_vs_diameter(tmp_path):
    r = _load("drums_vs_diameter.py")["main"](str(tmp_path), tiny=True)
    assert (tmp_path / "drums_vs_diameter.png").stat().st_size > 1000
    inertia = r["rotor_inertia_kg_m2"].reshape(2, 3)
    assert np.all(inertia[1] > inertia[0])  # a second drum adds inertia
    assert np.all(np.diff(inertia, axis=1) > 0)  # so does a larger diameter


def test_optimize_bandwidth_tiny():
    res = _load("optimize_bandwidth.py")["main"](tiny=True, verify=False)
    assert res["fast"]["clutch"]["max_torque_N_m"] >= 0.4 * (1 - 1e-9)


def test_random_sweep_spec_is_valid_and_runs_as_cli(tmp_path):
    spec, rest = load_spec(EXAMPLES / "random_sweep.toml")
    assert spec.n_designs == 100_000 and set(rest) == {"operating", "transmission"}
    small = tmp_path / "small.toml"
    small.write_text((EXAMPLES / "random_sweep.toml").read_text().replace("100000", "300"))
    out = tmp_path / "r.csv"
    argv = ["sweep", str(small), "--out", str(out), "--pareto", str(tmp_path / "p.png"),
            "--no-progress"]  # fmt: skip
    assert main(argv) == 0  # the CLI's entry, in this process (a process start saved)
    assert len(out.read_text().splitlines()) == 301
    assert (tmp_path / "p.png").stat().st_size > 1000


def test_readme_design_file_is_the_example_and_its_cap_is_noted(capsys):
    """README's design-file block is examples/thin_drums.toml, and evaluating it says that
    the current-density limit, not the typed 7 A, sets the current (issue 34)."""
    import json
    import re

    readme = (EXAMPLES.parent / "README.md").read_text()
    block = re.search(r'```toml\n(name = "thin-drums".*?)```', readme, re.S).group(1)
    assert block == (EXAMPLES / "thin_drums.toml").read_text()
    assert main(["evaluate", str(EXAMPLES / "thin_drums.toml"), "--json"]) == 0
    c = json.loads(capsys.readouterr().out)["clutch"]
    cap = 60e6 * np.pi * 0.321e-3**2 / 4  # 60 A/mm² in the 28 AWG wire (0.321 mm)
    assert abs(c["max_current_A"] / cap - 1) < 1e-9
    assert [n for n in c["notes"] if "current-density limit caps the current" in n]
