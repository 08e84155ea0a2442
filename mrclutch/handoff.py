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
from magnetics.drag import clutch_drag
from magnetics.export.femm import problem, write_fem, write_lua
from magnetics.export.onelab import write_geo, write_pro
from magnetics.hot import phi_at, tau_y_coefficient, tau_y_factor
from magnetics.hysteresis import HYSTERESIS
from magnetics.materials import FLUIDS, MATERIALS, BHCurve
from magnetics.torque import rpm_to_rad_s, torque_curve
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


def _unverified(rec: Any, *fields: str) -> str:
    """The ``fields`` the record lists as unverified, space-separated ("-" if none)."""
    bad = [f for f in fields if f in rec.get("unverified", ())]
    return " ".join(bad) or "-"


def _fluid_tables(name: str, rec: Any) -> dict[str, str]:
    """A fluid's tables (``material_tables``): τy(H), its datasheet points, η(T), τy(T)."""
    fl = FLUIDS[name]
    out = {
        f"{name}_tau_y.csv": _csv(
            ["H_A_per_m", "tau_y_Pa"],
            [f"{rec['label']}: yield stress", f"source: {fl.source}"],
            list(zip(TAU_H.tolist(), fl.tau_y(TAU_H).tolist(), strict=True)),
        )
    }
    ds = rec.get("tau_y")
    if isinstance(ds, dict) and "h" in ds:
        out[f"{name}_tau_y_datasheet.csv"] = _csv(
            ["H_A_per_m", "tau_y_Pa"],
            [
                f"{rec['label']}: datasheet yield stress (comparison only)",
                f"source: {ds.get('source', '')}",
            ],
            [(float(h), float(t)) for h, t in zip(ds["h"], ds["tau"], strict=True)],
        )
    lo, hi = fl.temperature_range
    temps = np.arange(lo, hi + 1e-9, VISCOSITY_STEP_C)
    out[f"{name}_viscosity.csv"] = _csv(
        ["T_C", "eta_Pa_s"],
        [
            f"{rec['label']}: off-state viscosity",
            f"source: {rec.get('viscosity_source', '')}; temperature law: the "
            f"carrier's Walther line ({fl.carrier}) [astm-d341]",
        ],
        list(zip(temps.tolist(), np.atleast_1d(fl.viscosity_at(temps)).tolist(), strict=True)),
    )
    if fl.carrier_expansion is not None:
        phi = np.atleast_1d(phi_at(fl.phi, fl.carrier_expansion, temps))
        ratio = np.atleast_1d(tau_y_factor(fl, temps))
        out[f"{name}_tau_y_temperature.csv"] = _csv(
            ["T_C", "iron_fraction", "tau_y_ratio"],
            [
                f"{rec['label']}: yield stress against temperature, tau_y(T)/tau_y(20 C) at "
                f"any field (magnetics.hot: the carrier expands by "
                f"{fl.carrier_expansion:g} 1/K, the iron not)",
                f"source: {rec.get('tau_y_temperature_source', '')}; carrier expansion: "
                f"{rec.get('carrier_expansion_source', '')}",
            ],
            list(zip(temps.tolist(), phi.tolist(), ratio.tolist(), strict=True)),
        )
    return out


def material_tables() -> dict[str, str]:
    """File name → CSV text of every material of the library (``geometry.materials``):
    ``<name>_bh.csv`` (the B–H table points as the data file holds them, before the
    tool's monotone interpolation); for fluids ``<name>_tau_y.csv`` (Carlson's τy(H), the
    model the tool uses, on ``TAU_H``), ``<name>_tau_y_datasheet.csv`` where the file has
    datasheet points, ``<name>_viscosity.csv`` (η(T) over the fluid's range) and
    ``<name>_tau_y_temperature.csv`` (τy(T)/τy(20 °C), magnetics.hot); ``hysteresis.csv``
    (each steel's coercivity, remanence and saturation polarisation, magnetics.hysteresis),
    ``fluids.csv`` (each fluid's τy(T) coefficient and lifetime dissipated energy,
    magnetics.life) and ``materials.csv``, the index. Each file's ``# `` lines name its
    source; a row's ``unverified`` column names its fields not read in a source."""
    out: dict[str, str] = {}
    index, steels, fluids = [], [], []
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
        hy = HYSTERESIS.get(name)
        if hy is not None:
            steels.append((name, hy.coercivity, hy.remanence, hy.saturation,
                           _unverified(rec, "hysteresis.coercivity_A_per_m",
                                       "hysteresis.remanence_T"), hy.source))  # fmt: skip
            files.append("hysteresis.csv")
        fl = FLUIDS.get(name)
        if fl is not None:
            tables = _fluid_tables(name, rec)
            out.update(tables)
            files += [*tables, "fluids.csv"]
            coef = tau_y_coefficient(fl)
            fluids.append((name, fl.phi, fl.tau_y_max, "" if fl.carrier_expansion is None
                           else fl.carrier_expansion, "" if coef is None else coef,
                           "" if fl.lifetime_energy is None else fl.lifetime_energy,
                           _unverified(rec, "carrier_expansion", "lifetime_dissipated_energy"),
                           rec.get("tau_y_temperature_source", ""),
                           rec.get("lifetime_dissipated_energy_source", "")))  # fmt: skip
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
    out["hysteresis.csv"] = _csv(
        ["name", "coercivity_A_per_m", "remanence_T", "saturation_polarisation_T",
         "unverified", "source"],
        ["each steel's major loop (magnetics.hysteresis): coercivity and remanence from its "
         "data file's [hysteresis], the saturation polarisation B - mu0 H at its B-H table's "
         "last point"],
        steels,
    )  # fmt: skip
    out["fluids.csv"] = _csv(
        ["name", "iron_fraction", "tau_y_max_Pa", "carrier_expansion_per_K",
         "tau_y_temperature_coefficient_per_K", "lifetime_dissipated_energy_J_per_m3",
         "unverified", "tau_y_temperature_source", "lifetime_dissipated_energy_source"],
        ["each MR fluid: Carlson's saturated yield stress [carlson], the d(tau_y/tau_y0)/dT "
         "at 20 C of the dilution law (magnetics.hot; empty: no carrier expansion given) and "
         "the lifetime dissipated energy (magnetics.life; empty: no data)"],
        fluids,
    )  # fmt: skip
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
    point, current fastest): the yield torque by ``method`` (magnetics.torque) at 20 °C,
    solved once, times τy(T)/τy(20 °C) (magnetics.hot.tau_y_factor: the carrier's dilution,
    the tool's hot torque as in mrclutch.duty.torque_at), plus every drag term at that
    speed and temperature (magnetics.drag.clutch_drag); ``off_state_torque_N_m`` is the
    drag alone, the torque at 0 A with no remanence (the residual torque after a peak
    current depends on the history: ``evaluate`` reports it)."""
    cur = np.asarray(currents, dtype=float)
    if cur.ndim != 1 or cur.size == 0 or not np.all(np.isfinite(cur)):
        raise ParameterError("currents: give finite values (A)")
    fluid = FLUIDS[design.materials.fluid]
    lo, hi = fluid.temperature_range
    for t in temperatures_c:
        check_range("fluid temperature", t, lo, hi, " °C")
    for s in speeds_rpm:
        check_range("slip speed", s, 0.0, 1e5, " rpm")
    section = build_section(design.clutch, design.materials)
    assert section.table is not None  # built from a design: it has its region table
    cold = torque_curve(section, cur, method=method, support=design.support).yield_torque
    cols: dict[str, list[float]] = {c: [] for c in MAP_COLUMNS}
    for t in temperatures_c:
        hot = cold * float(tau_y_factor(fluid, t))
        for s in speeds_rpm:
            off = clutch_drag(section.table, rpm_to_rad_s(s), t, design.support, fluid).torque
            for i, ty in zip(cur, hot, strict=True):
                for k, v in zip(MAP_COLUMNS, (i, s, t, ty, off, ty + off), strict=True):
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
