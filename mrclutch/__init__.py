"""mrclutch: MR drum clutch design, from the drums to what the hand feels.

Light to import: nothing here pulls in build123d, trimesh or pyvista.
"""

__version__ = "0.1.0"
