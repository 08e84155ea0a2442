"""3-D view of a clutch: parts coloured by material, cut in half to show the drums and gaps.

VTK, pyvista and build123d are imported inside the functions. The interactive window is a
pyvista Plotter; the screenshot renders the same scene (lights, camera, colours) with VTK's
own classes (``render_model``), without pyvista's plotting layer and the matplotlib it
loads (~1.2 s of CPU to import: the report's CAD process, issue 40), and composes it with
its legend (``compose``). Off screen, with no X display, VTK renders through EGL (Mesa's
``libegl1`` + ``libgl1-mesa-dri`` on Debian/Ubuntu; see docs/geometry.md);
``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` is set for that case so VTK does not first
try (and warn about) a missing X server.
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
#: The camera: along +y at the x–z cut plane, turned by these angles (degrees) to look a
#: little from the shaft side and from above.
AZIMUTH_DEG, ELEVATION_DEG = -25.0, 20.0
#: Multisample anti-aliasing of the screenshot (pyvista's default theme: MSAA, 8 samples).
MULTI_SAMPLES = 8


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
    plotter.camera.azimuth = AZIMUTH_DEG
    plotter.camera.elevation = ELEVATION_DEG
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
    dest = _png(path)
    compose(render_model(clutch, tolerance=tolerance, window_size=window_size), clutch,
            dest, window_size=window_size)  # fmt: skip
    return dest


#: Share of the screenshot's width given to the model; the legend takes the rest.
LEGEND_SPLIT = 0.66


def _png(path: str | os.PathLike[str]) -> Path:
    dest = Path(path)
    if dest.suffix.lower() != ".png":
        raise ParameterError(f"--screenshot {dest}: must end in .png")
    return dest


def render_model(
    clutch: DrumClutch,
    *,
    tolerance: float | None = None,
    window_size: tuple[int, int] = WINDOW_SIZE,
) -> Any:
    """The model's part of the screenshot (its ``LEGEND_SPLIT`` of ``window_size``), off
    screen: RGB pixels (uint8, rows from the top). The window's scene (``build_plotter``:
    pyvista's light kit, flat shading, the camera along +y turned by AZIMUTH_DEG and
    ELEVATION_DEG, MSAA) built with VTK's own classes; tessellated to ``tolerance`` [m], by
    default one pixel of the model's part."""
    w, h = window_size
    size = (max(1, round(w * LEGEND_SPLIT)), h)
    tolerance = view_tolerance(clutch, size) if tolerance is None else tolerance
    triangles = view_triangles(clutch, tolerance)  # before VTK: build123d's import first
    _prepare_offscreen()
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (VTK's OpenGL implementation)
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkRenderingCore import (
        vtkActor,
        vtkLightKit,
        vtkPolyDataMapper,
        vtkRenderer,
        vtkRenderWindow,
        vtkWindowToImageFilter,
    )

    ren = vtkRenderer()
    ren.SetBackground(1.0, 1.0, 1.0)
    ren.SetTwoSidedLighting(True)
    ren.AutomaticLightCreationOff()
    for part, material, v, faces in triangles:
        points = vtkPoints()
        points.SetData(numpy_to_vtk(v.astype("float64", order="C"), deep=True))
        cells = vtkCellArray()
        cells.ImportLegacyFormat(numpy_to_vtkIdTypeArray(faces.astype("int64"), deep=True))
        poly = vtkPolyData()
        poly.SetPoints(points)
        poly.SetPolys(cells)
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(poly)
        mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()  # pyvista's add_mesh defaults, flat shaded
        prop.SetColor(*material_colour(material))
        prop.SetOpacity(FLUID_OPACITY if part == "fluid" else 1.0)
        prop.SetInterpolationToFlat()
        prop.SetAmbient(0.0)
        prop.SetDiffuse(1.0)
        prop.SetSpecular(0.0)
        ren.AddActor(actor)
    vtkLightKit().AddLightsToRenderer(ren)
    lights = ren.GetLights()
    lights.InitTraversal()
    for _ in range(lights.GetNumberOfItems()):  # colours in 8-bit steps, as pyvista's Light
        light = lights.GetNextItem()
        for name in ("DiffuseColor", "SpecularColor", "AmbientColor"):
            rgb = getattr(light, f"Get{name}")()
            getattr(light, f"Set{name}")(*(round(x * 255) / 255 for x in rgb))
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(MULTI_SAMPLES)
    window.SetSize(*size)
    window.AddRenderer(ren)
    cam = ren.GetActiveCamera()
    b = ren.ComputeVisiblePropBounds()
    x, y, z = ((b[i] + b[i + 1]) / 2 for i in (0, 2, 4))
    cam.SetFocalPoint(x, y, z)
    cam.SetPosition(x, y - 1.0, z)  # along +y at the x–z cut plane
    cam.SetViewUp(0.0, 0.0, 1.0)
    ren.ResetCamera()
    cam.Azimuth(AZIMUTH_DEG)
    cam.Elevation(ELEVATION_DEG)
    ren.ResetCamera()
    try:
        window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.FixBoundaryOn()
        grab.ShouldRerenderOff()
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        pixels = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars())
    finally:
        window.Finalize()
    return pixels.reshape(size[1], size[0], 3)[::-1].copy()  # VTK's rows: bottom first


def compose(
    img: Any,
    clutch: DrumClutch,
    path: str | os.PathLike[str],
    *,
    window_size: tuple[int, int] = WINDOW_SIZE,
) -> Path:
    """``render_model``'s pixels and a legend panel beside them, as one PNG of
    ``window_size`` pixels at ``path`` (atomically); the report's process draws it from
    its CAD process's pixels."""
    dest = _png(path)
    _compose(img, legend_entries(clutch), window_size, dest)
    return dest


def _compose(img: Any, labels: list, size: tuple[int, int], dest: Path) -> None:
    """The rendered model and a legend panel beside it, as one PNG of ``size`` pixels."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    w, h = size
    dpi = 100
    fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi)  # no pyplot: nothing to manage
    FigureCanvasAgg(fig)
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


def show(clutch: DrumClutch, *, tolerance: float | None = None) -> None:
    """Open an interactive window (needs a display)."""
    if not has_display():
        raise ParameterError("no display for an interactive window; use --screenshot FILE.png")
    build_plotter(clutch, off_screen=False, tolerance=tolerance).show()
