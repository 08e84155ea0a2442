"""The design report's CAD side in a second process: build123d's import (seconds), the
B-rep mass, the STEP and STL export and the 3D view's rendering run there while the report's own
process solves the FEM and draws the plots (issue 40: a report on 2 cores).

``CadProcess(design, folder, check)`` starts it (``python -m mrclutch.cli.report_cad``: a
fresh interpreter, nothing forked from this one and no main module re-run, which
``multiprocessing``'s spawn would do to a script without a ``__main__`` guard) and sends it
the design over a pipe; ``result(name)`` waits for one task's result in the order of
``TASKS``, calling ``check`` (which may raise KeyboardInterrupt) every ``POLL_S``; an error
there is raised here, as the same exception, and its warnings are issued here. ``close()``
kills the process if it still runs and waits for it, so nothing it writes lands after the
caller removes ``folder``. The process runs in a session of its own: a terminal's Ctrl-C
reaches the report only, which stops and closes it (a KeyboardInterrupt raised inside
OpenCascade's C++ could abort it instead: see ``mrclutch.sweep.run.sigterm_as_interrupt``).

The process defers the packages build123d imports and its work never calls (``DEFERRED``:
sklearn, IPython, scipy; ``defer_imports``), so build123d's import costs about half.
"""

from __future__ import annotations

import ctypes
import dis
import importlib
import importlib.abc
import os
import pickle
import signal
import subprocess
import sys
import types
import warnings
from collections.abc import Callable
from importlib.machinery import ModuleSpec
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from mrclutch.cli.view import render_model
from mrclutch.design import ClutchDesign
from mrclutch.report_data import design_brep_mass, export_cad

#: The tasks of the CAD process, in the order it runs them: the B-rep mass first (the
#: evaluation waits for it), then the STEP + STL files and the 3D view's pixels (the
#: model's part of view.png, mrclutch.cli.view.render_model).
TASKS = ("mass", "cad", "view")
#: Seconds between two calls of ``check`` while a result is awaited.
POLL_S = 0.1


def _jobs(design: ClutchDesign, folder: Path) -> dict[str, Callable[[], Any]]:
    return {
        "mass": lambda: design_brep_mass(design),
        "cad": lambda: export_cad(design, folder),
        # the model's pixels: the report composes view.png with the matplotlib it has
        # loaded already (neither pyvista's plotting layer nor matplotlib is imported here)
        "view": lambda: render_model(design.clutch),
    }


def _picklable(exc: BaseException) -> BaseException:
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:  # an extension's exception: its type and text
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


def _serve(requests: Connection, results: Connection) -> None:
    """The child: reads (design, folder), then runs each task of TASKS and sends its
    result as (name, ok, value, warnings) when done; after an error, nothing more."""
    try:
        design, folder = requests.recv()
        requests.close()
        jobs = _jobs(design, Path(folder))
        for name in TASKS:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")  # the parent's filters decide
                try:
                    ok, value = True, jobs[name]()
                except Exception as exc:
                    ok, value = False, _picklable(exc)
            seen = {(str(w.message), w.category, w.filename, w.lineno) for w in caught}
            results.send((name, ok, value, sorted(seen, key=str)))
            if not ok:
                return
    except (BrokenPipeError, EOFError):  # the report ended first: nobody to tell
        return
    finally:
        results.close()


class _Failed:
    def __init__(self, error: BaseException) -> None:
        self.error = error


class CadProcess:
    """The CAD process of one report: started here, its files written into ``folder``."""

    def __init__(self, design: ClutchDesign, folder: str | Path,
                 check: Callable[[], None]) -> None:  # fmt: skip
        self._check = check
        req_r, req_w = os.pipe()
        res_r, res_w = os.pipe()
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
        try:
            self._proc = subprocess.Popen(
                [sys.executable, "-m", __name__, str(req_r), str(res_w), str(os.getpid())],
                pass_fds=(req_r, res_w), stdin=subprocess.DEVNULL, env=env,
                start_new_session=True,
            )  # fmt: skip
        except BaseException:
            for fd in (req_r, req_w, res_r, res_w):
                os.close(fd)
            raise
        os.close(req_r)
        os.close(res_w)
        self._conn = Connection(res_r, writable=False)
        self._results: dict[str, Any] = {}
        with Connection(req_w, readable=False) as requests:
            try:
                requests.send((design, str(folder)))
            except BrokenPipeError:  # it died at once: result() says so
                pass

    @property
    def pid(self) -> int:
        """The CAD process's id."""
        return self._proc.pid

    def result(self, name: str) -> Any:
        """The result of task ``name`` (waiting for it, ``check()`` every POLL_S)."""
        if name not in TASKS:
            raise ValueError(f"task {name!r}: one of {', '.join(TASKS)}")
        while name not in self._results:
            while not self._conn.poll(POLL_S):
                self._check()
            try:
                got, ok, value, caught = self._conn.recv()
            except EOFError:
                code = self._proc.wait()
                raise RuntimeError(f"the report's CAD process ended (exit code {code}) "
                                   f"before its {name}") from None  # fmt: skip
            for message, category, filename, lineno in caught:
                warnings.warn_explicit(message, category, filename, lineno)
            self._results[got] = value if ok else _Failed(value)
            if not ok:  # the child stopped: this error is every later task's too
                self._results.update({t: self._results[got] for t in TASKS
                                      if t not in self._results})  # fmt: skip
        found = self._results[name]
        if isinstance(found, _Failed):
            raise found.error
        return found

    def close(self) -> None:
        """Kill the process if it still runs, and wait for it."""
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.wait()
        self._conn.close()


#: Packages that build123d's ``__init__`` imports and the CAD work never calls: sklearn (its
#: STL primitive detection), IPython (its notebook display) and scipy (curve fits and convex
#: hulls; sklearn's scipy.stats): ~2.9 s of build123d's ~5.5 s import (issue 40). The CAD
#: process defers them (``defer_imports``). ezdxf is not among them: build123d's DXF exporter
#: reads its constants while its classes are defined, so it would load at once anyway.
DEFERRED = ("sklearn", "IPython", "scipy")
#: The instruction that binds a name in ``from module import name``.
_IMPORT_FROM = dis.opmap["IMPORT_FROM"]


class _DeferredModule(types.ModuleType):
    """A module of a deferred package, not run yet. ``from module import name`` binds a
    ``_Later`` of ``name``; any other use of an attribute (``module.name``) loads the
    package for real and gives the real attribute."""

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("__"):  # the import system's and inspect's probes
            raise AttributeError(attr)
        real = sys.modules.get(self.__name__)
        if real is None or isinstance(real, _DeferredModule):  # not loaded yet
            if _binding(sys._getframe(1)):
                return _Later(self.__name__, attr)
            real = _load(self.__name__)
        return getattr(real, attr)


def _binding(frame: types.FrameType) -> bool:
    """True when ``frame`` runs an import statement's ``from module import name``: the
    statement's own IMPORT_FROM, or importlib's check that each name exists (CPython)."""
    code = frame.f_code
    if code.co_name == "_handle_fromlist" and code.co_filename.startswith("<frozen importlib"):
        return True
    return code.co_code[frame.f_lasti] == _IMPORT_FROM


class _Later:
    """``module.attr`` of a deferred package, bound by ``from module import attr``: the
    package loads for real where it is first called, asked for an attribute, compared,
    hashed, or-ed into a type union, subclassed or used in ``isinstance``. Meant for the
    functions and classes build123d binds at import and calls in its own functions; the
    report's CAD outputs are the same with and without the deferral
    (tests/mrclutch/test_report_cad.py)."""

    __slots__ = ("_real", "_where")

    def __init__(self, module: str, attr: str) -> None:
        object.__setattr__(self, "_where", (module, attr))

    def _resolve(self) -> Any:
        try:
            return object.__getattribute__(self, "_real")
        except AttributeError:
            pass
        module, attr = object.__getattribute__(self, "_where")
        real = _load(module)
        try:
            found = getattr(real, attr)
        except AttributeError:  # a submodule its package does not import itself
            found = _load(f"{module}.{attr}")
        object.__setattr__(self, "_real", found)
        return found

    def __getattr__(self, attr: str) -> Any:
        return getattr(self._resolve(), attr)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._resolve()(*args, **kwargs)

    def __or__(self, other: Any) -> Any:
        return self._resolve() | other

    def __ror__(self, other: Any) -> Any:
        return other | self._resolve()

    def __eq__(self, other: object) -> bool:
        return bool(self._resolve() == other)

    def __hash__(self) -> int:
        return hash(self._resolve())

    def __instancecheck__(self, obj: object) -> bool:
        return isinstance(obj, self._resolve())

    def __subclasscheck__(self, cls: type) -> bool:
        return issubclass(cls, self._resolve())

    def __mro_entries__(self, bases: tuple) -> tuple:
        return (self._resolve(),)

    def __repr__(self) -> str:
        return repr(self._resolve())


class _DeferFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds the modules of the packages ``names`` (submodules included) as
    ``_DeferredModule``s, until a package of them is loaded for real (``_load``)."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = set(names)

    def find_spec(self, fullname: str, path: Any, target: Any = None) -> ModuleSpec | None:
        if fullname.partition(".")[0] not in self.names:
            return None
        return ModuleSpec(fullname, self, is_package=True)  # a __path__: submodules too

    def create_module(self, spec: ModuleSpec) -> types.ModuleType:
        return _DeferredModule(spec.name)

    def exec_module(self, module: types.ModuleType) -> None:
        """Nothing runs until the module is used."""


_FINDERS: list[_DeferFinder] = []


def defer_imports(names: tuple[str, ...] = DEFERRED) -> None:
    """From now on, in this process, importing a module of the packages ``names`` runs
    nothing until the module is used (``_DeferredModule``); then its package loads for real.
    For the CAD process, before build123d's import (``DEFERRED``)."""
    finder = _DeferFinder(names)
    _FINDERS.append(finder)
    sys.meta_path.insert(0, finder)


def _load(module: str) -> types.ModuleType:
    """``module`` imported for real, its package's deferred modules forgotten first."""
    top = module.partition(".")[0]
    for finder in _FINDERS:
        finder.names.discard(top)
    for name in [n for n, m in sys.modules.items() if isinstance(m, _DeferredModule)
                 and n.partition(".")[0] == top]:  # fmt: skip
        del sys.modules[name]
    return importlib.import_module(module)


def _die_with(parent: int) -> None:
    """End this process when ``parent`` ends, however it ends (Linux: the kernel's
    PR_SET_PDEATHSIG), so a report killed by SIGKILL leaves no CAD process writing into
    its staging folder."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # 1: PR_SET_PDEATHSIG, prctl(2)
    if os.getppid() != parent:  # it ended before that took effect
        os._exit(1)


if __name__ == "__main__":  # the child: its two pipes' file descriptors and its parent
    _die_with(int(sys.argv[3]))
    defer_imports()  # before build123d's import (geometry.mass, geometry.export)
    _serve(Connection(int(sys.argv[1]), writable=False),
           Connection(int(sys.argv[2]), readable=False))  # fmt: skip
