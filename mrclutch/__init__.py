"""mrclutch: MR drum clutch design, from the drums to what the hand feels.

Light to import: nothing here pulls in build123d, trimesh or pyvista. The version is the
installed distribution's (pyproject.toml is its one source).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("mrclutch")
except PackageNotFoundError:  # pragma: no cover - run from a source tree without install
    __version__ = "0+unknown"
