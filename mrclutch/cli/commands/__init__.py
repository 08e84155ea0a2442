"""CLI command modules. Each exposes ``register(subparsers)`` and imports heavy
libraries (build123d, pyvista, scikit-fem, matplotlib) only inside its handlers."""
