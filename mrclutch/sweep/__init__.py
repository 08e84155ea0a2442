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
This package re-exports their public names on first use (PEP 562, as geometry's
``EXPORTS``): the sweep plot in a fresh process needs ``front`` and ``store`` only, not the
running machinery ``run``, ``spec``, ``record`` and ``lock`` load (53–119 ms, issue 40).
"""

import importlib
from typing import Any

#: Each re-exported name → the module that defines it (tests/test_architecture.py reads
#: this table as imports of this package).
EXPORTS: dict[str, str] = {
    "CHUNKS_PER_WORKER": "mrclutch.sweep.run",
    "DEFAULT_CHUNK": "mrclutch.sweep.spec",
    "MAX_DESIGNS": "mrclutch.sweep.spec",
    "MAX_ROWS_IN_FLIGHT": "mrclutch.sweep.run",
    "META_INTERVAL": "mrclutch.sweep.record",
    "UNUSED_SECTIONS": "mrclutch.sweep.spec",
    "Evaluator": "mrclutch.sweep.run",
    "MaterialFile": "mrclutch.sweep.spec",
    "ParamRange": "mrclutch.sweep.spec",
    "SweepResult": "mrclutch.sweep.run",
    "SweepSpec": "mrclutch.sweep.spec",
    "chunk_rows": "mrclutch.sweep.run",
    "chunks_in_flight": "mrclutch.sweep.run",
    "csv_text": "mrclutch.sweep.store",
    "executor_workers": "mrclutch.sweep.run",
    "is_parquet": "mrclutch.sweep.store",
    "load_spec": "mrclutch.sweep.spec",
    "model_version": "mrclutch.sweep.record",
    "output_lock": "mrclutch.sweep.lock",
    "pareto_front": "mrclutch.sweep.front",
    "parse_parameters": "mrclutch.sweep.spec",
    "read_results": "mrclutch.sweep.store",
    "run_sweep": "mrclutch.sweep.run",
    "sigterm_as_interrupt": "mrclutch.sweep.run",
}

__all__ = sorted(EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in EXPORTS:
        raise AttributeError(f"module 'mrclutch.sweep' has no attribute {name!r}")
    return getattr(importlib.import_module(EXPORTS[name]), name)
