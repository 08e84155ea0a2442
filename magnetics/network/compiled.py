"""**One compiled kernel** (issue 31, docs/architecture.md): the network's kernels
(``magnetics.network.kernels``: the residual, its Jacobian, the Newton step and the whole
Newton with its line search) compiled by numba (``@njit(cache=True)``, ``_kernels``) and run
one design and current at a time; they are the network's only solver. numba is imported, and
the kernels compiled or loaded from numba's cache, on the first compiled solve of a process
(``_entry``), each kernel for its one signature; a first compile on a machine says so on
stderr with an estimate of its time (``load``). A few rows run the same functions as plain
Python (``uncompiled``: a single design never pays for loading the compiler).
``NUMBA_DISABLE_JIT=1`` runs the same functions as Python (the debug path: slow, the same
answers).
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

from magnetics.network import kernels

_COMPILE_NOTICE_S = 1.0  # a first compile longer than this says so on stderr

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
    ``limit``. The same functions either way (one implementation). (Not while any compiled
    kernel is loaded: the reading of a 10³-design solve, 1.6·10⁴ cells, then loads its
    compiled reader in ≈ 0.04 s instead of ≈ 0.8 s in Python, but a machine's first such
    run then compiles the reader too, ≈ 2 s of CPU, issue 40's first-run wait.)"""
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


#: Each kernel's one signature (numba's types; arrays C-contiguous, as every caller passes
#: them), in the order they compile: each after the kernels it calls. A kernel compiled for
#: its signature alone, then closed to more (``load``), so no call compiles a second overload
#: (a literal material row or a read-only array would: 32 overloads of 13 kernels before).
#: The Thomas solve first: a kernel of a typical size, whose time scales the compile notice's
#: estimate (``_Clock``) better than the few-line helpers that open it otherwise.
_F1, _I1, _F2, _F3 = "float64[::1]", "int64[::1]", "float64[:, ::1]", "float64[:, :, ::1]"
_MAT = f"{_F3}, {_F1}, {_I1}"  # a material table, its 1/step and its segments (``_tables``)
_SIGNATURES = {
    "_solve_ladder": f"void(int64, {_F1}, int64, int64, {_F2}, {_F2})",
    "_jac_layout": "UniTuple(int64, 8)(int64)",
    "_solve": f"void(int64, {_F1}, {_F1}, {_F1}, {_F2})",
    "_segment": f"int64({_F1}, {_I1}, int64, float64)",
    "_h_dh": f"UniTuple(float64, 2)({_MAT}, int64, float64)",
    "_h_mean_dh": f"UniTuple(float64, 2)({_MAT}, int64, float64)",
    "_odd": f"UniTuple(float64, 2)({_MAT}, int64, float64, float64, float64, boolean)",
    "_pair": f"UniTuple(float64, 5)({_MAT}, int64, {', '.join(['float64'] * 6)}, boolean)",
    "_band": f"UniTuple(float64, 3)({_MAT}, {', '.join(['float64'] * 5)}, boolean)",
    "_residual": f"void({_F1}, {_I1}, int64, int64, {_MAT}, {_F1}, float64, {_F1}, boolean, "
    f"{_F1}, {_F1}, {_F2})",
    "_workspace": f"{_F2}(int64)",
    "_newton": f"Tuple((boolean, int64))({_F1}, {_I1}, int64, int64, {_MAT}, float64, {_F1}, "
    f"boolean, float64, float64, int64, {_F1}, {_F2})",
    "_solve_rows": f"void({_F2}, {_I1}, int64, int64, {_MAT}, {_F2}, int64[:, ::1], {_F3}, "
    f"boolean, {_F2}, float64, int64, {_F3}, boolean[::1])",
    "_tangent_rows": f"void({_F2}, {_I1}, int64, int64, {_MAT}, {_F3}, {_F2}, {_F1}, {_F3})",
}


@functools.cache
def _calls(name: str) -> tuple[str, ...]:
    """The kernels ``name`` calls, directly or through others, in ``_SIGNATURES``' order."""
    seen, todo = set(), [name]
    while todo:
        for called in vars(kernels)[todo.pop()].__code__.co_names:
            if called in _SIGNATURES and called not in seen:
                seen.add(called)
                todo.append(called)
    return tuple(k for k in _SIGNATURES if k in seen and k != name)


def load(kernel: Any, signature: str, what: str, before: tuple[tuple[Any, str], ...] = ()) -> Any:
    """``kernel`` (a numba dispatcher) with its one overload, ``signature``, loaded from
    numba's cache or, where the cache holds none, compiled, after ``before`` (the kernels it
    calls: (dispatcher, signature) pairs, each compiled or loaded for its own signature
    first, so the kernel's calls find them and compile no overload of their own); every one
    then closed to more overloads (a call of another type is an error, never a compile). A
    compile says so on stderr once it runs past ``_COMPILE_NOTICE_S``, with an estimate of
    its time (``_Clock``), and its time after."""
    if not hasattr(kernel, "stats"):  # NUMBA_DISABLE_JIT: the Python function
        return kernel
    from numba.core.event import install_listener

    clock = _listener()(kernel, what, before)
    with install_listener("numba:compile", clock):
        _one(kernel, signature)
    clock.finish()
    return kernel


def _one(kernel: Any, signature: str) -> None:
    """``kernel`` compiled (or loaded) for ``signature`` unless it holds it, then closed."""
    from numba.core.sigutils import normalize_signature

    if tuple(normalize_signature(signature)[0]) not in kernel.overloads:
        kernel.compile(signature)
    kernel.disable_compile()


@functools.cache
def _listener() -> type:
    """``_Clock`` as numba's event listener (numba imported by then)."""
    from numba.core.event import Listener

    return type("Clock", (_Clock, Listener), {})


class _Clock:
    """A listener of numba's compile events while ``load`` runs. On the kernel's own compile
    (a cache miss) it compiles ``before`` first; past ``_COMPILE_NOTICE_S`` it says so on
    stderr with an estimate of the time left: the time so far scaled by the bytecode still
    to compile over the bytecode compiled (each kernel's share of the compile taken as its
    share of the kernels' bytecode; those loaded from the cache leave the count), and the
    time it took after (``finish``). benchmarks/bench_waits.py prints the estimate beside
    the time the compile took."""

    def __init__(self, kernel: Any, what: str, before: tuple[tuple[Any, str], ...]) -> None:
        self.kernel, self.what, self.before = kernel, what, before
        self.weight = {id(d): _weight(d) for d, _ in (*before, (kernel, ""))}
        self.total = float(sum(self.weight.values()))  # bytecode to compile
        self.done = 0.0  # bytecode compiled
        self.compiled: set[int] = set()
        self.t0: float | None = None
        self.said = False
        self.lock = threading.Lock()
        self.timer = threading.Timer(_COMPILE_NOTICE_S, self.notice)
        self.timer.daemon = True

    def on_start(self, ev: Any) -> None:
        disp = ev.data["dispatcher"]
        self.compiled.add(id(disp))
        if disp is not self.kernel or self.t0 is not None:
            return
        self.t0 = time.perf_counter()
        self.timer.start()
        for d, sig in self.before:
            _one(d, sig)
            if id(d) not in self.compiled:  # loaded from the cache (or held): no compile
                self.total -= self.weight[id(d)]

    def on_end(self, ev: Any) -> None:
        key = id(ev.data["dispatcher"])
        if key in self.weight and self.t0 is not None:
            self.done += self.weight[key]
            if time.perf_counter() - self.t0 > _COMPILE_NOTICE_S and self.done < self.total:
                self.notice()

    def notice(self) -> None:
        """The notice, once, as soon as a kernel is compiled (the estimate's scale)."""
        with self.lock:
            if self.said or self.t0 is None or self.done <= 0:
                return
            self.said = True
            took = time.perf_counter() - self.t0
            left = took * max(self.total - self.done, 0.0) / self.done
            print(f"mrclutch: compiling {self.what} (numba, once on this machine): ~{left:.0f} s "
                  f"left of ~{took + left:.0f} s …", file=sys.stderr, flush=True)  # fmt: skip

    def finish(self) -> None:
        self.timer.cancel()
        if self.t0 is None:
            return
        took = time.perf_counter() - self.t0
        if took > _COMPILE_NOTICE_S:
            print(f"mrclutch: compiled in {took:.1f} s (cached in {cache_dir()}: later runs "
                  "load it)", file=sys.stderr)  # fmt: skip


def _weight(kernel: Any) -> int:
    """A kernel's share of a compile: the length of its function's bytecode."""
    return len(kernel.py_func.__code__.co_code)


def _entry(name: str, rows: int) -> Any:
    """The kernel ``name`` (``_solve_rows``, ``_tangent_rows``) to run ``rows`` rows with:
    the module's own Python function while ``uncompiled`` allows, else the compiled one
    (loaded once a process, ``load``: what it calls compiled first where the cache misses)."""
    if uncompiled("network", rows, _PY_ROWS):
        return vars(kernels)[name]
    ns = _kernels()
    kernel = ns[name]
    if name not in _loaded:
        before = tuple((ns[k], _SIGNATURES[k]) for k in _calls(name))
        load(kernel, _SIGNATURES[name], _WHAT[name], before)
        _loaded.add(name)
        _loaded.add("network")
    return kernel


_WHAT = {"_solve_rows": "the reluctance network's solver",
         "_tangent_rows": "the network's flux linkage"}  # fmt: skip
