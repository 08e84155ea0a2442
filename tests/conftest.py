"""Fixtures shared across test modules."""

from __future__ import annotations

import pytest

from mrclutch import docs_figures


@pytest.fixture(scope="session")
def figures_runner(tmp_path_factory):
    """One docs_figures.Runner for the session: a command that the docs' figures and the
    help meta-test both run (``mrclutch fidelity``) runs once."""
    return docs_figures.Runner(tmp_path_factory.mktemp("figures"))
