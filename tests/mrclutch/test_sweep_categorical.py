"""Issue 45 (and issue 39 item 6): a categorical axis (a part's material) goes through every
path a numeric axis takes. The matrix: 4 axis kinds (a length range, an integer range, a list
of values, a material) × 6 paths run per kind (the speed estimate of a sweep above 1000
designs; the rows in CSV and Parquet, read back; a nominal ``--with`` column; a worst-case
``--with`` column; ``--verify-top``'s design rebuilt from its id; ``--pareto`` drawn from
the file) = 24 cases, plus the paths run once on a spec holding all four kinds: a process
pool, a Dask cluster (a user's fluid file shipped to its workers), ``--verify-top`` by the
FEM through the CLI, and the optimiser with and without ``--nominal``."""

import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np
import pytest
from test_sweep_inputs import FLUID as FLUID_TEMPLATE

from mrclutch.design import design_from_mapping, design_preset
from mrclutch.pipeline import BatchEvaluator, evaluate
from mrclutch.robust import RobustBatchEvaluator
from mrclutch.sweep import load_spec, read_results, run_sweep
from mrclutch.verify import design_of

#: axis kind → (its `[parameters]` line, the DrumClutch field or part it sets, the values a
#: two-design grid takes, in the file's unit: mm, count, or registry name)
KINDS = {
    "length": ("gap_mm = {min = 0.3, max = 0.5, count = 2}", "gap", [0.3, 0.5]),
    "integer": ("n_drums = {min = 2, max = 3}", "n_drums", [2, 3]),
    "values": ("drum_thickness_mm = {values = [0.25, 0.3]}", "drum_thickness", [0.25, 0.3]),
    "material": ('fluid = {values = ["MRF-122EG", "MRF-140CG"]}', "fluid",
                 ["mrf_122eg", "mrf_140cg"]),
}  # fmt: skip
COLUMN = {"length": "gap_mm", "integer": "n_drums", "values": "drum_thickness_mm",
          "material": "fluid"}  # fmt: skip
RANDOM = {  # the same axes in a random sweep (a list of values and a material draw from it)
    "length": "gap_mm = {min = 0.3, max = 0.5}",
    "integer": KINDS["integer"][0],
    "values": KINDS["values"][0],
    "material": KINDS["material"][0],
}
BASE = design_preset("paper")


def spec_file(folder, params, sweep='mode = "grid"\nchunk_size = 1', extra=""):
    path = folder / "spec.toml"
    path.write_text(f'[sweep]\nbase = "paper"\n{sweep}\n\n[parameters]\n{params}\n{extra}')
    return path


def base_of(path):
    spec, rest = load_spec(path)
    return spec, design_from_mapping({"clutch": spec.base.to_mm(), **rest}, where=str(path))


def single(design):
    """The design's own evaluation (evaluate, fast): what a row must equal."""
    return evaluate(design).clutch


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_the_speed_estimate_of_a_large_sweep(tmp_path, kind):
    """Above 1000 designs the CLI times its first designs (a material axis was passed as raw
    category numbers: 'materials.fluid = 2: unknown fluid')."""
    from mrclutch.cli.commands.sweep import _say_estimate

    path = spec_file(tmp_path, RANDOM[kind], 'mode = "random"\nsamples = 1001\nchunk_size = 8')
    spec, base = base_of(path)
    seconds = _say_estimate(spec, BatchEvaluator(base), 1)
    assert seconds is not None and np.isfinite(seconds) and seconds > 0


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_rows_csv_parquet_with_and_pareto(tmp_path, kind):
    """A two-design grid over one axis of each kind, with a nominal --with column, in CSV and
    Parquet: read back, the axis' column holds its values (a material's names: text in the
    CSV, a dictionary column in Parquet), every row equals its design's single evaluation,
    the two files agree, and --pareto draws from both."""
    import pyarrow.parquet as pq

    from mrclutch.cli.plots.design import pareto_plot

    line, name, values = KINDS[kind]
    spec, base = base_of(spec_file(tmp_path, line))
    ev = BatchEvaluator(base, ("max_passive_K_N_per_m",))
    res = {}
    for out in ("r.csv", "r.parquet"):
        assert run_sweep(spec, tmp_path / out, ev, ev.columns, progress=False).complete
        res[out] = read_results(tmp_path / out)
    col = COLUMN[kind]
    for r in res.values():
        got = r[col].tolist()
        assert got == values if kind in ("material", "integer") else np.allclose(got, values)
        assert np.all(np.isfinite(r["max_passive_K_N_per_m"])) and np.all(r["valid"] == 1)
    assert np.allclose(res["r.csv"]["max_torque_N_m"], res["r.parquet"]["max_torque_N_m"],
                       rtol=1e-8)  # fmt: skip
    if kind == "material":
        assert (tmp_path / "r.csv").read_text().splitlines()[1].split(",")[1] == "mrf_122eg"
        field = pq.read_table(tmp_path / "r.parquet").schema.field("fluid")
        assert str(field.type) == "dictionary<values=string, indices=int32, ordered=0>"
    for i in range(2):
        d = design_of(spec, base, i)
        got = getattr(d.materials if kind == "material" else d.clutch, name)
        want = values[i] if kind in ("material", "integer") else values[i] * 1e-3
        assert got == pytest.approx(want, rel=1e-12) if kind != "material" else got == want
    one = single(d)  # the last row's design (its values differ from the base's)
    assert res["r.parquet"]["max_torque_N_m"][1] == pytest.approx(one.max_torque, rel=1e-6)
    assert res["r.parquet"]["clutch_mass_kg"][1] == pytest.approx(one.clutch_mass, rel=1e-6)
    for out in ("r.csv", "r.parquet"):
        png = tmp_path / f"{out}.png"
        pareto_plot(tmp_path / out, png)
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_worst_case_with_column(tmp_path, kind):
    """The worst case over the uncertainty ranges (--with max_stable_K_worst_N_per_m) on a
    chunk of each kind: finite, and no larger than the nominal largest stable K (the worst
    case over ranges that contain the nominal)."""
    spec, base = base_of(spec_file(tmp_path, KINDS[kind][0], 'mode = "grid"\nchunk_size = 2'))
    cols = ("max_stable_K_N_per_m", "max_stable_K_worst_N_per_m")
    rows = RobustBatchEvaluator(base, cols)(spec.design_fields(0)[1])
    worst, nominal = rows["max_stable_K_worst_N_per_m"], rows["max_stable_K_N_per_m"]
    assert worst.shape == (2,) and np.all(np.isfinite(worst)) and np.all(worst > 0)
    assert np.all(worst <= nominal * (1 + 1e-9))


# ---- paths run once, on a spec holding all four kinds -------------------------------------

FLUID = FLUID_TEMPLATE.replace("{viscosity}", "0.1")  # a user's fluid file

#: every kind at once; the material axis: the three LORD fluids
ALL = "\n".join([RANDOM["length"], RANDOM["integer"], RANDOM["values"],
                 'fluid = {values = ["MRF-122EG", "MRF-132DG", "MRF-140CG"]}'])  # fmt: skip
ALL_SWEEP = 'mode = "random"\nsamples = 30\nseed = 4\nchunk_size = 10'


def _cli(spec, out, *extra, timeout=240):
    return subprocess.run([sys.executable, "-m", "mrclutch", "sweep", str(spec), "--out",
                           str(out), "--no-progress", *extra], capture_output=True, text=True,
                          timeout=timeout)  # fmt: skip


def _dask_or_skip(r):
    if r.returncode != 0 and "LocalCluster" in r.stderr and "OSError" in r.stderr:
        pytest.skip(f"distributed cannot start a cluster here: {r.stderr[-300:]}")


@pytest.fixture(scope="module")
def three_fluids(tmp_path_factory):
    """The spec with every kind (a three-fluid axis) and its in-process CSV."""
    tmp = tmp_path_factory.mktemp("all")
    spec = spec_file(tmp, ALL, ALL_SWEEP)
    r = _cli(spec, tmp / "one.csv")
    assert r.returncode == 0, r.stderr
    return spec, tmp / "one.csv"


def test_three_fluid_rows_on_a_pool_and_dask_equal_single_evaluations(three_fluids, tmp_path):
    """The acceptance sweep in small (30 designs, every kind, three fluids): a process pool
    (--workers 2) and a Dask cluster (--dask-local 2) write the in-process file byte for
    byte, and a row of each fluid equals its design's single ``evaluate``."""
    spec, one = three_fluids
    r = _cli(spec, tmp_path / "pool.csv", "--workers", "2")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "pool.csv").read_bytes() == one.read_bytes()
    r = _cli(spec, tmp_path / "dask.csv", "--dask-local", "2")
    _dask_or_skip(r)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "dask.csv").read_bytes() == one.read_bytes()
    res = read_results(one)
    s, base = base_of(spec)
    for fluid in ("mrf_122eg", "mrf_132dg", "mrf_140cg"):
        i = int(np.flatnonzero(res["fluid"] == fluid)[0])
        d = design_of(s, base, int(res["design_id"][i]))
        assert d.materials.fluid == fluid
        assert d.clutch.gap * 1e3 == pytest.approx(res["gap_mm"][i], rel=1e-8)
        assert d.clutch.n_drums == res["n_drums"][i]
        one_ev = single(d)
        assert res["max_torque_N_m"][i] == pytest.approx(one_ev.max_torque, rel=1e-6)
        assert res["off_state_torque_N_m"][i] == pytest.approx(one_ev.drag.torque, rel=1e-6)


def test_a_process_pool_parquet_run_equals_the_in_process_one(tmp_path):
    """Parquet parts (the dictionary column) from a pool equal those written here."""
    path = spec_file(tmp_path, ALL, ALL_SWEEP.replace("samples = 30", "samples = 12"))
    spec, base = base_of(path)
    ev = BatchEvaluator(base)
    run_sweep(spec, tmp_path / "a.parquet", ev, ev.columns, progress=False)
    with ProcessPoolExecutor(2) as pool:
        run_sweep(spec, tmp_path / "b.parquet", ev, ev.columns, executor=pool, progress=False)
    parts = sorted(p.name for p in (tmp_path / "a.parquet").iterdir())
    assert len(parts) == 2
    for p in parts:
        assert (tmp_path / "a.parquet" / p).read_bytes() == (
            tmp_path / "b.parquet" / p
        ).read_bytes()


def test_a_users_fluid_files_reach_dask_workers(tmp_path):
    """A fluid file named by [materials] and one on the axis: Dask workers never read them
    (a KeyError in the workers before); the spec carries their bytes. Rows equal the
    in-process run's, and the user's fluid gives other rows than MRF-122EG."""
    (tmp_path / "base.toml").write_text(FLUID.format(name="cat_base_fluid"))
    (tmp_path / "axis.toml").write_text(FLUID.format(name="cat_axis_fluid").replace(
        "phi = 0.3", "phi = 0.25"))  # fmt: skip
    path = spec_file(tmp_path, 'fluid = {values = ["MRF-122EG", "axis.toml"]}\n'
                     "gap_mm = {values = [0.3, 0.4]}", 'mode = "grid"\nchunk_size = 2',
                     '\n[materials]\nfluid_file = "base.toml"\n')  # fmt: skip
    r = _cli(path, tmp_path / "one.csv")
    assert r.returncode == 0, r.stderr
    r = _cli(path, tmp_path / "dask.csv", "--dask-local", "2")
    _dask_or_skip(r)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "dask.csv").read_bytes() == (tmp_path / "one.csv").read_bytes()
    res = read_results(tmp_path / "one.csv")
    assert res["fluid"].tolist() == ["mrf_122eg"] * 2 + ["cat_axis_fluid"] * 2
    assert not np.allclose(res["max_torque_N_m"][:2], res["max_torque_N_m"][2:])


def test_verify_top_by_the_fem_with_every_kind(three_fluids, tmp_path, capsys):
    """issue 39 item 6: --verify-top on a spec with every axis kind (a TypeError traceback
    with a material axis before): the best row re-solved by the FEM (coarse, 1 mm), the
    design rebuilt with its fluid."""
    spec, one = three_fluids
    r = _cli(spec, tmp_path / "v.csv", "--verify-top", "1", "--verify-fem-size-mm", "1",
             timeout=400)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "FEM check of the 1 best rows by max_torque_N_m" in r.stdout
    rows = (tmp_path / "v.csv.verified.csv").read_text().splitlines()
    assert len(rows) == 2
    best = read_results(one)
    i = int(np.nanargmax(np.where(best["valid"] == 1, best["max_torque_N_m"], np.nan)))
    assert int(rows[1].split(",")[0]) == int(best["design_id"][i])
    fem = float(rows[1].split(",")[5])
    assert np.isfinite(fem) and fem > 0


def test_the_optimiser_with_a_material_axis_with_and_without_nominal():
    """``optimize --material fluid=…`` without --nominal failed ('core: unknown DrumClutch
    field': the worst case took no material column). Both verdicts now give members made
    of the offered fluids, each row its own design's evaluation."""
    from mrclutch.optimize import pareto, robust_verdict

    offered = ("mrf_122eg", "mrf_140cg")
    for robust in (None, robust_verdict(BASE)):
        ps = pareto(BASE, members=2, materials={"fluid": list(offered)}, robust=robust,
                    pop_size=16, generations=4, seed=1)  # fmt: skip
        assert ps.members, robust
        for m in ps.members:
            assert m.design.materials.fluid in offered
            one = single(m.design)
            assert m.row["max_torque_N_m"] == pytest.approx(one.max_torque, rel=1e-6)


def test_verify_rebuilds_a_design_of_every_kind_at_once(three_fluids):
    spec, one = three_fluids
    s, base = base_of(spec)
    res = read_results(one)
    for i in range(len(res["design_id"])):
        d = design_of(s, base, i)
        assert d.materials.fluid == res["fluid"][i]
        assert d.clutch.drum_thickness * 1e3 == pytest.approx(res["drum_thickness_mm"][i])
        assert replace(d, materials=BASE.materials).materials == BASE.materials
