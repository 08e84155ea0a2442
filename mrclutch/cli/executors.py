"""Where ``mrclutch sweep`` runs its chunks: this process, a process pool, or a Dask cluster.

``distributed`` is imported only when a Dask option is given (it takes ≈ 1 s), so
``mrclutch --help`` and in-process sweeps never load it.
"""

from __future__ import annotations

import gc
import logging
import math
import os
import signal
import sys
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Any

from mrclutch.cli.errors import CLIError

#: s: the longest wait for a scheduler (a day); inf would hang a mistyped address forever.
MAX_CONNECT_TIMEOUT = 86400.0


def usable_cpus() -> int:
    """CPUs this process may run on (its affinity mask; the machine's count elsewhere)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def capped(option: str, n: int, say: Callable[[str], None] | None = None) -> int:
    """``n`` worker processes, at most ``usable_cpus()``: more only queue for the same
    CPUs and can exhaust the process limit (``--workers 10000`` forked them all). Says so
    on stderr when it caps."""
    most = usable_cpus()
    if n <= most:
        return n
    msg = f"{option} {n}: capped at {most}, the CPUs this process may use"
    (say or (lambda m: print(f"mrclutch: {m}", file=sys.stderr)))(msg)
    return most


@contextmanager
def sweep_executor(
    workers: int = 0,
    scheduler: str | None = None,
    dask_local: int | None = None,
    connect_timeout: float = 10.0,
) -> Iterator[tuple[Executor | None, int]]:
    """(executor, how many chunks it evaluates at once); ``(None, 1)`` runs in-process.

    ``workers``: a process pool of that size; ``scheduler``: the address of a running
    dask.distributed scheduler (its workers must have mrclutch installed); ``dask_local``: a
    LocalCluster of that many worker processes, one thread each.
    """
    given = [opt for opt, v in (("--workers", workers), ("--scheduler", scheduler),
                                ("--dask-local", dask_local)) if v]  # fmt: skip
    if len(given) > 1:
        raise CLIError(f"{' and '.join(given)}: give one way to run the chunks")
    if workers < 0:
        raise CLIError(f"--workers = {workers}: must be >= 0")
    if dask_local is not None and dask_local < 1:
        raise CLIError(f"--dask-local = {dask_local}: must be >= 1")
    if not (math.isfinite(connect_timeout) and 0 < connect_timeout <= MAX_CONNECT_TIMEOUT):
        raise CLIError(f"--connect-timeout = {connect_timeout}: must be in (0, "
                       f"{MAX_CONNECT_TIMEOUT:g}] s")  # fmt: skip
    workers = capped("--workers", workers)
    dask_local = capped("--dask-local", dask_local) if dask_local else dask_local
    if scheduler is None and dask_local is None:
        if not workers:
            yield None, 1
            return
        pool = ProcessPoolExecutor(workers)
        try:
            yield pool, workers
        finally:
            pool.shutdown(cancel_futures=True)
        return
    with _dask_client(scheduler, dask_local, connect_timeout) as client:
        executor = client.get_executor()
        try:
            yield executor, max(1, sum(client.nthreads().values()))
        finally:
            executor.shutdown(wait=False)


@contextmanager
def _dask_client(scheduler: str | None, n: int | None, timeout: float) -> Iterator[Any]:
    import distributed

    if scheduler is None:
        cluster = local_cluster(n or 1)
        client = distributed.Client(cluster)
        try:
            yield client
        finally:
            client.close()
            cluster.close()
        return
    try:
        client = distributed.Client(scheduler, timeout=timeout)
    except (OSError, ValueError) as exc:  # a bad address; none answering (TimeoutError)
        refused = f"--scheduler {scheduler}: {_line(exc)}"
    else:
        refused = None
    if refused is not None:
        # the half-started Client sits in a reference cycle: collected here, its __del__
        # closes its loop now; left to a later collection, that __del__ can run inside the
        # next Client's loop start (the new thread's bootstrap), which holds the lock its
        # close waits for: the process hung (a full suite run, in-process main())
        gc.collect()
        raise CLIError(refused)
    try:
        try:
            client.wait_for_workers(1, timeout=timeout)
        except (OSError, TimeoutError):
            raise CLIError(
                f"--scheduler {scheduler}: no worker joined within {timeout:g} s"
            ) from None
        yield client
    finally:
        client.close()


def local_cluster(n: int) -> Any:
    """A Dask LocalCluster of ``n`` worker processes, one thread each, without the
    ``MALLOC_TRIM_THRESHOLD_=65536`` Dask sets in its workers' environment by default: glibc
    then maps and unmaps every array above 128 KiB, and a 20 000-design chunk takes 1.2 s in
    a worker instead of 0.4 s (measured here). A value the user set in the environment
    is kept (the workers inherit it).

    The workers start with SIGINT ignored (a disposition a new process inherits, and
    Python and asyncio keep): Ctrl-C in a terminal signals the whole process group, and
    each worker printed its KeyboardInterrupt traceback (38–63 lines, issue 45). Only this
    process takes the Ctrl-C; it stops the sweep and closes the cluster."""
    import dask
    import distributed

    try:
        old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: signals are not ours to set
        old = None
    try:
        with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
            return distributed.LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                # any free port for its HTTP server: None still binds 8787, and a second
                # cluster on the machine then failed this one's start (port in use)
                dashboard_address=":0",
                # CRITICAL, not ERROR: not a warning per chunk cancelled by Ctrl-C, nor the
                # ERROR and traceback a worker logs when its heartbeat meets the scheduler
                # closing after a Ctrl-C (a race, seen in a full suite run). What the user
                # needs comes through the futures: a task's exception, as the sweep's line
                silence_logs=logging.CRITICAL,
            )
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)


def _line(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return text.splitlines()[0]


__all__ = ["capped", "local_cluster", "sweep_executor", "usable_cpus"]
