"""STEP of the assembly (mm, part names kept) and one STL per part, written atomically.

Every file goes through the output layer (``geometry.atomic``): it appears complete or not
at all (an error or Ctrl-C leaves any previous file untouched), and a write that fails
(disk full, read-only) is one ``OutputError`` line naming the file and the reason.
``export_clutch`` then checks the round trip: the STEP re-imported gives every part's
volume to ``1e-6`` relative, and every STL read back is watertight; a failed check raises
ParameterError naming the part that failed. Each STL's volume is compared with its
B-rep's: a difference above ``STL_VOLUME_RTOL`` is written as a note. The set is whole or
absent: its files are written in a staging folder inside the target and moved into place
only once all are written and checked, so an error, a failed check or Ctrl-C part way
leaves the target folder as it was (a previous export in it whole).

Materials: in the STEP a part that mixes materials is a sub-assembly of one solid per
material (``geometry.cad.solid_label``); beside it, ``<stem>.materials.json``
(``sidecar_path``) names every solid in file order with its material, density and volume,
so ``mrclutch inertia clutch.step`` can weigh the tool's own export (``read_materials``).
"""

from __future__ import annotations

import errno
import json
import math
import os
import shutil
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from geometry.atomic import (
    OutputError,
    atomic_path,
    check_target,
    fsync_dir,
    output_error,
    write_bytes,
    write_text,
)
from geometry.cad import (
    assembly,
    brep_volume_mm3,
    material_solids,
    part_solids,
    solid_label,
    tessellate,
)
from geometry.mass import check_mesh
from geometry.materials import DEFAULT_CHOICE, DENSITY_RANGE, LABEL, MaterialChoice
from geometry.params import DrumClutch
from geometry.reading import read_json
from geometry.section import build_section
from geometry.validation import ParameterError, check_positive

#: Relative volume agreement demanded of the STEP round trip.
STEP_RTOL = 1e-6
#: Relative difference of an STL's volume from its B-rep's above which export notes it.
STL_VOLUME_RTOL = 1e-2
#: Format tag of the materials sidecar.
SIDECAR_FORMAT = "mrclutch-materials/1"


@dataclass(frozen=True)
class ExportResult:
    """Paths written and the round-trip figures (volumes in mm³)."""

    step: Path
    stl: dict[str, Path]
    volumes_mm3: dict[str, float]
    step_volumes_mm3: dict[str, float]
    stl_triangles: dict[str, int]
    stl_volumes_mm3: dict[str, float] = field(default_factory=dict)
    materials: Path | None = None
    notes: tuple[str, ...] = ()


def write_step(shape: Any, path: str | os.PathLike[str]) -> Path:
    """STEP (AP214, mm) of ``shape``, atomically; child labels become product names."""
    from build123d import Unit, export_step

    dest = Path(path)
    with atomic_path(dest) as tmp:
        try:
            ok = export_step(shape, tmp, unit=Unit.MM)
        except RuntimeError:  # build123d ≥ 0.8 raises where older ones returned False
            ok = False
        if not ok:  # OpenCascade says only "failed": the folder's answer to a write says why
            raise OutputError(f"{dest}: cannot write ({_write_probe(tmp.parent)})")
    return dest


def _write_probe(folder: Path) -> str:
    """Why writing in ``folder`` fails (the reason of an OSError met writing and flushing
    64 KiB there), or that OpenCascade's writer failed when the folder takes the bytes."""
    try:
        with tempfile.TemporaryFile(dir=folder) as f:
            f.write(bytes(1 << 16))
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    return "OpenCascade's STEP writer failed"


def write_stl(
    shape: Any, path: str | os.PathLike[str], tolerance: float, angular_tolerance: float = 0.5
) -> tuple[int, float]:
    """Binary STL of ``shape`` (mm) at chord height ``tolerance`` (m), atomically.

    Returns the triangle count and the mesh's volume (mm³). The mesh is checked watertight
    before it is written.
    """
    import trimesh

    check_positive("tolerance", tolerance, " m")
    dest = Path(path)
    v, f = tessellate(shape, tolerance * 1e3, angular_tolerance)
    mesh = trimesh.Trimesh(v, f, process=True)
    check_mesh(mesh, dest.stem)
    write_bytes(dest, mesh.export(file_type="stl"))  # in memory: no file left open on error
    return len(mesh.faces), float(mesh.volume)


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


def sidecar_path(step: str | os.PathLike[str]) -> Path:
    """``clutch.step`` -> ``clutch.materials.json`` beside it."""
    p = Path(step)
    return p.with_name(f"{p.stem}.materials.json")


def step_solids(parts: dict[str, Any]) -> list[tuple[str, str, Any]]:
    """(part, solid label, shape) of every solid in file order: a sub-assembly's children,
    or the part itself."""
    out = []
    for part, shape in parts.items():
        kids = list(getattr(shape, "children", ()) or ())
        for k, ch in enumerate(kids or [shape]):
            out.append((part, (ch.label or f"{part}.{k + 1}") if kids else part, ch))
    return out


def write_materials(step: Path, solids: list[tuple[str, str, str, float, float]]) -> Path:
    """The sidecar of ``step``: (part, solid label, material, kg/m³, mm³) per solid."""
    doc = {
        "format": SIDECAR_FORMAT,
        "step": step.name,
        "units": {"density": "kg/m3", "volume": "mm3", "lengths": "mm"},
        "solids": [
            {
                "part": p,
                "name": n,
                "material": m,
                "label": LABEL.get(m, m),
                "density_kg_m3": rho,
                "volume_mm3": v,
            }
            for p, n, m, rho, v in solids
        ],
    }
    return write_text(sidecar_path(step), json.dumps(doc, indent=2) + "\n")


def read_materials(step: str | os.PathLike[str]) -> dict[str, dict[str, Any]] | None:
    """The sidecar of ``step`` as solid label -> entry, or None when there is none; a
    sidecar that cannot be read or lacks a density raises ParameterError (one line)."""
    path = sidecar_path(step)
    if not os.path.lexists(path):
        return None
    doc = read_json(path, "materials sidecar")  # regular, bounded, UTF-8 (geometry.reading)
    try:
        solids = doc["solids"]
        out = {}
        for e in solids:
            rho, vol = float(e["density_kg_m3"]), float(e["volume_mm3"])
            if not (math.isfinite(rho) and rho > 0 and math.isfinite(vol) and vol > 0):
                raise ValueError(f"solid {e['name']}: density {rho}, volume {vol}")
            lo, hi = DENSITY_RANGE
            if not lo <= rho <= hi:
                raise ParameterError(f"{path}: solid {e['name']}: density_kg_m3 = {rho:g}: "
                                     f"must be in [{lo:g}, {hi:g}] kg/m³")  # fmt: skip
            out[str(e["name"])] = {**e, "density_kg_m3": rho, "volume_mm3": vol}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ParameterError(f"{path}: not a materials sidecar ({exc})") from None
    return out


def export_clutch(
    clutch: DrumClutch,
    out_dir: str | os.PathLike[str],
    tolerance: float = 1e-5,
    *,
    angular_tolerance: float = 0.5,
    check: bool = True,
    materials: MaterialChoice = DEFAULT_CHOICE,
) -> ExportResult:
    """Write ``clutch.step`` and ``<part>.stl`` into ``out_dir`` and check the round trip;
    every part is made of (and coloured as) the material ``materials`` chooses for it.

    Whole or absent: the files are written in a staging folder inside ``out_dir`` and moved
    into place once every one is written and checked. A write that fails (OutputError:
    disk full, read-only), a failed check or Ctrl-C removes the staging folder, and the
    folder itself when this call made it; a previous export in ``out_dir`` stays whole."""
    check_positive("tolerance", tolerance, " m")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"--out {out}: exists and is not a directory")
    created = not out.exists()
    stage: Path | None = None
    done = False
    try:
        try:
            out.mkdir(parents=True, exist_ok=True)
            stage = Path(tempfile.mkdtemp(prefix=f".clutch-export-{os.getpid()}-", dir=out))
        except OSError as exc:
            raise output_error(out, exc) from None
        res = _publish(_export(clutch, stage, tolerance, angular_tolerance, check, materials), out)
        done = True
        return res
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        if created and not done:
            try:
                out.rmdir()
            except OSError:  # not empty (someone else's file) or already gone
                pass


def _publish(res: ExportResult, out: Path) -> ExportResult:
    """Move the staged files of ``res`` into ``out`` (renames within one folder: the STLs
    and the sidecar first, the STEP last), the result with their paths in ``out``. A
    target that is a link to another file system is written through it by a copy."""
    staged = [*res.stl.values(), res.materials, res.step]
    moved: dict[Path | None, Path] = {}
    for src in staged:
        assert src is not None  # _export always writes the sidecar
        dest = out / src.name
        try:
            target = check_target(dest)
            try:
                os.replace(src, target)
            except OSError as exc:
                if exc.errno != errno.EXDEV:
                    raise
                with atomic_path(dest) as tmp:  # a link out of this file system: copy through
                    shutil.copyfile(src, tmp)
        except OSError as exc:
            raise output_error(dest, exc) from None
        moved[src] = dest
    fsync_dir(out)
    return replace(res, step=moved[res.step], materials=moved[res.materials],
                   stl={n: moved[p] for n, p in res.stl.items()})  # fmt: skip


def _export(clutch: DrumClutch, out: Path, tolerance: float, angular_tolerance: float,
            check: bool, materials: MaterialChoice) -> ExportResult:  # fmt: skip
    section = build_section(clutch, materials)
    parts = part_solids(clutch, section)
    mats = material_solids(clutch, section)
    step = write_step(assembly(clutch, parts, mats, materials), out / "clutch.step")
    solids = []
    for part in parts:
        own = [(m, sh) for (p, m), sh in mats.items() if p == part]
        for material, sh in own:
            name = solid_label(part, material) if len(own) > 1 else part
            rho = float(section.densities[material])
            solids.append((part, name, material, rho, brep_volume_mm3(sh)))
    side = write_materials(step, solids)
    stl = {name: out / f"{name}.stl" for name in parts}
    tris: dict[str, int] = {}
    stl_vols: dict[str, float] = {}
    for n, s in parts.items():
        tris[n], stl_vols[n] = write_stl(s, stl[n], tolerance, angular_tolerance)
    vols = {n: brep_volume_mm3(s) for n, s in parts.items()}
    notes = tuple(
        f"{n}.stl: mesh volume {stl_vols[n]:.6g} mm³ is {(stl_vols[n] / v - 1) * 100:+.2g} % "
        f"off the exact {v:.6g} mm³ (chord height {tolerance * 1e3:g} mm; a smaller "
        "--tolerance-mm follows the curves closer)"
        for n, v in vols.items()
        if abs(stl_vols[n] / v - 1) > STL_VOLUME_RTOL
    )
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
    return ExportResult(step, stl, vols, back, tris, stl_vols, side, notes)
