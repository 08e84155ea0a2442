"""STEP of the assembly (mm, part names kept) and one STL per part, written atomically.

Every file goes through ``geometry.atomic.atomic_path``: it appears complete or not at all
(an error or Ctrl-C leaves any previous file untouched). ``export_clutch`` then checks the
round trip: the STEP re-imported gives every part's volume to ``1e-6`` relative, and every
STL read back is watertight; a failed check raises ParameterError (nothing is half-done:
the files that passed stay, the message names the one that failed).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from geometry.atomic import atomic_path
from geometry.cad import assembly, brep_volume_mm3, part_solids, tessellate
from geometry.mass import check_mesh
from geometry.params import DrumClutch
from geometry.validation import ParameterError, check_positive

#: Relative volume agreement demanded of the STEP round trip.
STEP_RTOL = 1e-6


@dataclass(frozen=True)
class ExportResult:
    """Paths written and the round-trip figures (volumes in mm³)."""

    step: Path
    stl: dict[str, Path]
    volumes_mm3: dict[str, float]
    step_volumes_mm3: dict[str, float]
    stl_triangles: dict[str, int]


def write_step(shape: Any, path: str | os.PathLike[str]) -> Path:
    """STEP (AP214, mm) of ``shape``, atomically; child labels become product names."""
    from build123d import Unit, export_step

    dest = Path(path)
    with atomic_path(dest) as tmp:
        if not export_step(shape, tmp, unit=Unit.MM):
            raise ParameterError(f"STEP export to {dest} failed")
    return dest


def write_stl(
    shape: Any, path: str | os.PathLike[str], tolerance: float, angular_tolerance: float = 0.5
) -> int:
    """Binary STL of ``shape`` (mm) at chord height ``tolerance`` (m), atomically.

    Returns the triangle count. The mesh is checked watertight before it is written.
    """
    import trimesh

    check_positive("tolerance", tolerance, " m")
    dest = Path(path)
    v, f = tessellate(shape, tolerance * 1e3, angular_tolerance)
    mesh = trimesh.Trimesh(v, f, process=True)
    check_mesh(mesh, dest.stem)
    with atomic_path(dest) as tmp:
        mesh.export(tmp, file_type="stl")
    return len(mesh.faces)


def read_step_parts(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The labelled solids of a STEP file (label -> shape, mm); unlabelled ones numbered."""
    from build123d import import_step

    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"STEP file {p}: not found")
    try:
        comp = import_step(p)
    except Exception as exc:  # OCC raises assorted errors on bad files
        raise ParameterError(f"STEP file {p}: cannot be read ({exc})") from None
    children = list(comp.children) or list(comp.solids())
    if not children:
        raise ParameterError(f"STEP file {p}: contains no solid")
    out: dict[str, Any] = {}
    for k, ch in enumerate(children):
        name = ch.label or f"solid{k + 1}"
        while name in out:
            name += "_"
        out[name] = ch
    return out


def export_clutch(
    clutch: DrumClutch,
    out_dir: str | os.PathLike[str],
    tolerance: float = 1e-5,
    *,
    angular_tolerance: float = 0.5,
    check: bool = True,
) -> ExportResult:
    """Write ``clutch.step`` and ``<part>.stl`` into ``out_dir`` and check the round trip."""
    check_positive("tolerance", tolerance, " m")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"--out {out}: exists and is not a directory")
    parts = part_solids(clutch)
    step = write_step(assembly(clutch, parts), out / "clutch.step")
    stl = {name: out / f"{name}.stl" for name in parts}
    tris = {n: write_stl(s, stl[n], tolerance, angular_tolerance) for n, s in parts.items()}
    vols = {n: brep_volume_mm3(s) for n, s in parts.items()}
    back: dict[str, float] = {}
    if check:
        back = {n: brep_volume_mm3(s) for n, s in read_step_parts(step).items()}
        for name, v in vols.items():
            if name not in back:
                raise ParameterError(f"{step}: part {name!r} missing after re-import")
            if abs(back[name] - v) > STEP_RTOL * v:
                raise ParameterError(
                    f"{step}: part {name} volume {back[name]:.9g} mm³ after re-import, "
                    f"{v:.9g} mm³ before (rtol {STEP_RTOL:g})"
                )
    return ExportResult(step, stl, vols, back, tris)
