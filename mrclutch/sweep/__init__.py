"""Vectorised design sweeps: a spec, chunks of designs, CSV streamed as it comes, resume.

A sweep is a grid or a random sample over DrumClutch parameters (ranges in mm in the spec
file). Designs are numbered 0..N−1; chunk k holds designs [k·C, (k+1)·C). A chunk's
designs depend only on the spec and k (random chunks draw from a generator seeded with
(seed, k)), so an interrupted sweep resumed later writes exactly the rows an
uninterrupted one would.

Each finished chunk is appended to the CSV in order with one write and a flush; a
sidecar ``<out>.meta.json`` records the spec's fingerprint (``resume`` refuses a different
spec) and, as they are written, every chunk's row range, byte range and SHA-256. A resume
verifies every recorded chunk (sizes, then checksums) and refuses, naming the first bad
chunk, a file that does not match; ``repair=True`` recomputes just the damaged chunks and
restores the file an uninterrupted run writes, byte for byte. An advisory lock
(``<out>.lock``, flock) keeps a second writer out while one runs; the kernel drops the lock
of a killed run, so its lock file is taken over. Every file goes through the output layer
(``geometry.atomic``): a full disk ends in one line and leaves whole chunks only. Any
``concurrent.futures.Executor`` (a process pool, or a Dask ``Client.get_executor()``) may
evaluate the chunks.

Where a change goes: ``spec`` (the spec file, its parameters and material files, the
designs of each chunk), ``run`` (running, interrupting and resuming a sweep), ``store``
(the CSV and Parquet output, reading it back), ``record`` (the ``.meta.json`` sidecar: what
a resume checks), ``lock`` (one writer at a time), ``front`` (the Pareto front of the rows).
This package re-exports their public names.
"""

from __future__ import annotations

from mrclutch.sweep.front import pareto_front
from mrclutch.sweep.lock import output_lock
from mrclutch.sweep.record import META_INTERVAL, model_version
from mrclutch.sweep.run import (
    CHUNKS_PER_WORKER,
    MAX_ROWS_IN_FLIGHT,
    Evaluator,
    SweepResult,
    chunk_rows,
    chunks_in_flight,
    executor_workers,
    run_sweep,
    sigterm_as_interrupt,
)
from mrclutch.sweep.spec import (
    DEFAULT_CHUNK,
    MAX_DESIGNS,
    UNUSED_SECTIONS,
    MaterialFile,
    ParamRange,
    SweepSpec,
    load_spec,
    parse_parameters,
)
from mrclutch.sweep.store import csv_text, is_parquet, read_results

__all__ = [
    "CHUNKS_PER_WORKER",
    "DEFAULT_CHUNK",
    "MAX_DESIGNS",
    "MAX_ROWS_IN_FLIGHT",
    "META_INTERVAL",
    "UNUSED_SECTIONS",
    "Evaluator",
    "MaterialFile",
    "ParamRange",
    "SweepResult",
    "SweepSpec",
    "chunk_rows",
    "chunks_in_flight",
    "csv_text",
    "executor_workers",
    "is_parquet",
    "load_spec",
    "model_version",
    "output_lock",
    "pareto_front",
    "parse_parameters",
    "read_results",
    "run_sweep",
    "sigterm_as_interrupt",
]
