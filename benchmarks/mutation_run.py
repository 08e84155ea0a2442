"""A sampled mutation run over the physics modules (docs/testing.md): not part of CI.

    python benchmarks/mutation_run.py --sample 200 --jobs 2 --out benchmarks/data/mutation.json

Each mutant changes ONE expression of one module (an arithmetic operator, a comparison, a
numeric constant, a unary minus, a boolean operator) by rewriting the module's AST. The
modules are those of ``geometry/``, ``magnetics/`` and ``mrclutch/haptics/``; strings,
docstrings, annotations, ``raise`` statements and the arguments of validation calls
(``check_*``) are left alone (mutating an error message or a validation limit is not a
physics error). Mutants are drawn uniformly at random (``--seed``) from every possible one.

Each mutant runs in a private copy of the tree (no bytecode cache, its own numba cache),
``-x`` so a killed mutant stops at its first failure, in two stages: first the tests that
execute the mutated line (a per-test coverage map, ``--coverage``, built once by running
the suite under pytest-cov with ``--cov-context=test``); if it survives those (or no test
covers the line, or at most two tests do: numba kernels, CLI subprocesses and module-level
lines run at import are not seen per test by coverage), every test file of its package
that imports the module by name. ``--out`` is resumed: mutants already there are kept.
Killed: a test failed or the run exceeded ``--timeout``. Survived: every selected test
passed. The JSON lists each mutant with its location, the original and the mutated
source, its status and the test that killed it; ``--report`` prints the
Markdown survival table docs/testing.md quotes.
"""

from __future__ import annotations

import argparse
import ast
import concurrent.futures as cf
import copy
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"geometry": "tests/geometry", "magnetics": "tests/magnetics",
            "mrclutch/haptics": "tests/mrclutch", "mrclutch": "tests/mrclutch"}  # fmt: skip
#: The physics run (docs/testing.md's first table): these packages' modules, their tests.
PHYSICS = ("geometry", "magnetics", "mrclutch/haptics")

#: ``--run round``: the modules touched in the last two rounds of work (git log of issues
#: 40–45: the robust verdicts, the uncertain inputs, the process limits, the pipeline, the
#: optimiser, the thermal figures) and the CLI's formatting and plots (what a person reads
#: and sees), run against tests/mrclutch and the thermal tests, with the doc-figure check
#: (tests/test_doc_figures.py) left out: it compares printed numbers with the docs' quoted
#: ones, so it catches a change, not an error.
ROUND_MODULES_D2D4F2C = (
    "mrclutch/robust.py", "mrclutch/uncertainty.py", "mrclutch/process.py",
    "mrclutch/pipeline.py", "mrclutch/optimize.py", "mrclutch/design.py",
    "magnetics/thermal.py", "mrclutch/cli/commands/design.py",
    "mrclutch/cli/commands/haptic.py", "mrclutch/cli/plots/haptic.py",
    "mrclutch/cli/plots/magnetics.py",
)  # fmt: skip
#: The same code where it is today (issue 43 split the modules above): robust.py into
#: robust_search, robust_columns and hand_box; pipeline.py into clutch, at_hand and
#: fast_batch; optimize.py into the optimize/ package, members and estimates; design.py's
#: operating point into operating.py; cli/commands/design.py into one module per command
#: and cli/formatting.py; haptic's run and the plots' responses into haptic_run, impedance.
ROUND_MODULES = (
    "mrclutch/robust.py", "mrclutch/robust_search.py", "mrclutch/robust_columns.py",
    "mrclutch/hand_box.py", "mrclutch/uncertainty.py", "mrclutch/process.py",
    "mrclutch/pipeline.py", "mrclutch/clutch.py", "mrclutch/at_hand.py",
    "mrclutch/fast_batch.py", "mrclutch/optimize/__init__.py", "mrclutch/optimize/single.py",
    "mrclutch/optimize/pareto.py", "mrclutch/optimize/limits.py", "mrclutch/optimize/box.py",
    "mrclutch/optimize/worst_case.py", "mrclutch/members.py", "mrclutch/estimates.py",
    "mrclutch/design.py", "mrclutch/operating.py", "magnetics/thermal.py",
    "mrclutch/cli/formatting.py", "mrclutch/cli/commands/evaluate.py",
    "mrclutch/cli/commands/sweep.py", "mrclutch/cli/commands/optimize.py",
    "mrclutch/cli/commands/optimize_pareto.py", "mrclutch/cli/commands/report_command.py",
    "mrclutch/cli/commands/haptic.py", "mrclutch/haptic_run.py",
    "mrclutch/cli/plots/haptic.py", "mrclutch/impedance.py", "mrclutch/cli/plots/magnetics.py",
)  # fmt: skip
ROUND_TESTS = ("tests/mrclutch", "tests/magnetics/test_thermal.py",
               "tests/magnetics/test_thermal_hand.py")  # fmt: skip
#: Tests no run may count a kill by (deselected): the doc-figure check.
IGNORED = ["tests/test_doc_figures.py"]
#: Each run: its modules (None: every module of PHYSICS' packages), the tests the coverage
#: map is built from, and its output, coverage map and verdict table.
RUNS: dict[str, dict] = {
    "physics": {"modules": None, "tests": tuple(sorted({PACKAGES[p] for p in PHYSICS})),
                "out": "benchmarks/data/mutation.json",
                "coverage": "benchmarks/data/mutation.coverage", "verdicts": ""},
    "round": {"modules": ROUND_MODULES_D2D4F2C, "tests": ROUND_TESTS,
              "out": "benchmarks/data/mutation_round.json",
              "coverage": "benchmarks/data/mutation_round.coverage", "verdicts": "round"},
    "round2": {"modules": ROUND_MODULES, "tests": ROUND_TESTS, "select": "static",
               "out": "benchmarks/data/mutation_round2.json", "coverage": "",
               "verdicts": "round2"},
}  # fmt: skip
_RUN: dict = dict(RUNS["physics"])  # the run in hand (main sets it)

_BINOPS = {ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult,
           ast.Pow: ast.Mult, ast.FloorDiv: ast.Div, ast.Mod: ast.FloorDiv}  # fmt: skip
_CMPOPS = {ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt,
           ast.Eq: ast.NotEq, ast.NotEq: ast.Eq}  # fmt: skip


@dataclass
class Mutant:
    module: str  # path relative to the root
    index: int  # which candidate of the module (its order in the AST walk)
    line: int
    kind: str
    before: str
    after: str
    status: str = "pending"
    killed_by: str = ""
    seconds: float = 0.0


def _skip_zones(tree: ast.AST) -> set[int]:
    """ids of nodes never mutated: docstrings, annotations, raise statements, the arguments
    of check_* validation calls and of decorators, f-strings."""
    skip: set[int] = set()

    def mark(node: ast.AST | None) -> None:
        if node is not None:
            skip.update(id(n) for n in ast.walk(node))

    for node in ast.walk(tree):
        if isinstance(node, ast.Raise | ast.JoinedStr | ast.Assert):
            mark(node)
        elif isinstance(node, ast.AnnAssign):
            mark(node.annotation)
        elif isinstance(node, ast.arg):
            mark(node.annotation)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            mark(node.returns)
            for d in node.decorator_list:
                mark(d)
        elif isinstance(node, ast.Call):
            name = (
                node.func.attr
                if isinstance(node.func, ast.Attribute)
                else getattr(node.func, "id", "")
            )
            if name.startswith("check_") or name in {"ParameterError", "warn", "print"}:
                mark(node)
    return skip


def _candidates(tree: ast.AST) -> list[tuple[ast.AST, str]]:
    """Every mutable node of the module, in ast.walk order, with the kind of mutation."""
    skip = _skip_zones(tree)
    out: list[tuple[ast.AST, str]] = []
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            out.append((node, "binop"))
        elif isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _CMPOPS:
            out.append((node, "compare"))
        elif (isinstance(node, ast.Constant) and type(node.value) in (int, float)
              and not isinstance(node.value, bool)):  # fmt: skip
            out.append((node, "constant"))
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            out.append((node, "unary"))
        elif isinstance(node, ast.BoolOp):
            out.append((node, "boolop"))
    return out


def _mutate(node: ast.AST, kind: str) -> ast.AST:
    new = copy.deepcopy(node)
    if kind == "binop":
        new.op = _BINOPS[type(node.op)]()
    elif kind == "compare":
        new.ops = [_CMPOPS[type(node.ops[0])]()]
    elif kind == "constant":
        v = node.value
        new.value = (v + 1) if isinstance(v, int) else (v * 1.1 if v != 0 else 1e-3)
    elif kind == "unary":
        return new.operand
    elif kind == "boolop":
        new.op = ast.Or() if isinstance(node.op, ast.And) else ast.And()
    return new


class _Replace(ast.NodeTransformer):
    def __init__(self, target: ast.AST, replacement: ast.AST) -> None:
        self.target, self.replacement = target, replacement

    def generic_visit(self, node: ast.AST) -> ast.AST:
        if node is self.target:
            return self.replacement
        return super().generic_visit(node)


def modules() -> list[Path]:
    if _RUN["modules"] is not None:
        return [ROOT / m for m in _RUN["modules"]]
    mods: list[Path] = []
    for pkg in PHYSICS:
        mods += [p for p in sorted((ROOT / pkg).rglob("*.py")) if p.name != "__init__.py"]
    return mods


def _source(module: str) -> str:
    """The module's text in the tree the run mutates: the working tree, or HEAD's commit
    with ``--tree head`` (the working tree's own edits would not fit the committed tree)."""
    if _SOURCE["tree"] == "head":
        return subprocess.run(["git", "show", f"{_SOURCE['commit']}:{module}"], cwd=ROOT,
                              check=True, capture_output=True, text=True).stdout  # fmt: skip
    return (ROOT / module).read_text()


def enumerate_mutants() -> list[Mutant]:
    out: list[Mutant] = []
    for path in modules():
        src = _source(str(path.relative_to(ROOT)))
        tree = ast.parse(src)
        for i, (node, kind) in enumerate(_candidates(tree)):
            before = ast.get_source_segment(src, node) or ast.unparse(node)
            after = ast.unparse(_mutate(node, kind))
            if before.strip() == after.strip():
                continue
            out.append(Mutant(str(path.relative_to(ROOT)), i, node.lineno, kind,
                              before[:120], after[:120]))  # fmt: skip
    return out


def mutated_source(m: Mutant) -> str:
    src = _source(m.module)
    tree = ast.parse(src)
    node, kind = _candidates(tree)[m.index]
    new = _Replace(node, _mutate(node, kind)).visit(tree)
    return ast.unparse(ast.fix_missing_locations(new))


def _package_tests(module: str) -> str:
    for pkg, tests in PACKAGES.items():  # the first (most specific) package that holds it
        if module.startswith(pkg + "/"):
            return tests
    raise ValueError(module)


def _importers(tree_root: Path, module: str) -> list[str]:
    """Test files of the module's package that import it by its dotted name."""
    dotted = module[:-3].replace("/", ".")
    dotted = dotted.removesuffix(".__init__")
    tests = tree_root / _package_tests(module)
    return sorted(str(p.relative_to(tree_root)) for p in tests.rglob("test_*.py")
                  if dotted in p.read_text())  # fmt: skip


def build_coverage(tree: Path, out: Path) -> None:
    """Run the packages' tests once under pytest-cov, recording which test ran each line."""
    env = dict(os.environ, PYTHONPATH=str(tree), COVERAGE_FILE=str(out),
               NUMBA_CACHE_DIR=str(tree / ".numba"), OPENBLAS_NUM_THREADS="1")  # fmt: skip
    # the top folders, by path: a dotted module name makes coverage import its package
    # before pytest does (numpy then refuses to load twice)
    cov = [f"--cov={p}" for p in sorted({m.split("/")[0] for m in _RUN["modules"] or PHYSICS})]
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *cov,
                        "--cov-context=test", "--cov-report=", "-o",
                        "addopts=--benchmark-disable", *(f"--ignore={t}" for t in IGNORED),
                        *_RUN["tests"]],
                       cwd=tree, env=env, check=False, capture_output=True, text=True)  # fmt: skip
    # a test that fails unmutated cannot kill a mutant: recorded, and left out of every run
    failing = sorted({ln.split(" ")[1] for ln in r.stdout.splitlines() if ln.startswith("FAILED ")})
    if r.returncode not in (0, 1) or not out.exists():
        raise SystemExit(f"the unmutated suite did not run in {tree} (exit {r.returncode}):\n"
                         f"{r.stdout[-1500:]}\n{r.stderr[-1500:]}")  # fmt: skip
    out.with_suffix(".failing.json").write_text(json.dumps(failing, indent=1))
    print(r.stdout[-2000:], flush=True)


def covering_tests(coverage_file: Path) -> dict[tuple[str, int], list[str]]:
    """(module, line) → the test node ids that executed it (the map names files of the
    copy it ran in: each is read by its path below that copy's ``tree/``)."""
    from coverage import CoverageData

    data = CoverageData(str(coverage_file))
    data.read()
    out: dict[tuple[str, int], list[str]] = {}
    for fname in data.measured_files():
        if "/tree/" not in fname:
            continue
        rel = fname.split("/tree/", 1)[1]
        for line, contexts in data.contexts_by_lineno(fname).items():
            ids = sorted({c.split("|")[0] for c in contexts if c})
            if ids:
                out[(rel, line)] = ids
    return out


#: ``select = "static"`` (run round2): the test files a mutant runs are ranked by what they
#: name, not by a coverage map (a map of the round's tests took a whole session on the shared
#: 2-core machine). Left out of the ranking: files that take minutes and reach the round's
#: modules only through paths other files take faster (CAD, fidelity, fuzzing, help texts).
SLOW_FILES = ("test_fidelity", "test_batch_fuzz", "test_fuzz_", "test_view",
              "test_cli_geometry", "test_help_files", "test_cli_lazy", "test_output_faults",
              "test_sweep_scaleout", "test_sweep_interrupts", "test_memory_limit")  # fmt: skip
#: The CLI words that run a module of cli/ (a test that calls ``main(["evaluate", ...])``
#: runs formatting.py without naming it).
CLI_WORDS = {"mrclutch/cli/formatting.py": ("evaluate", "report"),
             "mrclutch/cli/commands/evaluate.py": ("evaluate",),
             "mrclutch/cli/commands/sweep.py": ("sweep",),
             "mrclutch/cli/commands/optimize.py": ("optimize",),
             "mrclutch/cli/commands/optimize_pareto.py": ("optimize",),
             "mrclutch/cli/commands/report_command.py": ("report",),
             "mrclutch/cli/commands/haptic.py": ("haptic", "compare"),
             "mrclutch/cli/plots/haptic.py": ("haptic", "compare", "--plot"),
             "mrclutch/cli/plots/magnetics.py": ("torque",)}  # fmt: skip
#: How many test files a mutant runs (the best ranked; ``--files``).
_K = [4]
#: round2: each test's seconds (setup + call, summed over its parameters) as the runs met
#: it, kept beside --out (``.durations.json``); a test cut by the budget is put at the
#: budget. A test not yet met counts 10 s.
_COSTS: dict[str, float] = {}
_COST_FILE: list[Path] = []
_PLUGIN = """import os


def pytest_runtest_logreport(report):
    if report.when in ("setup", "call"):
        with open(os.environ["MUTATION_DURATIONS"], "a") as f:
            f.write(f"{report.nodeid}\\t{report.duration}\\n")
"""


def _names(src: str) -> set[str]:
    """The module's top-level names (functions, classes, assigned names) of 4+ letters."""
    out: set[str] = set()
    for node in ast.parse(src).body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef | ast.AsyncFunctionDef):
            out.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            for t in node.targets if isinstance(node, ast.Assign) else [node.target]:
                if isinstance(t, ast.Name):
                    out.add(t.id)
    return {n for n in out if len(n.strip("_")) >= 4}


def _mentions(text: str, names: set[str]) -> int:
    return sum(len(re.findall(rf"\b{re.escape(n)}\b", text)) for n in names)


def _dotted(module: str) -> str:
    return module[:-3].replace("/", ".").removesuffix(".__init__")


def _imports_it(text: str, module: str) -> bool:
    """Whether a file's text imports the module: by dotted name, ``from pkg import stem``
    or (inside the package) ``from .stem import`` / ``from . import stem``."""
    pkg, _, stem = _dotted(module).rpartition(".")
    pattern = (rf"\b{re.escape(_dotted(module))}\b"
               rf"|from {re.escape(pkg)} import [^\n]*\b{stem}\b"
               rf"|from \.+{stem} import|from \.+ import [^\n]*\b{stem}\b")  # fmt: skip
    return bool(re.search(pattern, text))


def _test_functions(path: Path) -> list[tuple[str, str]]:
    """(node id suffix, text) of each test function of a file: its own source and that of
    the same file's fixtures it takes by name (a module fixture runs the command it
    checks)."""
    src = path.read_text()
    tree = ast.parse(src)
    defs: dict[str, str] = {}
    tests: list[tuple[str, ast.FunctionDef]] = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            defs[node.name] = ast.get_source_segment(src, node) or ""
            if node.name.startswith("test_"):
                tests.append((node.name, node))
        elif isinstance(node, ast.ClassDef) and node.name.startswith("Test"):
            for f in node.body:
                if isinstance(f, ast.FunctionDef) and f.name.startswith("test_"):
                    tests.append((f"{node.name}::{f.name}", f))
    out = []
    for name, fn in tests:
        text = ast.get_source_segment(src, fn) or ""
        text += "".join(defs.get(a.arg, "") for a in fn.args.args)
        out.append((name, text))
    return out


def ranked_tests(tree: Path, module: str, k: int | None = None) -> list[str]:
    """The tests a mutant of ``module`` runs, best first, at most k: each test function of
    the run's files (with its fixtures of the same file) scores 1 per mention of one of the
    module's top-level names, 3 per quoted CLI word of it (``CLI_WORDS``), 0.3 per mention
    of a name of a module of the package that imports it (the split modules are reached
    through pipeline, robust …) and 2 if its file imports the module; tests scoring 0 are
    not run. The rank is the score per cost: divided by 1 + (the test's seconds, as the
    run has met them, ``_COSTS``) / 10 s, so a cheap test that names the module comes
    before a slow one that names it as often."""
    if module not in _SCORES:
        _SCORES[module] = _scores(tree, module)
    ranked = [(-score / (1.0 + _COSTS.get(node, 10.0) / 10.0), fname, node)
              for score, fname, node in _SCORES[module]]  # fmt: skip
    return [node for *_, node in sorted(ranked)[: k or _K[0]]]


_SCORES: dict[str, list[tuple[float, str, str]]] = {}  # module → its tests' relevance


def _scores(tree: Path, module: str) -> list[tuple[float, str, str]]:
    """(relevance, file name, node id) of the tests of the run that name ``module``."""
    src = (tree / module).read_text()
    own, words = _names(src), set(CLI_WORDS.get(module, ()))
    up: set[str] = set()
    for pkg in {m.split("/")[0] for m in _RUN["modules"]}:
        for p in (tree / pkg).rglob("*.py"):
            rel = str(p.relative_to(tree))
            if rel != module and _imports_it(p.read_text(), module):
                up |= _names(p.read_text())
    up -= own | words
    files: list[Path] = []
    for t in _RUN["tests"]:
        files += [tree / t] if t.endswith(".py") else sorted((tree / t).rglob("test_*.py"))
    scored = []
    for f in files:
        if any(f.name.startswith(s) for s in SLOW_FILES) or str(f.relative_to(tree)) in IGNORED:
            continue
        bonus = 2 * _imports_it(f.read_text(), module)
        for name, text in _test_functions(f):
            score = (
                bonus
                + _mentions(text, own)
                + 3 * sum(text.count(f'"{w}"') for w in words)
                + 0.3 * _mentions(text, up)
            )
            if score > bonus:
                scored.append((score, f.name, f"{f.relative_to(tree)}::{name}"))
    return scored


_FAILING: list[str] = []  # tests that fail on the unmutated tree (build_coverage)
#: A line covered by this many tests or fewer also runs its package's importers: coverage
#: records a module-level line (a constant, a default) under the one test that first
#: imported it, and sees neither numba kernels nor CLI subprocesses.
_FEW = 2


def _learn_costs(durations: Path, targets: list[str], cut: float | None) -> None:
    """Add the seconds each test took (``_PLUGIN``'s lines) to ``_COSTS``; with ``cut``
    (the run hit its budget) the tests that did not report put at the budget."""
    if not plugin_costs_on():
        return
    took: dict[str, float] = {}
    for ln in durations.read_text().splitlines():
        node, _, sec = ln.partition("\t")
        base = node.split("[", 1)[0]
        took[base] = took.get(base, 0.0) + float(sec)
    for t in targets:
        if t in took:
            _COSTS[t] = took[t]
        elif cut is not None:
            _COSTS[t] = max(_COSTS.get(t, 0.0), cut)
    _COST_FILE[0].write_text(json.dumps(_COSTS, indent=0, sort_keys=True))


def plugin_costs_on() -> bool:
    return bool(_COST_FILE)


def _pytest(tree: Path, targets: list[str], timeout: float, module: str = "") -> tuple[str, str]:
    env = dict(os.environ, PYTHONPATH=str(tree), PYTHONDONTWRITEBYTECODE="1",
               NUMBA_CACHE_DIR=str(tree / ".numba"), OPENBLAS_NUM_THREADS="1")  # fmt: skip
    durations = tree.parent / "durations.txt"
    durations.write_text("")
    env["MUTATION_DURATIONS"] = str(durations)
    plugin = ["-p", "_mutation_durations"] if (tree / "_mutation_durations.py").exists() else []
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *plugin,
           "--no-header", "-o", "addopts=--benchmark-disable", *targets,
           *(f"--ignore={t}" for t in IGNORED), *(f"--deselect={t}" for t in _FAILING)]  # fmt: skip
    try:
        r = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True,
                           timeout=timeout)  # fmt: skip
    except subprocess.TimeoutExpired:
        _learn_costs(durations, targets, timeout)
        return "killed", "timeout"
    _learn_costs(durations, targets, None)
    if r.returncode == 0:
        return "survived", ""
    failed = [ln.split(" ")[1] for ln in r.stdout.splitlines() if ln.startswith("FAILED ")]
    if r.returncode == 1 and failed:
        return "killed", failed[0]
    errored = [ln.split(" ")[1] for ln in r.stdout.splitlines() if ln.startswith("ERROR ")]
    if r.returncode == 1 and errored:  # a fixture of the test raised on the mutant
        return "killed", "setup error: " + errored[0]
    if r.returncode in (1, 2) and module and f"{module}:" in r.stdout + r.stderr:
        # the mutated module itself raised while the tests were collected (at import)
        return "killed", f"collection error raised in {module}"
    # pytest itself did not run (exit 3–5: internal error, usage, no tests): no verdict,
    # not a kill; the output's tail says why
    return "error", f"exit {r.returncode}: " + " | ".join((r.stdout + r.stderr).splitlines()[-6:])


#: "work": copy the working tree; "head": the committed tree of HEAD (``git archive``), so a
#: run on a tree others are editing sees one consistent commit.
_SOURCE = {"tree": "work", "commit": "HEAD"}


def _worker_tree() -> Path:
    """A private copy of the whole tree (the tests read docs/, examples/, benchmarks/)."""
    tree = Path(tempfile.mkdtemp(prefix="mutation-")) / "tree"
    if _SOURCE["tree"] == "head":
        tree.mkdir()
        tar = subprocess.run(["git", "archive", _SOURCE["commit"]], cwd=ROOT, check=True,
                             capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(tree)], input=tar, check=True)
        if _RUN.get("select") == "static":
            (tree / "_mutation_durations.py").write_text(_PLUGIN)
        return tree
    shutil.copytree(ROOT, tree, ignore=shutil.ignore_patterns(".git", "__pycache__", "*.pyc"))
    return tree


_TREE: Path | None = None


def run_one(m: Mutant, timeout: float, tests: list[str], failing: list[str]) -> Mutant:
    """Run one mutant: ``tests`` (node ids covering its line) first, then the importers;
    ``failing``: tests that fail unmutated, deselected. With ``select = "static"`` (run
    round2): the ranked test files (``ranked_tests``) in one pytest call, ``-x``, within
    ``timeout``; a run cut by it is a survivor (``killed_by`` says "budget"), not a kill."""
    global _TREE
    _FAILING[:] = failing
    tests = [t for t in tests if t not in failing]
    if _TREE is None:
        _TREE = _worker_tree()
    target = _TREE / m.module
    original = target.read_text()
    t0 = time.perf_counter()
    try:
        target.write_text(mutated_source(m))
        if _RUN.get("select") == "static":
            files = ranked_tests(_TREE, m.module)
            status, by = _pytest(_TREE, files, timeout, m.module) if files else ("survived", "")
            if by == "timeout":
                status, by = "survived", f"budget: {timeout:.0f} s cut {len(files)} tests"
        else:
            status, by = _pytest(_TREE, tests, timeout, m.module) if tests else ("survived", "")
            if status == "survived" and len(tests) <= _FEW:
                files = _importers(_TREE, m.module) or [_package_tests(m.module)]
                status, by = _pytest(_TREE, files, timeout * 4, m.module)
    finally:
        target.write_text(original)
    m.status, m.killed_by, m.seconds = status, by, time.perf_counter() - t0
    return m


VERDICTS = ROOT / "benchmarks/data/mutation_verdicts.toml"


def verdicts() -> dict[str, dict[str, str]]:
    """Each survivor's verdict, by "module:index": ``equivalent`` (no input a user can give
    tells it from the original; ``why`` says so), ``speed`` (the same answers, only more or
    fewer solver iterations: benchmarks judge those, not tests), ``test`` (the test added
    for it) or ``rerun`` (round2: a run cut by the budget; ``test``, an existing test, fails
    on it when run alone). The physics run's verdicts are the file's top-level tables;
    another run's are under its own table (``[round."module:index"]``)."""
    import tomllib

    data = tomllib.loads(VERDICTS.read_text()) if VERDICTS.exists() else {}
    return data.get(_RUN["verdicts"], {}) if _RUN["verdicts"] else data


def summary(mutants: list[Mutant]) -> dict[str, float]:
    """Counts of a run, with the survivors' verdicts: survival of the non-equivalent
    mutants in the run (before their tests were written) and after."""
    done = [m for m in mutants if m.status in ("killed", "survived")]  # errors: no verdict
    ver = verdicts()
    surv = [m for m in done if m.status == "survived"]

    def of(kind: str) -> list[Mutant]:
        return [m for m in surv if ver.get(f"{m.module}:{m.index}", {}).get("verdict") == kind]

    eq, speed, tested = of("equivalent"), of("speed"), of("test")
    rerun = of("rerun")  # cut by the budget; an existing test kills it, run alone after
    non_eq = len(done) - len(eq) - len(speed)  # mutants that change an answer
    return {
        "mutants": len(done),
        "killed": len(done) - len(surv),
        "survived": len(surv),
        "cut_by_budget": sum(m.killed_by.startswith("budget") for m in surv),
        "equivalent": len(eq),
        "speed_only": len(speed),
        "killed_on_rerun": len(rerun),
        "given_a_test": len(tested),
        "unexplained": len(surv) - len(eq) - len(speed) - len(tested) - len(rerun),
        "survival_non_equivalent_pct": 100.0 * (len(surv) - len(eq) - len(speed)) / max(non_eq, 1),
        "survival_after_tests_pct": 100.0
        * (len(surv) - len(eq) - len(speed) - len(tested) - len(rerun))
        / max(non_eq, 1),
    }


def report(mutants: list[Mutant]) -> str:
    done = [m for m in mutants if m.status in ("killed", "survived")]
    lines = ["| package | mutants | killed | survived |", "|---|---:|---:|---:|"]
    groups = PHYSICS if _RUN["modules"] is None else sorted({m.module for m in done})
    for pkg in groups:
        mine = [m for m in done if m.module == pkg or m.module.startswith(pkg + "/")]
        killed = sum(m.status == "killed" for m in mine)
        name = pkg if pkg.endswith(".py") else pkg + "/"
        lines.append(f"| {name} | {len(mine)} | {killed} | {len(mine) - killed} |")
    killed = sum(m.status == "killed" for m in done)
    lines.append(f"| all | {len(done)} | {killed} | {len(done) - killed} |")
    lines += ["", "| survivor | line | before → after | verdict |", "|---|---:|---|---|"]
    ver = verdicts()
    for m in sorted(done, key=lambda m: (m.module, m.line)):
        if m.status == "survived":
            v = ver.get(f"{m.module}:{m.index}", {})
            kind = v.get("verdict")
            say = (f"{kind}: {v.get('why', '')}" if kind in ("equivalent", "speed")
                   else f"test: `{v.get('test', '')}`" if kind == "test"
                   else f"killed on a re-run by `{v.get('test', '')}`" if kind == "rerun"
                   else "**unexplained**")  # fmt: skip
            if m.killed_by.startswith("budget"):
                say = f"(cut at {m.killed_by.split()[1]} s) {say}"
            before, after = (x.replace("|", "\\|") for x in (m.before, m.after))
            lines.append(f"| {m.module} | {m.line} | `{before}` → `{after}` | {say} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--run", choices=sorted(RUNS), default="physics",
                    help="physics: geometry/, magnetics/, mrclutch/haptics/ (the default); "
                    "round: the last two rounds' modules and the CLI's formatting and "
                    "plots, without the doc-figure tests, as at d2d4f2c; round2: the "
                    "same code where it is today, each mutant's test files ranked "
                    "statically")  # fmt: skip
    ap.add_argument(
        "--tree",
        choices=("work", "head"),
        default="work",
        help="run on a copy of the working tree (default) or of HEAD's commit",
    )
    ap.add_argument("--without", nargs="*", default=[], metavar="TEST_FILE",
                    help="test files left out of the run too (e.g. tests just added, for the "
                    "survival before them)")  # fmt: skip
    ap.add_argument("--sample", type=int, default=200)
    ap.add_argument("--seed", type=int, default=35)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=240.0, help="s per stage-1 run")
    ap.add_argument("--out", type=Path, default=None, help="default: the run's")
    ap.add_argument("--files", type=int, default=5, help="round2: tests a mutant runs")
    ap.add_argument("--list", action="store_true", help="print the sample, run nothing")
    ap.add_argument("--report", action="store_true", help="print the table of --out")
    ap.add_argument("--summary", action="store_true", help="print --out's counts as JSON")
    ap.add_argument("--only", nargs="*", help="re-run these 'module:index' mutants only")
    ap.add_argument("--map-tests", nargs="*", default=None, metavar="TEST",
                    help="the tests the coverage map is built from (default: the run's); a "
                    "mutant's second stage still runs every importer of its package")  # fmt: skip
    ap.add_argument(
        "--coverage",
        type=Path,
        default=None,
        help="per-test coverage map (built first if missing; default: the run's)",
    )
    args = ap.parse_args(argv)
    _RUN.clear()
    _RUN.update(RUNS[args.run])
    args.out = args.out or ROOT / _RUN["out"]
    args.coverage = args.coverage or ROOT / (_RUN["coverage"] or os.devnull)
    IGNORED.extend(args.without)
    if args.map_tests:
        _RUN["tests"] = tuple(args.map_tests)
    if args.report or args.summary:
        got = [Mutant(**d) for d in json.loads(args.out.read_text())["mutants"]]
        print(json.dumps(summary(got)) if args.summary else report(got))
        return 0
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                            capture_output=True, check=False).stdout.strip()  # fmt: skip
    _SOURCE.update(tree=args.tree, commit=commit or "HEAD")
    everything = enumerate_mutants()
    sample = random.Random(args.seed).sample(everything, min(args.sample, len(everything)))
    if args.only:
        keys = set(args.only)
        sample = [m for m in everything if f"{m.module}:{m.index}" in keys]
    if args.list:
        for m in sample:
            print(f"{m.module}:{m.line} [{m.kind}] {m.before!r} -> {m.after!r}")
        print(f"{len(sample)} of {len(everything)} candidate mutants")
        return 0
    t0 = time.perf_counter()
    if args.tree == "work":
        commit += " + working tree"
    _K[0] = args.files
    if _RUN.get("select") == "static":
        _COST_FILE[:] = [args.out.with_suffix(".durations.json")]
        if _COST_FILE[0].exists():
            _COSTS.update(json.loads(_COST_FILE[0].read_text()))
    if _RUN.get("select") == "static":  # no map: each mutant ranks its own test files
        args.coverage = Path(os.devnull)
    elif not args.coverage.exists():  # the unmutated suite once: the baseline and the map
        base = _worker_tree()
        build_coverage(base, args.coverage)
        shutil.rmtree(base.parent)
        print(f"coverage map in {time.perf_counter() - t0:.0f} s", flush=True)
    static = _RUN.get("select") == "static"
    cover = {} if static else covering_tests(args.coverage)
    failing = [] if static else json.loads(args.coverage.with_suffix(".failing.json").read_text())
    if failing:
        print(f"{len(failing)} tests fail unmutated, left out: {failing}", flush=True)
    done: list[Mutant] = []
    if args.out.exists():  # resume: the same tree and seed give the same sample
        done = [Mutant(**d) for d in json.loads(args.out.read_text())["mutants"]]
        seen = {(m.module, m.index) for m in done}
        sample = [m for m in sample if (m.module, m.index) not in seen]
    with cf.ProcessPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(run_one, m, args.timeout, cover.get((m.module, m.line), []),
                               failing) for m in sample]  # fmt: skip
        total = len(done) + len(sample)
        for fut in cf.as_completed(futures):
            m = fut.result()
            done.append(m)
            print(f"[{len(done)}/{total}] {m.status:8s} {m.module}:{m.line} {m.before!r} -> "
                  f"{m.after!r} ({m.seconds:.0f} s) {m.killed_by}", flush=True)  # fmt: skip
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(
                json.dumps(
                    {
                        "run": args.run,
                        "commit": commit,
                        "ignored": list(IGNORED),
                        "candidates": len(everything),
                        "seed": args.seed,
                        "mutants": [asdict(x) for x in done],
                    },
                    indent=1,
                )
            )
    print(f"\n{len(done)} mutants in {time.perf_counter() - t0:.0f} s\n")
    print(report(done))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
