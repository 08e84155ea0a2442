"""Scale-out (issue 16): chunks in flight follow the executor's size and still come out in
order; the CLI runs the same chunks on a Dask cluster (rows identical to the in-process run)
and refuses a bad or silent scheduler in one line; Parquet output survives a real SIGTERM."""

import gc
import signal
import subprocess
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pytest
from test_sweep_cli import SPEC, _sweep
from test_sweep_engine import OUTPUTS, geometric_outputs, grid_spec

from mrclutch.cli.main import main
from mrclutch.sweep import (
    MAX_ROWS_IN_FLIGHT,
    chunks_in_flight,
    executor_workers,
    run_sweep,
)

#: Seconds before a child sweep counts as hung: a guard, not a timing (a 20 000-row sweep on
#: a dask cluster took 81 s on a loaded 2-core machine, past the 60 s this once was).
HANG = 600


class CountingPool(ThreadPoolExecutor):
    """A thread pool that records the most chunks submitted and not yet taken back."""

    def __init__(self, n):
        super().__init__(n)
        self.out = self.most = 0
        self.lock = threading.Lock()

    def submit(self, fn, *args, **kwargs):
        with self.lock:
            self.out += 1
            self.most = max(self.most, self.out)
        inner = super().submit(fn, *args, **kwargs)
        outer = Future()
        inner.add_done_callback(lambda f: outer.set_result(f.result()))
        pool = self

        class Taken(Future):
            def result(self, timeout=None):
                with pool.lock:
                    pool.out -= 1
                return outer.result(timeout)

            def cancel(self):
                return inner.cancel()

        return Taken()


def slow_early_chunks(fields):
    """The first designs (gap 0.2 mm) take longest, so chunks finish out of order."""
    time.sleep(0.02 if fields["gap"][0] < 0.25e-3 else 0.0)
    return geometric_outputs(fields)


def test_chunks_in_flight_follow_the_workers_within_a_memory_bound():
    assert chunks_in_flight(1, 20_000) == 4
    assert chunks_in_flight(16, 20_000) == 64  # the measured 405 k/s setting
    assert chunks_in_flight(64, 20_000) == MAX_ROWS_IN_FLIGHT // 20_000  # memory bound
    assert chunks_in_flight(16, 10**7) == 2  # never fewer than 2
    with ThreadPoolExecutor(3) as ex:
        assert executor_workers(ex) == 3
    assert executor_workers(None) == 1


def test_a_pool_keeps_four_chunks_per_worker_in_flight_and_writes_in_order(tmp_path):
    spec = grid_spec(chunk=2)  # 18 chunks
    run_sweep(spec, tmp_path / "a.csv", geometric_outputs, OUTPUTS, progress=False)
    with CountingPool(2) as ex:
        run_sweep(spec, tmp_path / "b.csv", slow_early_chunks, OUTPUTS, executor=ex,
                  progress=False)  # fmt: skip
    assert ex.most == 8  # 4 × 2 workers (was a fixed 4)
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()
    with CountingPool(2) as ex:
        run_sweep(spec, tmp_path / "c.csv", geometric_outputs, OUTPUTS, executor=ex,
                  progress=False, workers=3)  # fmt: skip
    assert ex.most == 12  # an explicit worker count wins


def _fails(capsys, argv, fragment):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert fragment in err, err
    assert "Traceback" not in err and err.count("\n") == 1, err


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--scheduler", "nonsense"], "--scheduler nonsense: missing port number"),
        (["--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "0.5"],
         "--scheduler tcp://127.0.0.1:1: Timed out trying to connect"),
        (["--workers", "2", "--dask-local", "2"], "--workers and --dask-local: give one way"),
        (["--dask-local", "0"], "--dask-local = 0: must be >= 1"),
        (["--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "0"],
         "--connect-timeout = 0.0: must be in (0, 86400] s"),
    ],
)  # fmt: skip
def test_bad_or_unreachable_schedulers_are_one_line_errors(tmp_path, capsys, extra, fragment):
    (tmp_path / "s.toml").write_text(SPEC)
    out = tmp_path / "r.csv"
    _fails(capsys, ["sweep", str(tmp_path / "s.toml"), "--out", str(out), *extra], fragment)


def test_a_scheduler_without_workers_is_refused_within_the_timeout(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    (tmp_path / "s.toml").write_text(SPEC)
    try:
        # ":0": any free port for the scheduler's HTTP server (None still binds 8787, and a
        # cluster elsewhere on the machine holding it failed this test with a UserWarning)
        cluster = distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0")
    except OSError as exc:  # pragma: no cover - a sandbox without local sockets
        pytest.skip(f"distributed cannot start a cluster here: {exc}")
    with cluster:
        argv = ["sweep", str(tmp_path / "s.toml"), "--out", str(tmp_path / "r.csv"),
                "--scheduler", cluster.scheduler_address, "--connect-timeout", "0.5"]  # fmt: skip
        _fails(capsys, argv, "no worker joined within 0.5 s")


@pytest.fixture(scope="module")
def whole_parquet(tmp_path_factory):
    """(the spec, the parts of its sweep run in one process without interruption): one
    20 000-row run the Dask and the killed sweeps are both compared with (each ran its own,
    ~8 s of CPU)."""
    pytest.importorskip("pyarrow.parquet")
    tmp = tmp_path_factory.mktemp("whole")
    spec, whole = tmp / "spec.toml", tmp / "whole.parquet"
    spec.write_text(SPEC)  # 20 000 designs in 20 chunks
    subprocess.run(_sweep(spec, whole), check=True, capture_output=True, timeout=HANG)
    return spec, whole


def _same_parts(whole, other):
    names = sorted(p.name for p in whole.iterdir())
    assert names == sorted(p.name for p in other.iterdir()) and len(names) == 20
    assert all((other / n).read_bytes() == (whole / n).read_bytes() for n in names)


def test_dask_local_cluster_gives_the_rows_of_the_in_process_run(tmp_path, whole_parquet):
    """``--dask-local 2``: two worker processes (one thread each) started by the CLI write
    the in-process run's Parquet parts byte for byte (its rows, in its order)."""
    pytest.importorskip("distributed")
    spec, whole = whole_parquet
    dask = tmp_path / "dask.parquet"
    r = subprocess.run(_sweep(spec, dask, "--dask-local", "2"), capture_output=True, text=True,
                       timeout=HANG)  # fmt: skip
    if r.returncode != 0 and "LocalCluster" in r.stderr and "OSError" in r.stderr:
        pytest.skip(f"distributed cannot start a cluster here: {r.stderr[-300:]}")
    assert r.returncode == 0, r.stderr
    assert "20000 designs" in r.stdout
    _same_parts(whole, dask)


def test_killed_parquet_sweep_keeps_readable_parts_and_resumes_to_the_same_rows(
    tmp_path, whole_parquet
):
    """A real SIGTERM: every part on disk is readable at once (no footer left unwritten),
    and --resume ends with byte-identical parts. test_sweep_cli's SPEC: 20 000 rows in 20
    parts (60 000 in 30 cost three times the time for the same claim); killed once three
    are on disk, the 17 left take far longer than the 20 ms poll."""
    pq = pytest.importorskip("pyarrow.parquet")
    spec, whole = whole_parquet
    part = tmp_path / "part.parquet"
    proc = subprocess.Popen(_sweep(spec, part), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # wait until a few parts are on disk
        if part.is_dir() and len(list(part.glob("part-*.parquet"))) >= 3:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=HANG)
    if proc.returncode == 0:
        pytest.skip("the sweep finished before it could be interrupted")
    assert proc.returncode == 130, err
    assert b"--resume" in err and b"Traceback" not in err
    table = pq.read_table(part)  # readable as it was left
    assert 0 < table.num_rows < 20000 and table.num_rows % 1000 == 0
    assert np.array_equal(table["design_id"].to_numpy(), np.arange(table.num_rows))
    subprocess.run(_sweep(spec, part, "--resume"), check=True, capture_output=True, timeout=HANG)
    _same_parts(whole, part)


def test_pareto_plot_reads_a_parquet_sweep(tmp_path):
    pytest.importorskip("pyarrow")
    spec = tmp_path / "spec.toml"
    small = SPEC.replace("samples = 20000", "samples = 300").replace("size = 1000", "size = 100")
    assert "samples = 300" in small and "chunk_size = 100\n" in small
    spec.write_text(small)
    r = subprocess.run(_sweep(spec, tmp_path / "r.parquet", "--pareto", str(tmp_path / "p.png")),
                       capture_output=True, text=True, timeout=HANG)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "p.png").stat().st_size > 1000


def test_an_unreachable_scheduler_leaves_no_half_started_client(tmp_path, capsys):
    """The Client that failed to connect is collected before the refusal, not left in a
    reference cycle: its __del__, run by a later collection inside the next Client's loop
    start, waited for the lock that start held and hung a full suite run (distributed's
    LoopRunner). Checked without collecting here: no Client object is left alive."""
    distributed = pytest.importorskip("distributed")
    (tmp_path / "s.toml").write_text(SPEC)
    argv = ["sweep", str(tmp_path / "s.toml"), "--out", str(tmp_path / "r.csv"),
            "--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "0.5"]  # fmt: skip
    gc.disable()  # no automatic collection may hide a cycle the code left behind
    try:
        _fails(capsys, argv, "Timed out trying to connect")
        left = [o for o in gc.get_objects() if isinstance(o, distributed.Client)]
    finally:
        gc.enable()
    assert not left, left
