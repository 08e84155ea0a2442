"""The layers of docs/architecture.md, read from the source (AST), lazy imports included.

    geometry  ←  magnetics  ←  mrclutch.haptics  ←  mrclutch (application)  ←  mrclutch.cli

A module imports only from its own layer or a lower one; the module graph has no cycle;
imports inside functions are only for the heavy third-party packages below, so every
project dependency is visible at the top of its module.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from mrclutch.docs_architecture import LAYER_NAMES, layer_of, modules

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("geometry", "magnetics", "mrclutch")
LAYERS = LAYER_NAMES
#: Third-party packages a function may import lazily, and why.
LAZY_OK = {
    "build123d": "≈ 6 s to import (OpenCascade)",
    "OCP": "OpenCascade bindings, as build123d",
    "skfem": "FEM only on the reference path",
    "pyvista": "VTK, only for the 3-D view",
    "vtk": "as pyvista",
    "vtkmodules": "VTK's own modules: the report's screenshot without pyvista's plotting layer",
    "trimesh": "only for mesh inertia",
    "matplotlib": "only where a figure is drawn",
    "scipy": "≈ 0.3–0.4 s; the CLI and the analytic commands start without it",
    "tqdm": "progress bars only on long work",
    "dask": "only when a sweep runs on a Dask cluster",
    "distributed": "≈ 1 s; only when a sweep runs on a Dask cluster",
    "pyarrow": "≈ 0.3 s; only when a sweep writes or reads Parquet",
    "numba": "≈ 0.3 s and its compiled kernels; only when the network is solved",
    "pymoo": "≈ 0.5 s; only where optimize searches for a Pareto set",
    "ezdxf": "≈ 0.5 s; only when a DXF of the section is written",
    "tomllib": "stdlib, pure Python: ~18M instructions, 4 % of a preset's analytic inertia; "
    "only where a TOML text is parsed (a preset's materials come from their cache)",
    "subprocess": "stdlib, ~6 ms CPU (with selectors, signal) of every evaluate and torque, "
    "which load the network's compiled kernels but start no process; only where the kernels "
    "are compiled beside (magnetics.network.compiled)",
    "numpy.polynomial": "~4 ms CPU of haptic, which never multiplies a polynomial; only where "
    "the crossings of a zero-delay loop are its roots (haptics.limits, haptics.zwidth)",
    "html": "stdlib, ~2 ms CPU (html.entities' table) of evaluate; only where HTML is written "
    "(the report's duty and feel sections: duty_format.duty_html, feel_format.feel_html)",
}


#: The command line's layer: it may load a project module by name when a command runs
#: (mrclutch.cli.main's command table, a design's branch of haptic and compare), so that
#: parsing and the catalogue's answers start without the physics; what it loads is still
#: an import, held to the layers and the cycle check (``_loaded_by_name``).
CLI = LAYER_NAMES.index("mrclutch.cli")

#: The modules and their layers as docs/architecture.md's generated map reads them (one
#: definition of what a module and a layer are, for the map and for this test).
MODULES = modules()
layer = layer_of


def _package_of(module: str) -> str:
    is_pkg = MODULES[module].name == "__init__.py"
    return module if is_pkg else module.rpartition(".")[0]


def imports(module: str, source: str | None = None) -> list[tuple[str, int, bool]]:
    """(imported module, line, inside a function) for every project import in ``module``
    and every import inside its functions."""
    tree = ast.parse(MODULES[module].read_text() if source is None else source)
    lazy_lines = {
        s.lineno
        for n in ast.walk(tree)
        if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)
        for s in ast.walk(n)
        if isinstance(s, ast.Import | ast.ImportFrom)
    }
    out = []
    for name, line in _loaded_by_name(tree):  # importlib.import_module("pkg.mod")
        out.append((name, line, line in lazy_lines or _in_function(tree, line)))
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative import
                pkg = _package_of(module).split(".")
                base = ".".join(pkg[: len(pkg) - node.level + 1] + ([base] if base else []))
            # `from pkg import mod` imports the module pkg.mod
            names = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base
                     for a in node.names]  # fmt: skip
        for name in names:
            if name.split(".")[0] in PACKAGES:
                while name not in MODULES:  # an attribute path: its module
                    name = name.rpartition(".")[0]
                out.append((name, node.lineno, node.lineno in lazy_lines))
            elif node.lineno in lazy_lines:
                out.append((name, node.lineno, True))
    return out


def _loaded_by_name(tree: ast.Module) -> list[tuple[str, int]]:
    """(project module, line) of every ``importlib.import_module(NAME)`` whose NAME is a
    string, a module-level constant holding one, or an item of a module-level dict of them
    (``import_module(EXPORTS[name])``: every module the dict names): an import all the
    same, which the layers, the lazy-import rule and the cycle check must see."""
    consts: dict[str, list[str]] = {}
    for n in tree.body:
        targets = (n.targets if isinstance(n, ast.Assign)
                   else [n.target] if isinstance(n, ast.AnnAssign) else [])  # fmt: skip
        value = n.value if isinstance(n, ast.Assign | ast.AnnAssign) else None
        names = ([value] if isinstance(value, ast.Constant)
                 else value.values if isinstance(value, ast.Dict) else [])  # fmt: skip
        strings = [
            v.value for v in names if isinstance(v, ast.Constant) and isinstance(v.value, str)
        ]
        for t in targets:
            if isinstance(t, ast.Name) and strings:
                consts[t.id] = strings
    found = []
    for n in ast.walk(tree):
        if not (isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
                and n.func.attr == "import_module" and n.args):  # fmt: skip
            continue
        arg = n.args[0]
        if isinstance(arg, ast.Subscript) and isinstance(arg.value, ast.Name):
            arg = arg.value  # TABLE[key]: any module of the table
        names = ([arg.value] if isinstance(arg, ast.Constant) and isinstance(arg.value, str)
                 else consts.get(arg.id, []) if isinstance(arg, ast.Name) else [])  # fmt: skip
        found += [(name, n.lineno) for name in names
                  if name.split(".")[0] in PACKAGES and name in MODULES]  # fmt: skip
    return found


def _in_function(tree: ast.Module, line: int) -> bool:
    return any(
        isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)
        and n.lineno <= line <= (n.end_lineno or n.lineno)
        for n in ast.walk(tree)
    )


def test_the_package_tree_is_found() -> None:
    assert {"geometry.regions", "magnetics.circuit", "mrclutch.haptics.model",
            "mrclutch.pipeline", "mrclutch.cli.main"} <= set(MODULES)  # fmt: skip


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_go_down_the_layers_only(module: str) -> None:
    up = [
        f"{module}:{line} imports {target} ({LAYERS[layer(target)]} above {LAYERS[layer(module)]})"
        for target, line, _ in imports(module)
        if target.split(".")[0] in PACKAGES and layer(target) > layer(module)
    ]
    assert not up, "\n".join(up)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_functions_import_only_heavy_third_party_packages(module: str) -> None:
    bad = [
        f"{module}:{line} imports {target} inside a function"
        for target, line, lazy in imports(module)
        if lazy
        and not _lazy_ok(target)
        and not (layer(module) == CLI and target.split(".")[0] in PACKAGES)
        and not _own_export(module, target)
    ]
    assert not bad, "\n".join(bad)


def _lazy_ok(target: str) -> bool:
    """A third-party module LAZY_OK names, or a submodule of one it names (``numpy.polynomial``
    is allowed; ``numpy`` itself is not)."""
    return any(target == k or target.startswith(k + ".") for k in LAZY_OK)


def _own_export(module: str, target: str) -> bool:
    """A package's ``__init__`` re-exporting a name of one of its own modules on first use
    (PEP 562 ``__getattr__`` over a table, as geometry's ``EXPORTS``): the table at the top
    of the package names every module, and importing one light module of the package
    does not load the others."""
    return MODULES[module].name == "__init__.py" and target.startswith(module + ".")


def find_cycle(graph: dict[str, list[str]]) -> list[str] | None:
    """One cycle of the directed graph (as a closed path), or None."""
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for t in graph[m]:
            if state.get(t) == 1:
                return [*path[path.index(t) :], t]
            if t not in state and (c := visit(t)):
                return c
        path.pop()
        state[m] = 2
        return None

    for m in graph:
        if m not in state and (c := visit(m)):
            return c
    return None


def test_the_module_graph_has_no_cycle() -> None:
    graph = {m: sorted({t for t, _, _ in imports(m) if t in MODULES and t != m}) for m in MODULES}
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " → ".join(cycle or [])


def test_a_planted_lazy_upward_import_and_a_cycle_are_caught() -> None:
    """The checks can fail: a lazy import of the CLI from the physics is seen, as upward
    and as lazy, and a two-module cycle is found."""
    src = (
        "import numpy as np\n\ndef f():\n    from mrclutch.cli.main import main\n    return main\n"
    )
    found = imports("magnetics.torque", src)
    assert found == [("mrclutch.cli.main", 4, True)]
    assert layer("mrclutch.cli.main") > layer("magnetics.torque")
    by_name = (
        "import importlib\n\n_MAIN = 'mrclutch.cli.main'\n\n\ndef f():\n"
        "    return importlib.import_module(_MAIN), importlib.import_module('geometry.atomic')\n"
    )
    assert imports("magnetics.torque", by_name) == [
        ("mrclutch.cli.main", 7, True),
        ("geometry.atomic", 7, True),
    ]
    by_table = (
        "import importlib\n\nEXPORTS: dict[str, str] = {'a': 'mrclutch.cli.main', 'b': 'x.y'}\n"
        "\n\ndef __getattr__(name):\n    return importlib.import_module(EXPORTS[name])\n"
    )
    assert imports("magnetics.torque", by_table) == [("mrclutch.cli.main", 7, True)]
    assert not _own_export("magnetics.torque", "magnetics.torque.x")  # a module, not a package
    assert _own_export("geometry", "geometry.params") and not _own_export("geometry", "magnetics")
    assert {(t, lazy) for t, _, lazy in imports("geometry")} == {  # its table is seen
        ("geometry.params", True),
        ("geometry.section", True),
        ("geometry.validation", True),
    }
    assert find_cycle({"a": ["b"], "b": ["c"], "c": ["a"]}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": ["b"], "b": [], "c": ["a"]}) is None
