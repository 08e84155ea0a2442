"""How long a job will take, measured before it starts: a sweep's designs at the rate the
fast path runs here, one chunk's synced write, ``--verify-top``'s FEM solves at the FEM's
rate per grid node. The CLI says the estimate and asks for ``--yes``
(``mrclutch.cli.longjobs``); the measuring is here (issue 43: no computation under
``mrclutch/cli/``)."""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from geometry.atomic import write_bytes
from geometry.section import build_section
from magnetics.fem.grid import check_memory, time_estimate
from magnetics.network import use_compiled
from mrclutch.design import ClutchDesign


def sweep_rate(spec: Any, evaluator: Callable[[Mapping[str, Any]], Any], workers: int
               ) -> tuple[float, int]:  # fmt: skip
    """Designs/s of ``spec``'s sweep on ``workers`` processes, and how many designs the
    rate was measured on: the first designs of the spec timed (after 8 to warm up; chunks
    of its chunk size, up to 1024 designs or 0.3 s), on the compiled kernels the chunks run
    (``mrclutch.sweep.chunk_rows``), times the workers."""
    n = spec.n_designs
    _, fields = spec.design_fields(0)  # as the chunks are evaluated: a material as its name
    use_compiled()  # the kernels the chunks run (mrclutch.sweep.chunk_rows), not the
    evaluator({k: v[:8] for k, v in fields.items()})  # small-call path; warm: imports, loads
    step = max(1, min(spec.chunk_size, 1024))
    done, t0 = 0, time.perf_counter()
    while done < min(1024, n) and time.perf_counter() - t0 < 0.3:
        evaluator({k: v[done : done + step] for k, v in fields.items()})
        done += step
    return done / max(time.perf_counter() - t0, 1e-9) * max(1, workers), done


def chunk_write_s(out: str | None) -> float:
    """s one chunk's synced write takes beside ``out`` (a 4 kB file through the output
    layer, timed once; 0 without ``out``)."""
    if out is None:
        return 0.0
    folder = Path(out).resolve().parent
    while not folder.is_dir() and folder != folder.parent:
        folder = folder.parent
    try:
        with tempfile.TemporaryDirectory(dir=folder, prefix=".mrclutch-probe-") as tmp:
            t0 = time.perf_counter()
            write_bytes(Path(tmp) / "chunk", bytes(4096))
            return time.perf_counter() - t0
    except OSError:
        return 0.0


def check_fem_size(base: ClutchDesign, size: float) -> None:
    """One FEM solve of ``base`` at element ``size`` (m) fits in memory
    (``magnetics.fem.grid.check_memory``: ParameterError naming the smallest that fits)."""
    check_memory(build_section(base.clutch), size)


def fem_solve_seconds(base: ClutchDesign, size: float, solves: int) -> float:
    """s for ``solves`` FEM solves of ``base`` at element ``size`` (m), at the FEM's
    measured rate per grid node (``magnetics.fem.grid.time_estimate``)."""
    return time_estimate(build_section(base.clutch), size, solves)
