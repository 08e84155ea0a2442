"""Issue 45 (and issue 39 item 6): a categorical axis (a part's material) goes through every
path a numeric axis takes. The matrix ``test_an_axis_kind_on_a_path``: 5 axis kinds (a
length range, an integer range, a list of values, a material from the library, a fluid
file of the user's; the base design's fluid a user's file too, ``[materials] fluid_file``)
× 9 paths (a sweep above 1000 designs through the CLI, its speed
estimate first; the rows in CSV; in Parquet; a nominal ``--with`` column; a worst-case
``--with`` column; ``--verify-top`` by the FEM; ``--pareto``; a process pool; Dask workers)
= 45 cases, each row checked against its design's single ``evaluate``. Then, once: the
optimiser with and without ``--nominal`` (2 cases), and the acceptance sweep in small on a
spec holding four kinds, through the CLI (a three-fluid axis; its file written again by
the module's process pool and Dask workers; ``--verify-top``)."""

import multiprocessing
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np
import pytest
from test_sweep_inputs import FLUID as FLUID_TEMPLATE
from test_sweep_inputs import _registry  # noqa: F401 (autouse: the fluids loaded here undone)

from mrclutch.cli.main import main
from mrclutch.design import design_from_mapping, design_preset
from mrclutch.pipeline import BatchEvaluator, evaluate
from mrclutch.robust import RobustBatchEvaluator
from mrclutch.sweep import load_spec, read_results, run_sweep
from mrclutch.verify import TORQUE, design_of, verify_top

#: axis kind → (its `[parameters]` line, the DrumClutch field or part it sets, the values a
#: two-design grid takes, in the file's unit: mm, count, or registry name)
KINDS = {
    "length": ("gap_mm = {min = 0.3, max = 0.5, count = 2}", "gap", [0.3, 0.5]),
    "integer": ("n_drums = {min = 2, max = 3}", "n_drums", [2, 3]),
    "values": ("drum_thickness_mm = {values = [0.25, 0.3]}", "drum_thickness", [0.25, 0.3]),
    "material": ('fluid = {values = ["MRF-122EG", "MRF-140CG"]}', "fluid",
                 ["mrf_122eg", "mrf_140cg"]),
    "fluid file": ('fluid = {values = ["MRF-122EG", "axis.toml"]}', "fluid",
                   ["mrf_122eg", "cat_axis_fluid"]),
}  # fmt: skip
COLUMN = {"length": "gap_mm", "integer": "n_drums", "values": "drum_thickness_mm",
          "material": "fluid", "fluid file": "fluid"}  # fmt: skip
CATEGORICAL = ("material", "fluid file")
RANDOM = {  # the same axes in a random sweep (a list of values and a material draw from it)
    "length": "gap_mm = {min = 0.3, max = 0.5}",
    **{k: KINDS[k][0] for k in ("integer", "values", "material", "fluid file")},
}
BASE = design_preset("paper")
FLUID = FLUID_TEMPLATE.replace("{viscosity}", "0.1")  # a user's fluid file
AXIS_FLUID = FLUID.format(name="cat_axis_fluid").replace("phi = 0.3", "phi = 0.25")
#: the matrix's base design is of a user's fluid too: a worker must register it from the
#: bytes the spec carries to evaluate the rows of a numeric axis
BASE_FLUID = '\n[materials]\nfluid_file = "base.toml"\n'


def spec_file(folder, params, sweep='mode = "grid"\nchunk_size = 1', extra=BASE_FLUID):
    """The spec, with the user's fluid files beside it: the one a "fluid file" axis names,
    and the base design's (``BASE_FLUID``: the fluid of every row without a fluid axis)."""
    (folder / "axis.toml").write_text(AXIS_FLUID)
    (folder / "base.toml").write_text(FLUID.format(name="cat_base_fluid"))
    path = folder / "spec.toml"
    path.write_text(f'[sweep]\nbase = "paper"\n{sweep}\n\n[parameters]\n{params}\n{extra}')
    return path


def base_of(path):
    spec, rest = load_spec(path)
    return spec, design_from_mapping({"clutch": spec.base.to_mm(), **rest}, where=str(path))


#: design -> its evaluation, once a session: the matrix checks ~12 designs ~100 times (each
#: kind's two designs on every path), at ~0.3 s an evaluate
_SINGLE: dict = {}


def single(design):
    """The design's own evaluation (evaluate, fast): what a row must equal. Computed once
    per design (a frozen design, hashed by value; a user's fluid by its name, whose file
    holds the same text in every test here)."""
    if design not in _SINGLE:
        _SINGLE[design] = evaluate(design)
    return _SINGLE[design]


def _value(design, kind):
    name = KINDS[kind][1]
    return getattr(design.materials if kind in CATEGORICAL else design.clutch, name)


def check_rows(spec, base, res, kind, ids=None):
    """The rows ``ids`` of ``res``: the axis' column holds the value each design was given
    (its SI field ×1e3 for lengths, the registry name for a material), and the figures
    equal the design's single evaluation."""
    ids = range(len(res["design_id"])) if ids is None else ids
    for i in ids:
        assert res["design_id"][i] == i
        d = design_of(spec, base, i)
        got, want = res[COLUMN[kind]][i], _value(d, kind)
        if kind in CATEGORICAL or kind == "integer":
            assert got == want
        else:
            assert got == pytest.approx(want * 1e3, rel=1e-8)
        one = single(d)
        assert res["valid"][i] == 1
        assert res["max_torque_N_m"][i] == pytest.approx(one.clutch.max_torque, rel=1e-6)
        assert res["clutch_mass_kg"][i] == pytest.approx(one.clutch.clutch_mass, rel=1e-6)
        if "max_passive_K_N_per_m" in res:
            assert res["max_passive_K_N_per_m"][i] == pytest.approx(
                one.haptic["max_passive_K_N_per_m"], rel=1e-6)  # fmt: skip


def two_designs(tmp_path, kind, out, evaluator=BatchEvaluator, columns=(), executor=None):
    """The two-design grid over the axis of ``kind`` (a chunk a design) written to
    ``out``: (spec, base, its rows read back)."""
    spec, base = base_of(spec_file(tmp_path, KINDS[kind][0]))
    ev = evaluator(base, columns)
    res = run_sweep(spec, tmp_path / out, ev, ev.columns, executor=executor, progress=False)
    assert res.complete and res.rows == 2
    rows = read_results(tmp_path / out)
    got = rows[COLUMN[kind]].tolist()
    values = KINDS[kind][2]
    assert got == values if kind in CATEGORICAL or kind == "integer" else np.allclose(got, values)
    return spec, base, rows


def path_above_1000_designs(tmp_path, kind, executors):
    """``mrclutch sweep`` of 1001 random designs: the speed estimate times the first designs
    (a material axis was passed as raw category numbers: 'materials.fluid = 2: unknown
    fluid'), the rows written, every value of the axis drawn, a sample of rows equal to
    single evaluations."""
    from mrclutch.cli.commands.sweep import _say_estimate

    path = spec_file(tmp_path, RANDOM[kind], 'mode = "random"\nsamples = 1001\nchunk_size = 400')
    spec, base = base_of(path)
    seconds = _say_estimate(spec, BatchEvaluator(base), 1)
    assert seconds is not None and np.isfinite(seconds) and seconds > 0
    out = tmp_path / "r.csv"
    assert main(["sweep", str(path), "--out", str(out), "--no-progress"]) == 0
    res = read_results(out)
    assert res["design_id"].tolist() == list(range(1001))
    col = res[COLUMN[kind]]
    if kind == "length":
        assert np.all((col >= 0.3) & (col <= 0.5)) and np.unique(col).size > 900
    else:
        assert sorted(set(col.tolist())) == sorted(KINDS[kind][2])
    check_rows(spec, base, res, kind, (0, 399, 400, 1000))


def path_csv(tmp_path, kind, executors):
    spec, base, res = two_designs(tmp_path, kind, "r.csv")
    check_rows(spec, base, res, kind)
    second = (tmp_path / "r.csv").read_text().splitlines()[2].split(",")[1]
    if kind in CATEGORICAL:  # the name itself in the file, not an index
        assert second == KINDS[kind][2][1]
    else:
        assert float(second) == pytest.approx(KINDS[kind][2][1])


def path_parquet(tmp_path, kind, executors):
    import pyarrow.parquet as pq

    spec, base, res = two_designs(tmp_path, kind, "r.parquet")
    check_rows(spec, base, res, kind)
    kinds = {"integer": "int64", "length": "double", "values": "double"}
    field = pq.read_table(tmp_path / "r.parquet").schema.field(COLUMN[kind])
    want = kinds.get(kind, "dictionary<values=string, indices=int32, ordered=0>")
    assert str(field.type) == want


def path_nominal_with(tmp_path, kind, executors):
    """A nominal --with column: equal to evaluate's largest passive K of the design."""
    spec, base, res = two_designs(tmp_path, kind, "r.csv", columns=("max_passive_K_N_per_m",))
    assert np.all(res["max_passive_K_N_per_m"] > 0)
    check_rows(spec, base, res, kind)


def path_worst_with(tmp_path, kind, executors):
    """The worst case over the uncertainty ranges (--with max_stable_K_worst_N_per_m, the
    evaluator the CLI picks for it) written by a sweep (it failed with a material axis and
    left a header-only file): finite, and no larger than the nominal largest stable K (the
    ranges contain the nominal)."""
    cols = ("max_stable_K_N_per_m", "max_stable_K_worst_N_per_m")
    spec, base, res = two_designs(tmp_path, kind, "r.csv", RobustBatchEvaluator, cols)
    worst, nominal = res["max_stable_K_worst_N_per_m"], res["max_stable_K_N_per_m"]
    assert np.all(np.isfinite(worst)) and np.all(worst > 0)
    assert np.all(worst <= nominal * (1 + 1e-9))
    check_rows(spec, base, res, kind)


def path_verify_top(tmp_path, kind, executors):
    """--verify-top 1 (the FEM, coarse: 1 mm): the best row's design rebuilt from its id,
    with its material (a TypeError traceback with a material axis before), re-solved."""
    spec, base, res = two_designs(tmp_path, kind, "r.csv")
    rows = verify_top(spec, base, tmp_path / "r.csv", 1, TORQUE, True, 1e-3)
    best = int(res["design_id"][np.argmax(res[TORQUE])])
    assert [r.design_id for r in rows] == [best]
    assert rows[0].fast_torque == pytest.approx(res[TORQUE][best], rel=1e-8)
    assert np.isfinite(rows[0].fem_torque) and abs(rows[0].error) < 0.2


def path_pareto(tmp_path, kind, executors):
    from mrclutch.cli.plots.design import pareto_plot

    for out in ("r.csv", "r.parquet"):
        two_designs(tmp_path, kind, out)
        png = pareto_plot(tmp_path / out, tmp_path / f"{out}.png")
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def path_process_pool(tmp_path, kind, executors):
    """Spawned processes (they never read the user's fluid files): the pool writes the
    in-process bytes (its chunks first: each registers the spec's files itself), and
    --verify-top's FEM solves there equal those in this process. The Dask path takes the
    other order, so that each of the two registrations is the first one somewhere."""
    for out in ("r.csv", "r.parquet"):
        two_designs(tmp_path, kind, out)
        spec, base, res = two_designs(tmp_path, kind, f"pool-{out}", executor=executors("pool"))
        assert _files(tmp_path / f"pool-{out}") == _files(tmp_path / out)
    check_rows(spec, base, res, kind)
    _same_fem(spec, base, tmp_path / "r.csv", executors("pool"))


def path_dask_workers(tmp_path, kind, executors):
    """A Dask cluster's workers (the user's fluid file registered only from the bytes the
    spec carries: a KeyError in the workers before): --verify-top's FEM solves there
    (before any chunk) equal those in this process, and the workers write the in-process
    bytes."""
    spec, base, _ = two_designs(tmp_path, kind, "r.csv")
    _same_fem(spec, base, tmp_path / "r.csv", executors("dask"))
    spec, base, res = two_designs(tmp_path, kind, "dask.csv", executor=executors("dask"))
    assert (tmp_path / "dask.csv").read_bytes() == (tmp_path / "r.csv").read_bytes()
    check_rows(spec, base, res, kind)


def _same_fem(spec, base, results, executor):
    """--verify-top 2 (FEM at 1 mm) on ``executor``: the rows this process solves."""
    there = verify_top(spec, base, results, 2, TORQUE, True, 1e-3, executor)
    here = verify_top(spec, base, results, 2, TORQUE, True, 1e-3)
    assert [r.design_id for r in there] == [r.design_id for r in here] and len(here) == 2
    for a, b in zip(there, here, strict=True):
        assert a.fem_torque == pytest.approx(b.fem_torque, rel=1e-9) and a.fem_torque > 0


def _files(p):
    return {f.name: f.read_bytes() for f in p.iterdir()} if p.is_dir() else p.read_bytes()


PATHS = {
    "above 1000 designs": path_above_1000_designs,
    "csv": path_csv,
    "parquet": path_parquet,
    "nominal --with": path_nominal_with,
    "worst-case --with": path_worst_with,
    "--verify-top": path_verify_top,
    "--pareto": path_pareto,
    "process pool": path_process_pool,
    "dask workers": path_dask_workers,
}


@pytest.fixture(scope="module")
def executors():
    """A process pool of 2 spawned processes and a Dask LocalCluster of 2 worker processes
    (what --dask-local 2 starts), each started once for the module, on first use."""
    from mrclutch.cli.executors import local_cluster

    made = {}
    closers = []

    def get(which):
        if which not in made:
            if which == "pool":
                pool = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"))
                made[which] = pool
                closers.append(pool.shutdown)
            else:
                distributed = pytest.importorskip("distributed")
                try:
                    cluster = local_cluster(2)
                except OSError as exc:  # pragma: no cover - a sandbox without local sockets
                    pytest.skip(f"distributed cannot start a cluster here: {exc}")
                client = distributed.Client(cluster)
                made[which] = client.get_executor()
                closers.extend([cluster.close, client.close,
                                lambda: made[which].shutdown(wait=False)])  # fmt: skip
        return made[which]

    yield get
    for close in reversed(closers):
        close()


@pytest.mark.parametrize("path", list(PATHS))
@pytest.mark.parametrize("kind", list(KINDS))
def test_an_axis_kind_on_a_path(tmp_path, kind, path, executors):
    """One case of the matrix: the axis of ``kind`` through ``path`` (``PATHS``)."""
    PATHS[path](tmp_path, kind, executors)


# ---- paths run once, on a spec holding four kinds at once ---------------------------------

#: every kind at once; the material axis: the three LORD fluids
ALL = "\n".join([RANDOM["length"], RANDOM["integer"], RANDOM["values"],
                 'fluid = {values = ["MRF-122EG", "MRF-132DG", "MRF-140CG"]}'])  # fmt: skip
ALL_SWEEP = 'mode = "random"\nsamples = 30\nseed = 4\nchunk_size = 10'


def _cli(spec, out, *extra, timeout=240):
    return subprocess.run([sys.executable, "-m", "mrclutch", "sweep", str(spec), "--out",
                           str(out), "--no-progress", *extra], capture_output=True, text=True,
                          timeout=timeout)  # fmt: skip


@pytest.fixture(scope="module")
def three_fluids(tmp_path_factory):
    """The spec with four kinds (a three-fluid axis) and its in-process CSV."""
    tmp = tmp_path_factory.mktemp("all")
    spec = spec_file(tmp, ALL, ALL_SWEEP, extra="")
    r = _cli(spec, tmp / "one.csv")
    assert r.returncode == 0, r.stderr
    return spec, tmp / "one.csv"


def test_three_fluid_rows_on_a_pool_and_dask_equal_single_evaluations(three_fluids, tmp_path,
                                                                      executors):  # fmt: skip
    """The acceptance sweep in small (30 designs, four kinds, three fluids): the CLI's file
    (``three_fluids``), written byte for byte by a process pool of 2 and a Dask cluster of 2
    workers (the module's ``executors``, what --workers 2 and --dask-local 2 start: the
    options' wiring is test_verify's and test_sweep_scaleout's, run through the CLI there;
    a CLI process here started a second pool and cluster), and a row of each fluid equals
    its design's single ``evaluate``."""
    spec, one = three_fluids
    s, base = base_of(spec)
    ev = BatchEvaluator(base)  # the CLI's, without --with
    for name in ("pool", "dask"):
        out = tmp_path / f"{name}.csv"
        res = run_sweep(s, out, ev, ev.columns, executor=executors(name), workers=2,
                        progress=False)  # fmt: skip
        assert res.complete and res.rows == 30
        assert out.read_bytes() == one.read_bytes(), name
    res = read_results(one)
    for fluid in ("mrf_122eg", "mrf_132dg", "mrf_140cg"):
        i = int(np.flatnonzero(res["fluid"] == fluid)[0])
        d = design_of(s, base, int(res["design_id"][i]))
        assert d.materials.fluid == fluid
        assert d.clutch.gap * 1e3 == pytest.approx(res["gap_mm"][i], rel=1e-8)
        assert d.clutch.n_drums == res["n_drums"][i]
        one_ev = single(d).clutch
        assert res["max_torque_N_m"][i] == pytest.approx(one_ev.max_torque, rel=1e-6)
        assert res["off_state_torque_N_m"][i] == pytest.approx(one_ev.drag.torque, rel=1e-6)


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


@pytest.mark.parametrize("verdict", ["--nominal", "worst case"])
def test_the_optimiser_with_a_material_axis(verdict):
    """``optimize --material fluid=…`` without --nominal failed ('core: unknown DrumClutch
    field': the worst case took no material column). Both verdicts (``--nominal``: no
    ``robust``, as the CLI passes it) give members made of the offered fluids, each row its
    own design's evaluation."""
    from mrclutch.optimize import pareto, robust_verdict

    offered = ("mrf_122eg", "mrf_140cg")
    robust = None if verdict == "--nominal" else robust_verdict(BASE)
    ps = pareto(BASE, members=2, materials={"fluid": list(offered)}, robust=robust,
                pop_size=16, generations=4, seed=1)  # fmt: skip
    assert ps.members
    for m in ps.members:
        assert m.design.materials.fluid in offered
        one = single(m.design).clutch
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
