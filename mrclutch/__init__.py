"""mrclutch: MR drum clutch design, from the drums to what the hand feels.

Light to import: nothing here pulls in numpy, build123d, trimesh or pyvista, and the
version is read only when asked for (``mrclutch.__version__``: the installed
distribution's, pyproject.toml is its one source; importlib.metadata costs ~10–80 ms, more
than the rest of ``mrclutch --help``).
"""

import importlib


def __getattr__(name: str) -> str:
    if name != "__version__":
        raise AttributeError(f"module 'mrclutch' has no attribute {name!r}")
    metadata = importlib.import_module("importlib.metadata")
    try:
        return str(metadata.version("mrclutch"))
    except metadata.PackageNotFoundError:  # pragma: no cover - a source tree, not installed
        return "0+unknown"
