"""Fixtures shared across test modules."""

from __future__ import annotations

import copy
import os
import re
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path

import pytest

from mrclutch import docs_figures

#: The heaviest work units of the last full run with durations (``CI=1 python -m pytest
#: --durations=80`` at c4490a3, 597 s on 2 workers, idle: each unit's sum of its tests in
#: the slowest 80, a lower bound for a unit with more tests: the install test 100 s, the
#: GetDP comparisons 55 s, test_one_answer 51 s, test_report 39 s, the Dask and Parquet
#: scale-out 38 s, the Pareto CLI 37 s, test_optimize 35 s, the kernel's compile tests 32
#: s, the killed sweeps 31 s, ...; the fidelity figures' unit 26 s and the dense robust
#: sampling 29 s before 9846749 and 27bb597 cut them to ~21 and ~15 s), heaviest first,
#: down to 10 s. xdist hands the units out in collection order (``--no-loadscope-reorder``;
#: its default, most tests first, sent these few-test files last, where one of them ran
#: alone on one worker at the end); a unit not named here follows, those holding more
#: ``slow`` tests first (test_optimize.py and test_sweep_cli.py hold none: unnamed, they
#: were handed out 103rd and 119th of 163 units). Only the order changes.
HEAVY_FIRST = (
    "tests/test_install.py",
    "tests/magnetics/test_onelab.py",
    "tests/mrclutch/test_one_answer.py",
    "tests/mrclutch/test_report.py",
    "tests/mrclutch/test_sweep_scaleout.py",
    "tests/mrclutch/test_optimize_pareto.py",
    "tests/mrclutch/test_optimize.py",
    "tests/magnetics/test_network_kernel.py",
    "tests/mrclutch/test_sweep_cli.py",
    "tests/mrclutch/test_sweep_categorical.py",
    "figures:mrclutch fidelity --preset paper --out {tmp}/fidelity_errors --repeats 1",
    "figures:python benchmarks/measure_torque_convention.py",
    "figures:mrclutch optimize --no-verify --json",
    "tests/mrclutch/test_output_faults.py",
    "tests/mrclutch/test_json_walk.py",
    "tests/mrclutch/test_robust.py",
    "tests/mrclutch/test_sweep_interrupts.py",
    "figures:python benchmarks/figures/circuit_vs_fem_paper.py",
    "figures:python benchmarks/measure_fem_ripple.py",
    "tests/mrclutch/test_cli_geometry.py",
    "tests/mrclutch/test_optimize_json_walk.py",
    "figures:python benchmarks/bench_eddy.py",
)


def _unit(item: pytest.Item, commands: dict[str, str]) -> str:
    """The xdist work unit of a test (``--dist loadgroup``): its file, except that the
    docs' figure checks go by the command they run (one unit a command, so each command
    still runs once in the session, and test_doc_figures.py's 18 commands spread over the
    workers instead of pinning one)."""
    path = item.nodeid.split("::", 1)[0]
    callspec = getattr(item, "callspec", None)
    if path.endswith("test_doc_figures.py") and item.name.startswith(
        "test_quoted_figure_matches_its_command["
    ):
        return "figures:" + commands[callspec.params["key"]]
    return path


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Each test gets its work unit as an ``xdist_group`` (tryfirst: before xdist's worker
    reads the marks into the node ids), and the units are ordered heaviest first
    (``HEAVY_FIRST``), each unit's tests kept together and in their order. Only in an
    xdist worker (the order it reports is the order the units are handed out): a serial
    run (``-n 0``, the mutation runs' ``-x``) keeps pytest's order."""
    if not hasattr(config, "workerinput"):
        return
    commands = {k: f.command for k, f in docs_figures.load_registry().items()}
    units: dict[str, list[pytest.Item]] = {}
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            unit = _unit(item, commands)
            item.add_marker(pytest.mark.xdist_group(re.sub(r"[@\[\]]", "_", unit)))
        else:
            unit = str(item.get_closest_marker("xdist_group").args[0])
        units.setdefault(unit, []).append(item)

    def rank(unit: str) -> tuple[int, int]:
        if unit in HEAVY_FIRST:
            return HEAVY_FIRST.index(unit), 0
        return len(HEAVY_FIRST), -sum(bool(i.get_closest_marker("slow")) for i in units[unit])

    items[:] = [i for unit in sorted(units, key=rank) for i in units[unit]]


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


ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def fresh_python() -> Callable[[str], subprocess.CompletedProcess]:
    """Runs code in a fresh interpreter on this checkout (``PYTHONPATH`` its root, cwd
    there): what a command imports is only seen in a process that imported nothing yet.
    Returns the finished process (text output), its exit status checked to be 0."""

    def run(code: str) -> subprocess.CompletedProcess:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           env=env, cwd=ROOT, timeout=300)  # fmt: skip
        assert p.returncode == 0, p.stderr[-2000:]
        return p

    return run


@contextmanager
def _judged_once() -> Iterator[None]:
    """Inside, ``pipeline.evaluate`` and ``verdict.judge_evaluation`` (what evaluate, compare
    and haptic call; ``verdict.judge`` is the two) compute once per argument tuple and hand
    back that result (the judged JSON as a deep copy: evaluate adds its ``nulls`` to it).
    Both are pure functions of a frozen design, so each command prints what it printed when
    it computed its own (the FEM at reference fidelity, 1-2 s a call; the box over the
    ranges, ~0.5 s); a command that calls them with other arguments (another fidelity,
    nominal only) still computes its own. A report's evaluation (the B-rep mass from its
    CAD process) is left outside by the tests that use it. The modules that bind the two by
    name (compare and haptic's ``haptic_design``, device's ``handoff``) are imported first
    and patched too, so they share the evaluation inside and, outside, call the real ones
    (imported lazily inside, they kept the first context's functions and cache for the rest
    of the process)."""
    from mrclutch import handoff, pipeline, verdict
    from mrclutch.cli.commands import haptic_design

    real_evaluate, real_judge = pipeline.evaluate, verdict.judge_evaluation
    evs: dict = {}
    judged: dict = {}

    def evaluate(design, fidelity="fast", accuracy=None, K=None):
        key = (design, fidelity, accuracy, K)
        if key not in evs:
            evs[key] = real_evaluate(design, fidelity, accuracy, K)
        return evs[key]

    def judge_evaluation(ev, robust=None):
        key = (id(ev), robust)  # ev kept alive below: its id is not reused
        if key not in judged:
            judged[key] = (ev, real_judge(ev, robust))
        return copy.deepcopy(judged[key][1])

    with pytest.MonkeyPatch.context() as mp:
        for module in (pipeline, verdict, haptic_design, handoff):
            mp.setattr(module, "evaluate", evaluate)
        for module in (verdict, haptic_design):
            mp.setattr(module, "judge_evaluation", judge_evaluation)
        yield


@pytest.fixture
def judged_once() -> Callable[[], AbstractContextManager[None]]:
    """A context (``with judged_once():``) in which several commands on one design share
    one evaluation and one judgement (``_judged_once``): tests that run evaluate, compare
    and haptic (text and ``--json``) on the same design pay for it once."""
    return _judged_once
