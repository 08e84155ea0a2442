"""The CLI is thin (issue 43): a module under ``mrclutch/cli/`` parses arguments, calls the
application layer (``mrclutch.*``) and formats; it reaches ``geometry``, ``magnetics`` and
``mrclutch.haptics`` only through the application layer's public functions, and it does no
numpy-level computation (no ``import numpy`` outside the plotting and JSON modules below).

Read from the source (AST) with the import graph of ``tests/test_architecture.py``, lazy
imports included. Two lists, each entry with its reason: the few lower-layer modules any CLI
module may use (validation, the output layer, plain data), and the CLI modules that may
import numpy to draw or write arrays. No CLI module is exempt (issue 43 item 1: the last
ones moved their computation to mrclutch.torque_curves, haptic_run, handoff, inertia,
solids and impedance).
"""

from __future__ import annotations

import ast

import pytest
from test_architecture import MODULES, imports

CLI = sorted(m for m in MODULES if m.startswith("mrclutch.cli"))
#: The layers below the application that the CLI must not import directly.
BELOW = ("geometry", "magnetics", "mrclutch.haptics")

#: Lower-layer modules any CLI module may import: no physics, nothing decided.
ALLOWED = {
    "geometry.validation": "argument checks (check_choice, check_int) and ParameterError: "
    "parsing, the one error type bad input ends in",
    "geometry.atomic": "the one output layer (temporary file, fsync, rename): every file the "
    "tool writes goes through it",
    "geometry.params": "DrumClutch, the design's dimensions: a frozen dataclass (data)",
}

#: CLI modules that may import numpy, and why: arrays drawn or written, never computed.
NUMPY_OK = {
    "mrclutch.cli.jsonio": "numpy scalars and arrays to JSON (to_jsonable)",
    "mrclutch.cli.plots": "the figures draw arrays (every module of the package)",
}


def below(module: str, source: str | None = None) -> set[str]:
    """The modules of the layers below the application that ``module`` imports."""
    return {
        t
        for t, _, _ in imports(module, source)
        if any(t == b or t.startswith(b + ".") for b in BELOW)
    }


def imports_numpy(module: str, source: str | None = None) -> list[int]:
    """The lines where ``module`` imports numpy (or a numpy submodule), lazily or not."""
    tree = ast.parse(MODULES[module].read_text() if source is None else source)
    lines = []
    for n in ast.walk(tree):
        if isinstance(n, ast.Import):
            names = [a.name for a in n.names]
        elif isinstance(n, ast.ImportFrom) and not n.level:
            names = [n.module or ""]
        else:
            continue
        if any(name.split(".")[0] == "numpy" for name in names):
            lines.append(n.lineno)
    return lines


def _numpy_ok(module: str) -> bool:
    return any(module == m or module.startswith(m + ".") for m in NUMPY_OK)


def test_the_cli_modules_are_found() -> None:
    assert {"mrclutch.cli.main", "mrclutch.cli.formatting", "mrclutch.cli.commands.evaluate",
            "mrclutch.cli.commands.optimize"} <= set(CLI)  # fmt: skip


@pytest.mark.parametrize("module", CLI)
def test_cli_reaches_the_lower_layers_only_through_the_application(module: str) -> None:
    extra = below(module) - set(ALLOWED)
    assert not extra, (
        f"{module} imports {sorted(extra)} directly: call the application layer "
        "(mrclutch.*) instead, and move the computation or decision there"
    )


@pytest.mark.parametrize("module", CLI)
def test_cli_does_no_numpy_computation(module: str) -> None:
    lines = imports_numpy(module)
    assert _numpy_ok(module) or not lines, (
        f"{module}:{lines} imports numpy: compute in the application layer and format its "
        "result here"
    )


def test_the_lists_name_real_modules_and_stay_small() -> None:
    """Every entry names a module that exists; the allow-list stays tiny."""
    listed = {m for m in NUMPY_OK if m in MODULES}
    assert listed <= set(CLI)
    assert set(ALLOWED) <= set(MODULES)
    assert len(ALLOWED) <= 3


def test_a_planted_violation_is_caught() -> None:
    """A command module that imports the torque kernel and numpy fails both checks; the
    same module importing only the application layer and the output layer passes."""
    module = "mrclutch.cli.commands.evaluate"
    bad = (
        "import numpy as np\n"
        "from magnetics.torque import torque_curve\n"
        "from mrclutch.haptics.model import Plant\n"
        "def f():\n"
        "    from geometry.section import build_section\n"
    )
    assert below(module, bad) == {"magnetics.torque", "mrclutch.haptics.model",
                                  "geometry.section"}  # fmt: skip
    assert imports_numpy(module, bad) == [1]
    good = "from geometry.atomic import atomic_path\nfrom mrclutch.verdict import judge\n"
    assert below(module, good) <= set(ALLOWED) and imports_numpy(module, good) == []
