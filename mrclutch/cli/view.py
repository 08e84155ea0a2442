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

from geometry.params import DrumClutch
from geometry.validation import ParameterError
from mrclutch.cli.plots import save_png
from mrclutch.solids import legend_entries, material_colour, view_tolerance, view_triangles

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


def scene_meshes(
    clutch: DrumClutch, tolerance: float | None = None, cut: bool = True
) -> list[tuple[str, str, Any]]:
    """(part, material, pyvista.PolyData in mm) for every solid; half of each if ``cut``.
    ``tolerance`` [m] defaults to :func:`mrclutch.solids.view_tolerance` of the default
    window."""
    import pyvista as pv

    tolerance = view_tolerance(clutch, WINDOW_SIZE) if tolerance is None else tolerance
    return [(part, material, pv.PolyData(v, faces))
            for part, material, v, faces in view_triangles(clutch, tolerance, cut)]  # fmt: skip


def build_plotter(
    clutch: DrumClutch,
    *,
    off_screen: bool,
    tolerance: float | None = None,
    window_size: tuple[int, int] = WINDOW_SIZE,
    cut: bool = True,
    legend: bool = True,
) -> Any:
    """A pyvista Plotter with the clutch, looking at the cut face from slightly above;
    tessellated to ``tolerance`` [m], by default one pixel of ``window_size``. The
    screenshot draws its legend beside the model instead (``legend=False`` here)."""
    tolerance = view_tolerance(clutch, window_size) if tolerance is None else tolerance
    if off_screen:
        _prepare_offscreen()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=off_screen, window_size=list(window_size))
    plotter.set_background("white")
    for part, material, mesh in scene_meshes(clutch, tolerance, cut):
        plotter.add_mesh(
            mesh,
            color=material_colour(material),
            opacity=FLUID_OPACITY if part == "fluid" else 1.0,
            smooth_shading=False,
            label=f"{part} ({material})",
        )
    if legend:
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
    """Render off screen (no display needed) into a PNG of ``window_size`` pixels at
    ``path``, atomically: the model on the left, its legend in a panel on the right (never
    over the model; each swatch outlined so the pale stainless reads on white), text at
    least 2.1 % of the width tall (≥ 9 px when the image is shown 450 px wide)."""
    dest = Path(path)
    if dest.suffix.lower() != ".png":
        raise ParameterError(f"--screenshot {dest}: must end in .png")
    w, h = window_size
    model_w = max(1, round(w * LEGEND_SPLIT))
    plotter = build_plotter(clutch, off_screen=True, tolerance=tolerance,
                            window_size=(model_w, h), legend=False)  # fmt: skip
    try:
        img = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    _compose(img, legend_entries(clutch), (w, h), dest)
    return dest


#: Share of the screenshot's width given to the model; the legend takes the rest.
LEGEND_SPLIT = 0.66


def _compose(img: Any, labels: list, size: tuple[int, int], dest: Path) -> None:
    """The rendered model and a legend panel beside it, as one PNG of ``size`` pixels."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    w, h = size
    dpi = 100
    fig = plt.figure(figsize=(w / dpi, h / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, LEGEND_SPLIT, 1))
    ax.imshow(img)
    ax.set_axis_off()
    side = fig.add_axes((LEGEND_SPLIT, 0, 1 - LEGEND_SPLIT, 1))
    side.set_axis_off()
    font_pt = max(6.0, 0.021 * w * 72 / dpi)  # 2.1 % of the width, in points
    side.legend(handles=[Patch(facecolor=c, edgecolor="0.15", lw=1.0, label=t)
                         for t, c in labels], loc="center left", fontsize=font_pt,
                frameon=False, labelcolor="0.1", handlelength=1.4)  # fmt: skip
    save_png(fig, dest, dpi=dpi)
    plt.close(fig)


def show(clutch: DrumClutch, *, tolerance: float | None = None) -> None:
    """Open an interactive window (needs a display)."""
    if not has_display():
        raise ParameterError("no display for an interactive window; use --screenshot FILE.png")
    build_plotter(clutch, off_screen=False, tolerance=tolerance).show()
