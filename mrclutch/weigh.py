"""The mass and inertia of a CAD file, as ``mrclutch inertia FILE.step|FILE.stl`` gives them:
a STEP per part (densities from the options, or the export's materials sidecar solid by
solid), an STL as one part of one density; and the tool's own output rotor where the file
has its part names.

The CLI (mrclutch/cli/commands/inertia.py) parses the options (the densities among them),
calls these and formats. build123d and trimesh load with the geometry functions.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from geometry.cad import brep_volume_mm3
from geometry.export import read_materials, read_step_parts, sidecar_path, step_solids
from geometry.mass import check_mesh, check_shells, weigh_mesh, weigh_shape
from geometry.materials import DENSITY_RANGE
from geometry.reading import check_regular
from geometry.section import OUTPUT_PARTS
from geometry.validation import ParameterError

__all__ = [
    "DENSITY_RANGE",
    "load_stl",
    "output_rotor",
    "read_step",
    "stl_hint",
    "weigh_step",
    "weigh_stl",
]


def read_step(path: Path) -> tuple[dict[str, Any], dict[str, dict[str, Any]] | None]:
    """(part → shape, the export's materials sidecar or None) of a STEP file (a FIFO, device
    or directory refused by name; size capped)."""
    check_regular(path, "CAD file")
    return read_step_parts(path), read_materials(path)


def weigh_step(path: Path, shapes: dict[str, Any], side: dict[str, dict[str, Any]] | None,
               densities: dict[str, float], axis: str) -> dict[str, dict[str, Any]]:  # fmt: skip
    """Every part of a STEP weighed about ``axis`` through the origin: ``densities``
    (kg/m³, from the options) win; the other parts' come from the sidecar solid by solid,
    each solid's volume checked against the sidecar's (1e-5)."""
    results: dict[str, dict[str, Any]] = {}
    for part, shape in shapes.items():
        rho = densities.get(part)
        if rho is not None:
            pm = weigh_shape(shape, rho, axis)
            results[part] = {"mass_kg": pm.mass, "inertia_kg_m2": pm.inertia,
                             "density_kg_m3": rho, "density_from": "option"}  # fmt: skip
            continue
        mass = inertia = 0.0
        materials = []
        for _, name, solid in step_solids({part: shape}):
            entry = (side or {}).get(name)
            if entry is None:
                raise ParameterError(
                    f"{sidecar_path(path)}: no entry for solid {name!r} of {path.name}; "
                    "give --density or --part-density"
                )
            vol = brep_volume_mm3(solid)
            if abs(vol / entry["volume_mm3"] - 1) > 1e-5:
                raise ParameterError(
                    f"{sidecar_path(path)}: solid {name} is {vol:.6g} mm³ in {path.name}, "
                    f"{entry['volume_mm3']:.6g} mm³ in the sidecar (written for another file?)"
                )
            pm = weigh_shape(solid, entry["density_kg_m3"], axis)
            mass, inertia = mass + pm.mass, inertia + pm.inertia
            materials.append(str(entry.get("material", name)))
        vol_m3 = brep_volume_mm3(shape) * 1e-9
        results[part] = {"mass_kg": mass, "inertia_kg_m2": inertia,
                         "density_kg_m3": mass / vol_m3, "density_from": "sidecar",
                         "materials": materials}  # fmt: skip
    return results


def stl_hint(stl: Path) -> str:
    """What the export's materials file beside an STL says about its part (an STL has no
    material): the densities to give, or the STEP that weighs the exact mix."""
    suffix = ".materials.json"
    for side in sorted(stl.parent.glob(f"*{suffix}")):
        step = side.name[: -len(suffix)] + ".step"
        try:
            info = read_materials(side.with_name(step)) or {}
        except ParameterError:
            continue
        mats = sorted({(v["material"], v["density_kg_m3"]) for v in info.values()
                       if v.get("part") == stl.stem})  # fmt: skip
        if mats:
            listed = ", ".join(f"{m} {rho:g} kg/m³" for m, rho in mats)
            mixed = (f"; it mixes materials, so one density is approximate: "
                     f"`mrclutch inertia {step}` weighs each" if len(mats) > 1 else "")  # fmt: skip
            return f"({side.name} beside it lists {stl.stem}: {listed}{mixed})"
    return "(an STL carries no material; the export's <stem>.materials.json lists each part's)"


def load_stl(path: Path) -> Any:
    """The STL's mesh (trimesh; a FIFO, device or directory refused by name; size capped)."""
    check_regular(path, "CAD file")
    import trimesh

    try:
        return trimesh.load_mesh(path, file_type="stl")
    except Exception as exc:  # trimesh raises assorted errors on bad files
        raise ParameterError(f"{path}: not a readable STL ({exc})") from None


def weigh_stl(mesh: Any, name: str, density: float, axis: str) -> dict[str, Any]:
    """One STL part weighed about ``axis`` at ``density`` (kg/m³), once it is checked closed
    and of outward-facing shells."""
    check_mesh(mesh, name)
    check_shells(mesh, name)
    pm = weigh_mesh(mesh, density, axis)
    return {"mass_kg": pm.mass, "inertia_kg_m2": pm.inertia, "density_kg_m3": density}


def output_rotor(results: dict[str, dict[str, Any]], keys: Sequence[str]) -> tuple[str, dict]:
    """(label, sums of ``keys``) of the output rotor's parts where the file has the tool's
    own part names (geometry.section.OUTPUT_PARTS), else ("", {})."""
    if not set(OUTPUT_PARTS) <= set(results):
        return "", {}
    return "+".join(OUTPUT_PARTS), {k: sum(results[p][k] for p in OUTPUT_PARTS) for k in keys}
