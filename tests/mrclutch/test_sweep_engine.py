"""The sweep engine: enumeration, streaming, interruption and resume, executors, Pareto."""

import itertools
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry import ParameterError
from geometry.params import broadcast_fields, valid
from geometry.regions import per_topology
from mrclutch.sweep import (
    ParamRange,
    SweepSpec,
    executor_workers,
    load_spec,
    pareto_front,
    run_sweep,
)

OUTPUTS = ("outer_radius", "pole_radius")


def geometric_outputs(fields):
    """A cheap, deterministic evaluator (the product's evaluator is tested elsewhere)."""
    p = broadcast_fields(fields)
    return per_topology(
        p, valid(p), lambda rg, _: {"outer_radius": rg.outer_radius, "pole_radius": rg.pole_radius}
    )


class InterruptAfter:
    """Evaluator that raises KeyboardInterrupt (as Ctrl-C would) at its n-th call."""

    def __init__(self, n):
        self.n, self.calls = n, 0

    def __call__(self, fields):
        self.calls += 1
        if self.calls > self.n:
            raise KeyboardInterrupt
        return geometric_outputs(fields)


def grid_spec(chunk=7):
    return SweepSpec(
        (
            ParamRange("gap", 0.2e-3, 0.5e-3, 4),
            ParamRange("n_drums", 1, 3, 0),
            ParamRange("drum_thickness", 0.1e-3, 0.4e-3, 3),
        ),
        chunk_size=chunk,
    )


def test_grid_enumerates_the_full_product_once():
    spec = grid_spec()
    assert spec.n_designs == 4 * 3 * 3
    seen = []
    for k in range(spec.n_chunks):
        _, f = spec.chunk(k)
        seen += list(zip(f["gap"], f["n_drums"], f["drum_thickness"], strict=True))
    expected = itertools.product(
        np.linspace(0.2e-3, 0.5e-3, 4), [1, 2, 3], np.linspace(0.1e-3, 0.4e-3, 3)
    )
    assert seen == list(expected)


def test_random_chunks_are_reproducible_and_in_range():
    spec = SweepSpec(
        (ParamRange("gap", 0.2e-3, 0.5e-3, 0),), mode="random", samples=50, seed=3, chunk_size=16
    )
    a = spec.chunk(2)[1]["gap"]
    b = spec.chunk(2)[1]["gap"]
    assert np.array_equal(a, b)
    assert np.all((a >= 0.2e-3) & (a <= 0.5e-3))
    assert not np.array_equal(a, spec.chunk(1)[1]["gap"])
    assert spec.chunk(3)[0].size == 50 - 3 * 16


def test_interrupted_then_resumed_equals_uninterrupted(tmp_path):
    spec = grid_spec(chunk=5)
    whole = run_sweep(spec, tmp_path / "a.csv", geometric_outputs, OUTPUTS, progress=False)
    assert whole.complete and whole.rows == spec.n_designs
    part = run_sweep(spec, tmp_path / "b.csv", InterruptAfter(3), OUTPUTS, progress=False)
    assert not part.complete and part.rows == 15
    # a kill mid-write leaves a partial line: resume must trim it
    with (tmp_path / "b.csv").open("a") as f:
        f.write("15,0.2,1,0.1,0.01")
    again = run_sweep(
        spec, tmp_path / "b.csv", geometric_outputs, OUTPUTS, resume=True, progress=False
    )
    assert again.complete and again.resumed_from == 15
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


def test_resume_refuses_a_different_spec_and_overwrite_is_explicit(tmp_path):
    out = tmp_path / "s.csv"
    run_sweep(grid_spec(), out, geometric_outputs, OUTPUTS, progress=False)
    with pytest.raises(ParameterError, match="exists; pass --resume"):
        run_sweep(grid_spec(), out, geometric_outputs, OUTPUTS, progress=False)
    with pytest.raises(ParameterError, match="different sweep spec"):
        run_sweep(grid_spec(chunk=6), out, geometric_outputs, OUTPUTS, resume=True, progress=False)


def test_thread_pool_executor_gives_the_same_rows(tmp_path):
    spec = grid_spec(chunk=4)
    run_sweep(spec, tmp_path / "a.csv", geometric_outputs, OUTPUTS, progress=False)
    with ThreadPoolExecutor(2) as ex:
        run_sweep(
            spec,
            tmp_path / "b.csv",
            geometric_outputs,
            OUTPUTS,
            executor=ex,
            progress=False,
            max_pending=3,
        )
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


def test_spec_file_errors_name_the_key(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[sweep]\nmode = "grid"\n[parameters]\ngap = {min = 0.2, max = 0.5, count = 3}\n')
    with pytest.raises(ParameterError, match=r"gap: lengths need their unit in the key \(gap_mm\)"):
        load_spec(f)
    f.write_text('[sweep]\nmode = "grid"\n[parameters]\ngap_mm = {min = 0.2, max = 0.5}\n')
    with pytest.raises(ParameterError, match=r"gap_mm\.count: missing"):
        load_spec(f)
    f.write_text('[sweep]\nmodes = "grid"\n[parameters]\ngap_mm = {values = [0.3]}\n')
    with pytest.raises(ParameterError, match=r"sweep\.modes: unknown key"):
        load_spec(f)
    f.write_text(
        '[sweep]\nmode = "grid"\n[parameters]\ngap_mm = {values = [0.2, 0.3]}\n'
        "n_drums = {min = 1, max = 2}\n"
    )
    spec, rest = load_spec(f)
    assert spec.n_designs == 4 and rest == {}


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 6), st.integers(0, 6), st.integers(0, 6)), min_size=1, max_size=40
    )
)
def test_pareto_front_matches_brute_force(points):
    obj = np.array(points, dtype=float)
    maximize = [True, False, True]
    mask = pareto_front(obj, maximize)
    x = obj * np.where(maximize, 1, -1)
    for i in range(len(x)):
        dominated = any(
            np.all(x[j] >= x[i]) and np.any(x[j] > x[i]) for j in range(len(x)) if j != i
        )
        if dominated:
            assert not mask[i]
        elif not any(np.array_equal(x[j], x[i]) and mask[j] for j in range(len(x)) if j != i):
            assert mask[i]  # non-dominated (duplicates keep one representative)


def test_dask_local_cluster_executor_gives_the_same_rows(tmp_path):
    """The path that scales sweeps out: a Dask distributed executor (Client.get_executor)."""
    distributed = pytest.importorskip("distributed")
    spec = grid_spec(chunk=6)
    run_sweep(spec, tmp_path / "a.csv", geometric_outputs, OUTPUTS, progress=False)
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        executor = client.get_executor()
        assert executor_workers(executor) == 2  # the cluster's threads: 8 chunks in flight
        run_sweep(spec, tmp_path / "b.csv", geometric_outputs, OUTPUTS, executor=executor,
                  progress=False)  # fmt: skip
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


def test_the_local_clusters_workers_print_no_error_log(capfd):
    """--dask-local's workers print no log of their own, ERROR included: after a Ctrl-C a
    worker's heartbeat can meet the scheduler closing and log an ERROR with a traceback
    under the sweep's one line (seen once in a full suite run). The workers write to this
    process's stderr (fd 2), which capfd reads."""
    distributed = pytest.importorskip("distributed")
    from mrclutch.cli.executors import local_cluster

    def heartbeat_error():  # nested: pickled by value, run on the worker
        import logging

        text = "Failed to communicate with scheduler during heartbeat."
        logging.getLogger("distributed.worker").error(text)
        return "logged"

    try:
        cluster = local_cluster(1)
    except OSError as exc:  # pragma: no cover - a sandbox without local sockets
        pytest.skip(f"distributed cannot start a cluster here: {exc}")
    try:
        with distributed.Client(cluster) as client:
            assert list(client.run(heartbeat_error).values()) == ["logged"]
    finally:
        cluster.close()
    assert "Failed to communicate" not in capfd.readouterr().err
