"""Fixtures shared by the tests of the application layer."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

FUZZ = Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_cli.py"


@pytest.fixture(scope="module")
def fuzz():
    """benchmarks/fuzz_cli.py loaded as a module (it is a script, not a package module),
    once a test module; removed from sys.modules after it."""
    spec = importlib.util.spec_from_file_location("fuzz_cli", FUZZ)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_cli"] = mod
    spec.loader.exec_module(mod)
    yield mod
    sys.modules.pop("fuzz_cli", None)
