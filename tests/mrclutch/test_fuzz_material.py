"""The fuzzer's plausible fluid files (benchmarks/fuzz_cli.py, issue 44 item 6): one of
the library's fluids with a few fields moved inside their physical ranges loads, and the
fast commands answer it with no NaN and every null with its reason; a plausible file
refused is counted as a failure, not as a clean refusal."""

from __future__ import annotations

import random
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

import geometry.materials as gm
import magnetics.materials as mm


@pytest.fixture
def registry():
    """The material registry as it was: the fluids these tests load are removed after."""
    tables = (gm._RECORDS, gm._DENSITY, gm._LABEL, gm._COLOUR, gm._KIND, mm._MATERIALS,
              mm._FLUIDS)  # fmt: skip
    saved = [dict(t) for t in tables]
    yield
    for t, s in zip(tables, saved, strict=True):
        t.clear()
        t.update(s)


def test_plausible_fluid_files_move_fields_inside_their_ranges(fuzz):
    """Each draw differs from the library fluid it started from in at least one field, and
    every moved number stays in the physical range the draw promises (a B–H table scaled
    in B alone fell below μ0 near saturation: draw 57 of seed 44, rightly refused)."""
    library = {p.stem: tomllib.loads(p.read_text()) for p in fuzz.LIBRARY_FLUIDS}
    for k in range(40):
        text, (lo, hi) = fuzz.plausible_fluid(random.Random(f"range-{k}"), k)
        rec = tomllib.loads(text)
        assert rec["name"] == f"fuzz_fluid_{k}" and lo < hi
        assert 2000.0 <= rec["density"] <= 4500.0 or rec["density"] in {
            r["density"] for r in library.values()}  # fmt: skip
        assert 1e-3 <= rec["viscosity"] <= 10.0 and 0.0 < rec["phi"] < 0.64
        if "b" in rec["bh"]:  # B = μ0 (H + f M): every slope of the table still >= μ0
            slopes = np.diff(rec["bh"]["b"]) / np.diff(rec["bh"]["h"])
            assert slopes.min() >= 4e-7 * np.pi * (1 - 1e-9), k
        changed = [
            key for key in fuzz.FLUID_MOVES
            if all(rec.get(key) != r.get(key) for r in library.values())
        ]  # fmt: skip
        assert changed, k


def test_about_a_third_of_material_draws_are_plausible(fuzz, tmp_path):
    """PLAUSIBLE_FRACTION (0.3) of 200 draws: 60 expected, σ = √(200·0.3·0.7) ≈ 6.5."""
    n = sum(
        Path(fuzz.make_material(random.Random(f"frac-{k}"), tmp_path, k)[1]).name.startswith(
            "mpd")
        for k in range(200)
    )  # fmt: skip
    assert 35 <= n <= 85


def test_plausible_fluid_files_are_answered_without_nan_or_unexplained_null(
    fuzz, tmp_path, registry
):
    """Six draws (evaluate --fidelity fast --no-uncertainty --json, or torque --json), each
    through the fuzzer's own checks: exit 0, no NaN, every null with its reason."""
    bad = []
    for k in range(6):
        argv = fuzz.make_plausible_material(random.Random(f"answer-{k}"), tmp_path, k)
        assert argv[0] in ("evaluate", "torque") and "--json" in argv
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            result = fuzz.run_input("material", argv, 120.0, tmp_path)
        if result != ("ok", "0"):
            bad.append((result, argv, Path(argv[1]).read_text()))
    assert not bad, bad


def test_a_plausible_fluid_file_refused_is_a_failure(fuzz, tmp_path):
    argv = ["evaluate", str(tmp_path / "mpd3.toml"), "--fidelity", "fast", "--json"]
    cls, detail = fuzz.check_input("material", argv, 2, "", tmp_path)
    assert cls == "refused" and "plausible fluid file refused" in detail
    hostile = ["evaluate", str(tmp_path / "md3.toml"), "--fidelity", "fast"]
    assert fuzz.check_input("material", hostile, 2, "", tmp_path) is None


def test_a_fluid_with_almost_no_iron_is_refused_by_name(fuzz, tmp_path, capsys, registry):
    """Found by the fuzzer (seed 45, input 980): phi = 1e-300 loaded, its yield torque
    underflowed to 0 and the feel figures divided by it (ZeroDivisionError). phi below
    magnetics.materials.PHI_MIN (1 %) is refused: one line naming phi, exit 2."""
    from mrclutch.cli.main import main

    text = fuzz.FLUID_FILE.read_text().replace('name = "mrf_132dg"', 'name = "no_iron"')
    mat = tmp_path / "f.toml"
    mat.write_text(text.replace("phi = 0.32", "phi = 1e-300"))
    design = tmp_path / "d.toml"
    design.write_text(f'[clutch]\nbase = "paper"\n[materials]\nfluid_file = "{mat}"\n')
    assert main(["evaluate", str(design), "--fidelity", "fast", "--json"]) == 2
    err = capsys.readouterr().err
    assert "phi = 1e-300" in err and "[0.01, 0.64)" in err and len(err.splitlines()) == 1
    mat.write_text(text.replace("phi = 0.32", "phi = 0.01"))  # the bound itself loads
    assert main(["torque", str(design), "--method", "circuit", "--json"]) == 0
