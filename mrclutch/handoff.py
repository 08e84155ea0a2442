"""What the next tools in the chain read (docs/handoff.md): the section as a FEMM or ONELAB
problem, a DXF or a dimensioned drawing, the material library as CSV tables, a torque map a
controller loads as a lookup table, and the device description a haptic rendering
framework clamps its commands to. Pure functions of a design; the
command line writes their results through the output layer.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from typing import Any

import numpy as np

from geometry.drawing import section_drawing, section_dxf
from geometry.materials import KIND, RECORDS
from geometry.section import build_section
from geometry.validation import ParameterError, check_range
from magnetics.export.femm import problem, write_fem, write_lua
from magnetics.export.onelab import write_geo, write_pro
from magnetics.materials import FLUIDS, MATERIALS, BHCurve
from magnetics.torque import torque_curve
from mrclutch.design import ClutchDesign
from mrclutch.haptics.model import bandwidth
from mrclutch.haptics.zwidth import is_stable_spring_damper
from mrclutch.pipeline import evaluate

#: H (A/m) of the exported τy(H) tables: 0 … 400 kA/m, past the knee of every library fluid
TAU_H = np.linspace(0.0, 4e5, 81)
#: °C step of the exported η(T) tables over each fluid's operating range
VISCOSITY_STEP_C = 5.0
#: the device description's schema name (docs/handoff.md); bump it when a key changes
DEVICE_SCHEMA = "mrclutch.device/1"


#: the solvers' hand-offs (``export --format``): each format's files, by suffix
SOLVER_FILES = {"femm": ((".fem", write_fem), (".lua", write_lua)),
                "onelab": ((".geo", write_geo), (".pro", write_pro))}  # fmt: skip


def solver_files(design: ClutchDesign, fmt: str, current: float, name: str) -> dict[str, str]:
    """File name → text of the design's FEMM 4.2 (``femm``: NAME.fem, NAME.lua) or Gmsh +
    GetDP (``onelab``: NAME.geo, NAME.pro) problem at the coil current ``current`` (A)."""
    p = problem(build_section(design.clutch, design.materials), current, name)
    return {f"{name}{suffix}": write(p) for suffix, write in SOLVER_FILES[fmt]}


def dxf_text(design: ClutchDesign) -> str:
    """The design's r-z section as DXF text: a layer per part and material."""
    return section_dxf(build_section(design.clutch, design.materials))


def draw_section(design: ClutchDesign, path: str) -> None:
    """The dimensioned section drawing (SVG) at ``path``, with the ``[process]`` tolerances;
    the caller passes the output layer's temporary path."""
    section = build_section(design.clutch, design.materials)
    section_drawing(section, path, design.process.tolerance, design.process.runout)


def _csv(header: Sequence[str], comments: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    buf = io.StringIO()
    for c in comments:
        buf.write(f"# {c}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([f"{x:.10g}" if isinstance(x, float) else x for x in r])
    return buf.getvalue()


def material_tables() -> dict[str, str]:
    """File name → CSV text of every material of the library (``geometry.materials``):
    ``<name>_bh.csv`` (the B–H table points as the data file holds them, before the
    tool's monotone interpolation), for fluids ``<name>_tau_y.csv`` (Carlson's τy(H), the
    model the tool uses, on ``TAU_H``), ``<name>_tau_y_datasheet.csv`` where the file has
    datasheet points, ``<name>_viscosity.csv`` (η(T) over the fluid's range), and
    ``materials.csv``, the index. Each file's ``# `` lines name its source."""
    out: dict[str, str] = {}
    index = []
    for name in sorted(RECORDS):
        rec, kind = RECORDS[name], KIND[name]
        mag = MATERIALS.get(name)
        files = []
        if isinstance(mag, BHCurve):
            f = f"{name}_bh.csv"
            out[f] = _csv(
                ["B_T", "H_A_per_m"],
                [f"{rec['label']}: B-H table", f"source: {mag.source}"],
                list(zip(mag.b_table, mag.h_table, strict=True)),
            )
            files.append(f)
        fl = FLUIDS.get(name)
        if fl is not None:
            f = f"{name}_tau_y.csv"
            out[f] = _csv(
                ["H_A_per_m", "tau_y_Pa"],
                [f"{rec['label']}: yield stress", f"source: {fl.source}"],
                list(zip(TAU_H.tolist(), fl.tau_y(TAU_H).tolist(), strict=True)),
            )
            files.append(f)
            ds = rec.get("tau_y")
            if isinstance(ds, dict) and "h" in ds:
                f = f"{name}_tau_y_datasheet.csv"
                out[f] = _csv(
                    ["H_A_per_m", "tau_y_Pa"],
                    [
                        f"{rec['label']}: datasheet yield stress (comparison only)",
                        f"source: {ds.get('source', '')}",
                    ],
                    [(float(h), float(t)) for h, t in zip(ds["h"], ds["tau"], strict=True)],
                )
                files.append(f)
            lo, hi = fl.temperature_range
            temps = np.arange(lo, hi + 1e-9, VISCOSITY_STEP_C)
            f = f"{name}_viscosity.csv"
            out[f] = _csv(
                ["T_C", "eta_Pa_s"],
                [
                    f"{rec['label']}: off-state viscosity",
                    f"source: {rec.get('viscosity_source', '')}; temperature law: the "
                    f"carrier's Walther line ({fl.carrier}) [astm-d341]",
                ],
                list(
                    zip(temps.tolist(), np.atleast_1d(fl.viscosity_at(temps)).tolist(), strict=True)
                ),
            )
            files.append(f)
        index.append(
            (
                name,
                kind,
                rec["label"],
                float(rec["density"]),
                float(rec["conductivity"]),
                " ".join(files),
                " ".join(rec.get("unverified", [])) or "-",
            )
        )
    out["materials.csv"] = _csv(
        [
            "name",
            "kind",
            "label",
            "density_kg_per_m3",
            "conductivity_S_per_m",
            "tables",
            "unverified",
        ],
        [
            "the material library (geometry/data/materials): one row per material; sources in "
            "each table and in docs/references.md"
        ],
        index,
    )
    return out


# ---- the torque map ---------------------------------------------------------------------
MAP_COLUMNS = (
    "current_A",
    "slip_speed_rpm",
    "fluid_temperature_C",
    "yield_torque_N_m",
    "off_state_torque_N_m",
    "torque_N_m",
)


def torque_map(
    design: ClutchDesign,
    currents: Sequence[float],
    speeds_rpm: Sequence[float],
    temperatures_c: Sequence[float],
    method: str = "network",
) -> dict[str, np.ndarray]:
    """Torque over current × slip speed × fluid temperature (``MAP_COLUMNS``, one row per
    point, current fastest): the yield torque by ``method`` (magnetics.torque) plus every
    drag term at that speed and temperature (magnetics.drag); ``off_state_torque_N_m`` is
    the drag alone, the torque at 0 A. The yield stress does not depend on temperature in
    the library's fluid model (Carlson's law), so only the drag varies with it."""
    cur = np.asarray(currents, dtype=float)
    if cur.ndim != 1 or cur.size == 0 or not np.all(np.isfinite(cur)):
        raise ParameterError("currents: give finite values (A)")
    section = build_section(design.clutch, design.materials)
    lo, hi = FLUIDS[design.materials.fluid].temperature_range
    cols: dict[str, list[float]] = {c: [] for c in MAP_COLUMNS}
    for t in temperatures_c:
        check_range("fluid temperature", t, lo, hi, " °C")
        for s in speeds_rpm:
            check_range("slip speed", s, 0.0, 1e5, " rpm")
            tc = torque_curve(
                section, cur, method=method, speed_rpm=s, temperature=t, support=design.support
            )
            for i, ty, tt in zip(cur, tc.yield_torque, tc.torque, strict=True):
                for k, v in zip(MAP_COLUMNS, (i, s, t, ty, tc.off_state_torque, tt), strict=True):
                    cols[k].append(float(v))
    return {k: np.array(v) for k, v in cols.items()}


# ---- the device description -----------------------------------------------------------
def device_description(design: ClutchDesign, n_k: int = 9) -> dict[str, Any]:
    """What a rendering framework clamps its commands to (schema ``DEVICE_SCHEMA``,
    docs/handoff.md), from the design's evaluation (mrclutch.pipeline.evaluate) of the MR
    pair at the hand: the largest force, K_max, the passive (K, B) region of a virtual
    spring-damper as a polygon (its Z-width, mrclutch.haptics.zwidth) with each vertex's
    stability, the damping range, the bandwidth at ``n_k`` stiffnesses from 0 to K_max,
    and the delay and update rate the verdicts assume."""
    ev = evaluate(design)
    p = ev.mr
    zw = ev.zwidth["mr"]
    b = np.asarray(zw["B_N_s_per_m"], dtype=float)
    k_hi = np.asarray(zw["K_max_N_per_m"], dtype=float)
    k_lo = np.asarray(zw["K_min_N_per_m"], dtype=float)
    ok = np.isfinite(k_hi) & np.isfinite(k_lo)
    upper = [(float(k), float(bb)) for k, bb in zip(k_hi[ok], b[ok], strict=True)]
    lower = [(float(k), float(bb)) for k, bb in zip(k_lo[ok], b[ok], strict=True)][::-1]
    polygon = upper + [v for v in lower if v not in upper]
    k_max = float(ev.haptic["K_max_N_per_m"])
    ks = np.linspace(0.0, k_max, n_k)
    bw = [float(x) for x in np.atleast_1d(bandwidth(p, ks[1:]))]
    return {
        "schema": DEVICE_SCHEMA,
        "design": design.name,
        "units": "SI at the hand: N, m, s",
        "force_max_N": float(p.f_max),
        "K_max_N_per_m": k_max,
        "max_passive_K_N_per_m": float(ev.haptic["max_passive_K_N_per_m"]),
        "max_stable_K_N_per_m": float(ev.haptic["max_stable_K_N_per_m"]),
        "passive_region": {
            "polygon_K_N_per_m_B_N_s_per_m": [list(v) for v in polygon],
            "vertices_stable": [bool(is_stable_spring_damper(p, k, bb)) for k, bb in polygon],
            "area_N2_s_per_m2": float(zw["zwidth_area_N2_s_per_m2"]),
        },
        "damping_N_s_per_m": {
            "intrinsic_b1": float(p.b1),
            "virtual_max_passive": float(zw["B_top_N_s_per_m"]),
        },
        "bandwidth_hz": [
            {"K_N_per_m": float(k), "bandwidth_hz": w} for k, w in zip(ks[1:], bw, strict=True)
        ],
        "delay_s": float(p.delay),
        "update_rate_hz": None if p.sample_period <= 0 else 1.0 / float(p.sample_period),
        "update_rate_note": "continuous-time loop with a pure delay (no sample-and-hold)"
        if p.sample_period <= 0
        else "sample-and-hold at the update rate",
    }
