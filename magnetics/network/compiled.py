"""**One compiled kernel** (issue 31, docs/architecture.md): the network's kernels
(``magnetics.network.kernels``: the residual, its Jacobian, the Newton step and the whole
Newton with its line search) compiled by numba (``@njit(cache=True)``, ``_kernels``) and run
one design and current at a time; they are the network's only solver. numba is imported, and
the kernels compiled or loaded from numba's cache, on the first compiled solve of a process
(``_entry``); a first compile on a machine (≈ 10 s) says so on stderr. A few rows run the
same functions as plain Python (``uncompiled``: a single design never pays for loading the
compiler). ``NUMBA_DISABLE_JIT=1`` runs the same functions as Python (the debug path: slow,
the same answers).
"""

from __future__ import annotations

import functools
import os
import sys
import threading
import time
import types
from pathlib import Path
from typing import Any

import numpy as np

from magnetics.materials import magnetic
from magnetics.network import kernels
from magnetics.network.kernels import _PACKED, _tables

_COMPILE_NOTICE_S = 1.0  # a first compile longer than this says so on stderr
_COMPILE_ESTIMATE_S = 10  # CPU seconds of a kernel's first compile (benchmarks/bench_waits.py)

#: Rows (design × current) a process solves with the kernels' own Python before it loads
#: the compiled ones: importing numba and loading a cached kernel cost ≈ 1 s, a row in
#: Python ≈ 1–2 ms, so a single design (``evaluate``, ``torque``, ``haptic``) never pays
#: for machinery sized for 10⁵ (issue 40); past the budget, or once loaded, compiled.
_PY_ROWS = 200
_used: dict[str, int] = {}  # rows run uncompiled so far, per budget
_loaded: set[str] = set()  # compiled entries loaded in this process


def use_compiled() -> None:
    """Run every later solve and torque reading of this process compiled, whatever its
    size. A sweep's chunks call it first: the uncompiled and compiled paths agree to
    rounding (1e-16), not bit for bit, so which path a chunk takes must not depend on what
    the process ran before it (a resumed sweep rewrites byte-identical chunks)."""
    _loaded.update(("network", "reader"))


def uncompiled(budget: str, rows: int, limit: int) -> bool:
    """Whether ``rows`` more rows of ``budget``'s kernel run as plain Python: while this
    process has loaded none of its compiled entry and its rows so far stay within
    ``limit``. The same functions either way (one implementation)."""
    if budget in _loaded or _used.get(budget, 0) + rows > limit:
        return False
    _used[budget] = _used.get(budget, 0) + rows
    return True


def cache_dir() -> Path:
    """numba's cache of the compiled kernels: ``NUMBA_CACHE_DIR`` if set, else the user's
    cache folder (``$XDG_CACHE_HOME``, ``~/.cache``; ``%LOCALAPPDATA%`` on Windows) under
    ``mrclutch/numba``. Never inside the installed package: a cache left there outlives a
    reinstall, and Python then takes its folder for the package (issue 39)."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        return Path(env)
    if sys.platform == "win32" and os.environ.get("LOCALAPPDATA"):
        base = Path(os.environ["LOCALAPPDATA"])
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "mrclutch" / "numba"


def numba_module() -> Any:
    """numba, imported with its cache in ``cache_dir()`` (the environment variable set before
    the import, so numba's config, and any process this one starts, read it)."""
    os.environ["NUMBA_CACHE_DIR"] = str(cache_dir())
    import numba

    numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
    return numba


@functools.cache
def _kernels() -> dict[str, Any]:
    """The compiled kernels (numba, cached on disk in ``cache_dir()``): a namespace of
    their own, the module's globals with every kernel replaced by its dispatcher compiled
    from the same function's code, so the compiled kernels call each other compiled while
    the module's plain functions stay the uncompiled path. Nothing is compiled or loaded
    here: each entry on its first call (``_entry``). ``NUMBA_DISABLE_JIT=1``: the module's
    globals (the debug path)."""
    numba = numba_module()
    g = vars(kernels)
    if numba.config.DISABLE_JIT:
        return g
    ns = dict(g)
    jit = numba.njit(cache=True, error_model="numpy")
    for name in kernels._KERNELS:
        f = g[name]
        ns[name] = jit(types.FunctionType(f.__code__, ns, f.__name__, f.__defaults__))
    return ns


def load(kernel: Any, what: str, warm: Any) -> Any:
    """``kernel`` (a numba dispatcher) with its one overload compiled or loaded by
    ``warm(kernel)`` (a call on no design). A compile (numba's cache holds no index of it
    yet) that runs past ``_COMPILE_NOTICE_S`` says so on stderr while it runs, and its
    time after."""
    cold = _cold(kernel)
    timer = threading.Timer(_COMPILE_NOTICE_S, _notice, (what,))
    timer.daemon = True
    t0 = time.perf_counter()
    if cold:
        timer.start()
    try:
        warm(kernel)
    finally:
        timer.cancel()
    took = time.perf_counter() - t0
    missed = len(kernel.stats.cache_misses) if hasattr(kernel, "stats") else 0
    if missed and took > _COMPILE_NOTICE_S:
        print(f"mrclutch: compiled in {took:.0f} s (cached in {cache_dir()}: later runs load "
              "it)", file=sys.stderr)  # fmt: skip
    return kernel


def _warm_solve(kernel: Any) -> None:
    tab, inv, nseg = _tables(magnetic("steel_1018"), magnetic("mrf_132dg"))
    e2, e3 = np.zeros((0, 1)), np.zeros((0, 1, 8))
    off = np.zeros(len(_PACKED), np.int64)
    kernel(e2, off, 1, 6, tab, inv, nseg, e2, np.zeros((0, 1), np.int64), e3, False, e2, 1e-10,
           60, e3, np.zeros(0, np.bool_))  # fmt: skip


def _warm_tangent(kernel: Any) -> None:
    tab, inv, nseg = _tables(magnetic("steel_1018"), magnetic("mrf_132dg"))
    e2, e3 = np.zeros((0, 1)), np.zeros((0, 1, 8))
    kernel(e2, np.zeros(len(_PACKED), np.int64), 1, 6, tab, inv, nseg, e3, e2, np.zeros(8), e3)


_WARM = {"_solve_rows": (_warm_solve, "the reluctance network's solver"),
         "_tangent_rows": (_warm_tangent, "the network's flux linkage")}  # fmt: skip


def _entry(name: str, rows: int) -> Any:
    """The kernel ``name`` (``_solve_rows``, ``_tangent_rows``) to run ``rows`` rows with:
    the module's own Python function while ``uncompiled`` allows, else the compiled one
    (loaded once a process, ``load``)."""
    if uncompiled("network", rows, _PY_ROWS):
        return vars(kernels)[name]
    kernel = _kernels()[name]
    if name not in _loaded:
        if hasattr(kernel, "stats"):
            warm, what = _WARM[name]
            load(kernel, what, warm)
        _loaded.add(name)
        _loaded.add("network")
    return kernel


def _cold(kernel: Any) -> bool:
    """Whether numba's cache holds no index of ``kernel`` yet (its first compile on this
    machine); False on the debug path (no dispatcher)."""
    if not hasattr(kernel, "stats"):
        return False
    name = f"{kernel.py_func.__module__.rpartition('.')[2]}.{kernel.py_func.__name__}-*.nbi"
    return not any(Path(kernel.stats.cache_path).glob(name))


def _notice(what: str = "the reluctance network's solver") -> None:
    print(f"mrclutch: compiling {what} (numba, once on this machine; ~{_COMPILE_ESTIMATE_S} s "
          "of CPU) …", file=sys.stderr, flush=True)  # fmt: skip
