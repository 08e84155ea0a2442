"""3-D view of a clutch: parts coloured by material, cut in half to show the drums and gaps.

pyvista (VTK) and build123d are imported inside the functions. Off screen, with no X
display, VTK renders through EGL (Mesa's ``libegl1`` + ``libgl1-mesa-dri`` on Debian/Ubuntu;
see docs/geometry.md); ``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` is set for that
case so VTK does not first try (and warn about) a missing X server.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from geometry.atomic import atomic_path
from geometry.cad import MATERIAL_COLOURS, material_solids, tessellate
from geometry.params import DrumClutch
from geometry.section import build_section
from geometry.validation import ParameterError, check_positive

#: Default window of the view and screenshots (pixels).
WINDOW_SIZE = (1024, 768)
#: Opacity of the MR fluid so the drums in it stay visible.
FLUID_OPACITY = 0.55


def has_display() -> bool:
    """True where an interactive window can open (X11/Wayland display, or not Linux)."""
    if os.name != "posix" or "darwin" in os.uname().sysname.lower():
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _prepare_offscreen() -> None:
    if not has_display():
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def view_tolerance(clutch: DrumClutch, window_size: tuple[int, int] = WINDOW_SIZE) -> float:
    """Chord height [m] the view needs: one pixel when the whole clutch fills the window
    (its larger envelope side over the window's smaller side). A finer tessellation adds
    triangles no one can see; a coarser one shows facets."""
    if min(window_size) < 1:
        raise ParameterError(f"window_size = {window_size!r}: need positive pixel counts")
    return max(build_section(clutch).envelope) / min(window_size)


def scene_meshes(
    clutch: DrumClutch, tolerance: float | None = None, cut: bool = True
) -> list[tuple[str, str, Any]]:
    """(part, material, pyvista.PolyData in mm) for every solid; half of each if ``cut``.
    ``tolerance`` [m] defaults to :func:`view_tolerance` of the default window."""
    import pyvista as pv

    tolerance = view_tolerance(clutch) if tolerance is None else tolerance
    check_positive("tolerance", tolerance, " m")
    out = []
    for (part, material), shape in material_solids(
        clutch, angle_deg=180.0 if cut else 360.0
    ).items():
        v, f = tessellate(shape, tolerance * 1e3, 0.3)
        faces = np.hstack([np.full((len(f), 1), 3), f]).ravel()
        out.append((part, material, pv.PolyData(v, faces)))
    return out


def build_plotter(
    clutch: DrumClutch,
    *,
    off_screen: bool,
    tolerance: float | None = None,
    window_size: tuple[int, int] = WINDOW_SIZE,
    cut: bool = True,
) -> Any:
    """A pyvista Plotter with the clutch, looking at the cut face from slightly above;
    tessellated to ``tolerance`` [m], by default one pixel of ``window_size``."""
    tolerance = view_tolerance(clutch, window_size) if tolerance is None else tolerance
    if off_screen:
        _prepare_offscreen()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=off_screen, window_size=list(window_size))
    plotter.set_background("white")
    for part, material, mesh in scene_meshes(clutch, tolerance, cut):
        plotter.add_mesh(
            mesh,
            color=MATERIAL_COLOURS[material],
            opacity=FLUID_OPACITY if part == "fluid" else 1.0,
            smooth_shading=False,
            label=f"{part} ({material})",
        )
    plotter.add_legend(bcolor="white", face="rectangle", size=(0.28, 0.28))
    # look along +y at the x–z cut plane, a little from above and from the shaft side
    plotter.camera_position = "xz"
    plotter.camera.azimuth = -25
    plotter.camera.elevation = 20
    plotter.reset_camera()
    return plotter


def screenshot(
    clutch: DrumClutch,
    path: str | os.PathLike[str],
    *,
    tolerance: float | None = None,
    window_size: tuple[int, int] = WINDOW_SIZE,
) -> Path:
    """Render off screen (no display needed) into a PNG at ``path``, atomically."""
    dest = Path(path)
    if dest.suffix.lower() != ".png":
        raise ParameterError(f"--screenshot {dest}: must end in .png")
    plotter = build_plotter(clutch, off_screen=True, tolerance=tolerance, window_size=window_size)
    try:
        with atomic_path(dest) as tmp:
            plotter.screenshot(str(tmp))
    finally:
        plotter.close()
    return dest


def show(clutch: DrumClutch, *, tolerance: float | None = None) -> None:
    """Open an interactive window (needs a display)."""
    if not has_display():
        raise ParameterError("no display for an interactive window; use --screenshot FILE.png")
    build_plotter(clutch, off_screen=False, tolerance=tolerance).show()
