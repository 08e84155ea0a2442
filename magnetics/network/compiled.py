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
from typing import TYPE_CHECKING, Any

from geometry.atomic import user_cache
from magnetics.network import kernels

if TYPE_CHECKING:
    import subprocess

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


#: LLVM's optimisation level of the kernels (numba's ``NUMBA_OPT``; numba's own default is 3),
#: unless the user sets ``NUMBA_OPT``. At 2 a machine's first compile of the solver takes
#: ≈ 0.9 s less CPU (this process's, the critical path: medians 10.6 -> 9.7 s) and the sweep's
#: rows per CPU-second are no fewer (13.1e3 vs 11.0e3, 20 000 rows, interleaved), its rows
#: bit-identical at 0-3 (no fastmath: LLVM reassociates nothing at any level); at 1 the same,
#: at 0 the rows are 6x slower (f43's table in its commit message).
_OPT = "2"


def opt_level() -> str:
    """The LLVM optimisation level the kernels compile at: ``NUMBA_OPT`` if set, else
    ``_OPT``."""
    return os.environ.get("NUMBA_OPT") or _OPT


def cache_dir() -> Path:
    """numba's cache of the compiled kernels: ``NUMBA_CACHE_DIR`` if set, else the user's
    cache folder (``$XDG_CACHE_HOME``, ``~/.cache``; ``%LOCALAPPDATA%`` on Windows) under
    ``mrclutch/numba/opt<level>``. Never inside the installed package: a cache left there
    outlives a reinstall, and Python then takes its folder for the package (issue 39). A
    folder per optimisation level (``opt_level``): numba's cache index keys an entry by its
    signature, the CPU and the bytecode, not the level, so a kernel compiled once at
    ``NUMBA_OPT=0`` (6x slower rows) would be served to every later run; the same answers
    either way. A ``NUMBA_CACHE_DIR`` the user sets is used as it is."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    return Path(env) if env else user_cache("numba") / f"opt{opt_level()}"


def numba_module() -> Any:
    """numba, imported with its cache in ``cache_dir()`` and its optimisation level
    ``opt_level()`` (the environment variables set before the import, so numba's config,
    and any process this one starts, read them; numba's compiler rereads them before each
    compile, so they hold if numba was imported before)."""
    os.environ["NUMBA_CACHE_DIR"] = str(cache_dir())
    os.environ["NUMBA_OPT"] = opt_level()
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
    # no reference counting (NRT): the kernels allocate nothing (the caller's workspace,
    # ``kernels._workspace``), and without it ≈ 20 % less code compiles (IR lines counted)
    jit = numba.njit(cache=True, error_model="numpy", _nrt=False)
    inline = numba.njit(cache=True, error_model="numpy", _nrt=False, inline="always")
    for name in kernels._KERNELS:
        f = g[name]
        code = types.FunctionType(f.__code__, ns, f.__name__, f.__defaults__)
        ns[name] = (inline if name in _INLINE else jit)(code)
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
    "_solve_rows": f"void({_F2}, {_I1}, int64, int64, {_MAT}, {_F2}, int64[:, ::1], {_F3}, "
    f"boolean, {_F2}, float64, int64, {_F3}, boolean[::1], {_F2})",
    "_tangent_rows": f"void({_F2}, {_I1}, int64, int64, {_MAT}, {_F3}, {_F2}, {_F1}, {_F3}, {_F2})",
}

#: Kernels compiled inline into their one caller (numba's ``inline="always"``), not on their
#: own: the Newton, called once by ``_solve_rows`` (its own compile re-optimised and emitted
#: the residual's and the solve's code once more, ≈ 2 s of CPU, that ``_solve_rows`` then
#: optimised again).
_INLINE = ("_newton",)

#: Kernels a second process compiles into numba's cache while this one compiles the others
#: (``_Clock``, on a machine of 2 or more cores): the Thomas solve and its ladder (≈ 30 % of
#: the solver's compile), which no kernel of the residual calls; those that call them (the
#: Newton, the entries) compile after it, on the code it cached.
_BESIDE = ("_solve_ladder", "_solve")
_BESIDE_WAIT_S = 300.0  # past this the second process is ended and its kernels compiled here


@functools.cache
def _calls(name: str) -> tuple[str, ...]:
    """The kernels ``name`` calls, directly or through others (those compiled inline too,
    ``_INLINE``), in ``_SIGNATURES``' order."""
    seen, todo = set(), [name]
    while todo:
        for called in vars(kernels)[todo.pop()].__code__.co_names:
            if (called in _SIGNATURES or called in _INLINE) and called not in seen:
                seen.add(called)
                todo.append(called)
    return tuple(k for k in _SIGNATURES if k in seen and k != name)


def load(
    kernel: Any,
    signature: str,
    what: str,
    before: tuple[tuple[Any, str], ...] = (),
    beside: tuple[str, ...] = (),
) -> Any:
    """``kernel`` (a numba dispatcher) with its one overload, ``signature``, loaded from
    numba's cache or, where the cache holds none, compiled, after ``before`` (the kernels it
    calls: (dispatcher, signature) pairs, each compiled or loaded for its own signature
    first, so the kernel's calls find them and compile no overload of their own); every one
    then closed to more overloads (a call of another type is an error, never a compile). A
    compile says so on stderr once it runs past ``_COMPILE_NOTICE_S``, with an estimate of
    its time (``_Clock``), and its time after. ``beside``: names of kernels in ``before``
    that a second process compiles meanwhile (``_compile_beside``)."""
    if not hasattr(kernel, "stats"):  # NUMBA_DISABLE_JIT: the Python function
        return kernel
    from numba.core.event import install_listener

    clock = _listener()(kernel, what, before, beside)
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
    stderr with an estimate of the time left (once ``_NOTICE_SHARE`` of the bytecode after
    the first kernel is compiled): the time since the first kernel compiled scaled by the
    bytecode still to compile over the bytecode compiled since (each kernel's
    share of the compile taken as its share of the kernels' bytecode; those loaded from the
    cache leave the count; the first kernel's time holds the process's first-compile start,
    whatever its size), and the
    time it took after (``finish``). benchmarks/bench_waits.py prints the estimate beside
    the time the compile took. The kernels named in ``beside`` (and what they call) compile
    in a second process meanwhile (``_compile_beside``): they leave the count, and the
    kernels that call them compile after it."""

    def __init__(self, kernel: Any, what: str, before: tuple[tuple[Any, str], ...],
                 beside: tuple[str, ...] = ()) -> None:  # fmt: skip
        self.kernel, self.what, self.before, self.beside = kernel, what, before, beside
        self.weight = {id(d): _weight(d) for d, _ in (*before, (kernel, ""))}
        self.total = float(sum(self.weight.values()))  # bytecode to compile
        self.done = 0.0  # bytecode compiled
        self.warm: tuple[float, float] | None = None  # (time, bytecode) at the first's end
        self.compiled: set[int] = set()
        self.t0: float | None = None
        self.said = False
        self.lock = threading.Lock()
        self.timer = threading.Timer(_COMPILE_NOTICE_S, self.opening)
        self.timer.daemon = True

    def on_start(self, ev: Any) -> None:
        disp = ev.data["dispatcher"]
        self.compiled.add(id(disp))
        if disp is not self.kernel or self.t0 is not None:
            return
        self.t0 = time.perf_counter()
        self.timer.start()
        late = set(self.beside)  # the second process's kernels and those that call them
        late.update(n for n in _SIGNATURES if late & set(_calls(n)))
        first = [(d, s) for d, s in self.before if _name(d) not in late]
        after = [(d, s) for d, s in self.before if _name(d) in late]
        child = _compile_beside(self.beside) if self.beside else None
        mine: set[int] = set()  # the second process's own: out of the count (meanwhile)
        if child is not None:
            mine = {id(d) for d, _ in self.before if _name(d) in self.beside}
            self.total -= sum(self.weight[k] for k in mine)
        try:
            for i, (d, sig) in enumerate((*first, *after)):
                if i == len(first) and child is not None:
                    _wait(child)
                _one(d, sig)
                if id(d) not in self.compiled and id(d) not in mine:  # loaded: no compile
                    self.total -= self.weight[id(d)]
        except BaseException:  # Ctrl-C or a failed compile: no second process left running
            if child is not None:
                child.kill()
                child.wait()
            raise

    def on_end(self, ev: Any) -> None:
        key = id(ev.data["dispatcher"])
        if key in self.weight and self.t0 is not None:
            self.done += self.weight[key]
            if self.warm is None:
                self.warm = (time.perf_counter(), self.done)
            if time.perf_counter() - self.t0 > _COMPILE_NOTICE_S and self.done < self.total:
                self.notice()

    def opening(self) -> None:
        """Past ``_COMPILE_NOTICE_S``: that it compiles (the estimate follows, ``notice``)."""
        with self.lock:
            if not self.said:
                print(f"mrclutch: compiling {self.what} (numba, once on this machine) …",
                      file=sys.stderr, flush=True)  # fmt: skip
        self.notice()

    def notice(self) -> None:
        """The notice, once, when enough kernels are compiled (the estimate's scale)."""
        with self.lock:
            # once 15 % of the bytecode after the first kernel is compiled (_NOTICE_SHARE),
            # with some compiled since it (a rate) and some left (the timer's call may come
            # after the last kernel, e.g. when all but the entry loaded from the cache)
            if (
                self.said
                or self.warm is None
                or self.done <= self.warm[1]
                or self.done >= self.total
                or self.done - self.warm[1] < _NOTICE_SHARE * (self.total - self.warm[1])
            ):
                return
            self.said = True
            now = time.perf_counter()
            took = now - self.t0  # type: ignore[operator]
            # the rate after the first kernel: its time holds the process's first-compile
            # start (numba's typing and lowering set up), ≈ 1 s, whatever its size
            rate = (now - self.warm[0]) / (self.done - self.warm[1])
            left = rate * max(self.total - self.done, 0.0)
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


def _name(kernel: Any) -> str:
    """A dispatcher's kernel name (its Python function's)."""
    return str(getattr(getattr(kernel, "py_func", None), "__name__", ""))


def _compile_beside(names: tuple[str, ...]) -> subprocess.Popen[bytes] | None:
    """A second process that compiles the kernels ``names`` (and what they call) into
    numba's cache (``compile_alone``), started when this machine has a second core; None
    otherwise. Its output is discarded: if it fails, this process compiles them itself."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    if cores < 2:
        return None
    import subprocess  # only where a process is started: not a one-design command's import

    root = str(Path(kernels.__file__).resolve().parents[2])
    path = os.pathsep.join(filter(None, (root, os.environ.get("PYTHONPATH"))))
    code = "import sys\nfrom magnetics.network.compiled import compile_alone\n" \
        "compile_alone(sys.argv[1:])"  # fmt: skip
    try:
        return subprocess.Popen([sys.executable, "-c", code, *names], cwd=root,
                                env={**os.environ, "PYTHONPATH": path},
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)  # fmt: skip
    except OSError:
        return None


def _wait(child: subprocess.Popen[bytes]) -> None:
    """The second process's end (ended after ``_BESIDE_WAIT_S``: what it has not cached
    compiles here)."""
    import subprocess

    try:
        child.wait(timeout=_BESIDE_WAIT_S)
    except subprocess.TimeoutExpired:
        child.kill()
        child.wait()


def compile_alone(names: list[str]) -> None:
    """The kernels ``names``, each after what it calls, compiled (or loaded) into numba's
    cache for their signatures: the second process of ``_compile_beside``."""
    ns = _kernels()
    for name in names:
        for k in (*_calls(name), name):
            _one(ns[k], _SIGNATURES[k])


#: The share of the bytecode after the first kernel that is compiled before the notice
#: gives its estimate: at 15 % the solver's six small kernels (~1 s into a first run), with
#: ``_weight``'s fit at level 2 ~0.8-0.9x the compile's time in three fresh caches; at 25 %
#: (the share before that fit) not before the residual, ~4-5 s in, at 0.9-1.2x. The small
#: kernels also bear the first use of each numba feature (rated alone: 1.6-2.8x over at
#: level 3, before ``_weight`` was fitted).
_NOTICE_SHARE = 0.15


def _weight(kernel: Any) -> int:
    """A kernel's share of a compile, in bytes of bytecode: its own, nine tenths of the
    kernels' it calls (numba links their code into its module and LLVM optimises it again)
    and 167 for a compile's fixed cost: a least-squares fit of the solver kernels' compile
    times at LLVM level 2 (``_OPT``; CPU, 4 fresh caches, ``python benchmarks/bench_network.py
    --compile``, the first kernel left out: it bears numba's start-up) to 0.060 s +
    3.6e-4 s/byte own + 3.2e-4 s/byte called: the two large kernels within 1 %, the six
    small ones within 0.1 s each and 1 % together. The fit at level 3 (0.086 s + 6.4e-4 own
    + 1.4e-4 called) put the notice's estimate at 0.5-0.7x the compile at level 2."""
    name = kernel.py_func.__name__
    called = _calls(name) if name in _SIGNATURES else ()
    size = sum(len(vars(kernels)[k].__code__.co_code) for k in called)
    return len(kernel.py_func.__code__.co_code) + 9 * size // 10 + 167


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
        beside = tuple(k for k in _BESIDE if k in _calls(name) and not ns[k].overloads)
        load(kernel, _SIGNATURES[name], _WHAT[name], before, beside)
        _loaded.add(name)
        _loaded.add("network")
    return kernel


_WHAT = {"_solve_rows": "the reluctance network's solver",
         "_tangent_rows": "the network's flux linkage"}  # fmt: skip
