"""The figures the design report computes beside the evaluation: its CAD export (STEP, one STL
per part, their volumes) and its torque–current curves (circuit and network, with FEM points)
and their errors. The HTML report writer (``mrclutch.cli.report``) draws and writes them
(issue 43: no computation under ``mrclutch/cli/``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from geometry.export import export_clutch
from geometry.section import Section, build_section
from magnetics.torque import TorqueCurve, torque_curve
from mrclutch.design import ClutchDesign

#: Currents of the report's torque curve (A): the paper's Fig. 2b range.
CURVE_CURRENTS = np.linspace(0.0, 7.0, 29)
#: Currents at which the FEM checks the circuit in the report (A).
FEM_CHECK_CURRENTS = (1.0, 3.0, 5.0, 7.0)


def section_of(design: ClutchDesign) -> Section:
    """The design's cross-section with its materials (what the section drawing shows)."""
    return build_section(design.clutch, design.materials)


def export_cad(design: ClutchDesign, folder: Path) -> dict[str, Any]:
    """STEP, materials sidecar and one STL per part written into ``folder``
    (``geometry.export.export_clutch``); their names, volumes and the STL volume errors."""
    res = export_clutch(design.clutch, folder, materials=design.materials)
    return {
        "step": res.step.name,
        "materials": res.materials.name if res.materials is not None else None,
        "stl": {name: p.name for name, p in res.stl.items()},
        "part_volumes_m3": {n: v * 1e-9 for n, v in res.volumes_mm3.items()},
        "stl_volume_error_rel": {
            n: res.stl_volumes_mm3[n] / v - 1 for n, v in res.volumes_mm3.items()
        },
        "notes": list(res.notes),
    }


def torque_curves(design: ClutchDesign) -> tuple[list[TorqueCurve], dict[str, Any]]:
    """The circuit's and the network's torque over CURVE_CURRENTS and the FEM's at
    FEM_CHECK_CURRENTS, at the design's input speed (to draw), and as JSON with each fast
    model's largest relative error against the FEM points."""
    rpm = design.operating.input_speed_rpm
    sec = section_of(design)
    circ = torque_curve(sec, CURVE_CURRENTS, method="circuit", speed_rpm=rpm)
    net = torque_curve(sec, CURVE_CURRENTS, method="network", speed_rpm=rpm)
    fem = torque_curve(sec, FEM_CHECK_CURRENTS, method="fem", speed_rpm=rpm)
    err = {k: float(np.max(np.abs(np.interp(fem.currents, tc.currents, tc.torque)
                                  / fem.torque - 1))) for k, tc in (("circuit", circ),
                                                                    ("network", net))}  # fmt: skip
    return [circ, net, fem], {
        "speed_rpm": rpm,
        "circuit": {"current_A": circ.currents, "torque_N_m": circ.torque},
        "network": {"current_A": net.currents, "torque_N_m": net.torque},
        "fem": {"current_A": fem.currents, "torque_N_m": fem.torque},
        "circuit_vs_fem_max_error_rel": err["circuit"],
        "network_vs_fem_max_error_rel": err["network"],
    }
