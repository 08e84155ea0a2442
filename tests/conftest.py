"""Fixtures shared across test modules."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

from mrclutch import docs_figures

#: What pytest_configure changed in os.environ, restored by pytest_unconfigure.
_ENV_SAVED: dict[str, str | None] = {}


def pytest_configure(config: pytest.Config) -> None:
    """The tool's subprocesses (``python -m mrclutch …``: the help meta-test, the docs'
    figures, the sweeps) keep their bytecode, as an installed package does: with
    ``PYTHONDONTWRITEBYTECODE`` set (this workplace's shells set it) each of them compiled
    the project's sources again, ≈ 0.3 s of CPU a process. The bytecode goes to a cache
    folder outside the tree (``PYTHONPYCACHEPREFIX``); the environment is restored at the
    end of the session."""
    if not os.environ.get("PYTHONDONTWRITEBYTECODE") or os.environ.get("PYTHONPYCACHEPREFIX"):
        return
    for key in ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX"):
        _ENV_SAVED[key] = os.environ.get(key)
    del os.environ["PYTHONDONTWRITEBYTECODE"]
    user = os.getuid() if hasattr(os, "getuid") else os.getpid()
    prefix = Path(tempfile.gettempdir()) / f"mrclutch-tests-pyc-{user}"
    os.environ["PYTHONPYCACHEPREFIX"] = str(prefix)


def pytest_unconfigure(config: pytest.Config) -> None:
    for key, value in _ENV_SAVED.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value
    _ENV_SAVED.clear()


@pytest.fixture(autouse=True, scope="session")
def _fem_memory_budget():
    """A test worker holds the libraries and caches of every test it ran (0.8 GiB seen), not
    one command's: the FEM's budget counts what the process holds (1 GiB in all by default,
    magnetics.fem.grid.memory_budget), so the tests get the old 4 GiB unless the environment
    sets one (tests/mrclutch/test_memory_limit.py tests the default). Session-wide, so the
    module-scoped fixtures that run a report or an optimiser in process get it too (a
    function-scoped one came after them); undone at the session's end."""
    with pytest.MonkeyPatch.context() as mp:
        if "MRCLUTCH_FEM_MEMORY_GB" not in os.environ:
            mp.setenv("MRCLUTCH_FEM_MEMORY_GB", "4")
        yield


@pytest.fixture(scope="session")
def figures_runner(tmp_path_factory):
    """One docs_figures.Runner for the session (each command the docs' figures quote runs
    once a worker: ``mrclutch fidelity``'s full run, a minute, feeds docs/fidelity.md's table)."""
    return docs_figures.Runner(tmp_path_factory.mktemp("figures"))
