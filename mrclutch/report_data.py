"""The figures the design report computes beside the evaluation: its CAD export (STEP, one STL
per part, their volumes) and its torque–current curves (circuit and network, with FEM points)
and their errors, and the B-rep mass its CAD process hands over. The HTML report writer
(``mrclutch.cli.report``) draws and writes them (issue 43: no computation under
``mrclutch/cli/``)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from geometry.export import export_clutch
from geometry.mass import MassReport, PartMass, brep_mass, brep_mass_from
from geometry.materials import MaterialChoice
from geometry.params import DrumClutch
from magnetics.torque import TorqueCurve, torque_curve
from mrclutch.design import ClutchDesign

#: Currents of the report's torque curve (A): the paper's Fig. 2b range.
CURVE_CURRENTS = np.linspace(0.0, 7.0, 29)
#: Currents at which the FEM checks the circuit in the report (A).
FEM_CHECK_CURRENTS = (1.0, 3.0, 5.0, 7.0)


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
    sec = design.section()
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


#: A MassReport as plain data: (method, {part: (mass kg, inertia kg m²)}, notes), what a pipe
#: to the report's CAD process carries (a MappingProxyType does not pickle).
MassData = tuple[str, dict[str, tuple[float, float]], tuple[str, ...]]


def mass_data(rep: MassReport) -> MassData:
    """``rep`` as plain data (``MassData``)."""
    return rep.method, {p: (pm.mass, pm.inertia) for p, pm in rep.parts.items()}, rep.notes


def mass_report(data: MassData) -> MassReport:
    """The MassReport that ``mass_data`` flattened."""
    method, parts, notes = data
    return MassReport(method, MappingProxyType({p: PartMass(m, i) for p, (m, i) in
                                                parts.items()}), tuple(notes))  # fmt: skip


def design_brep_mass(design: ClutchDesign) -> MassData:
    """The design's exact B-rep mass (``geometry.mass.brep_mass``, build123d) as plain data."""
    return mass_data(brep_mass(design.clutch, materials=design.materials))


@contextmanager
def design_mass_from(design: ClutchDesign, fetch: Callable[[], MassData]) -> Iterator[None]:
    """Inside, the B-rep mass of ``design`` (its clutch and materials) is ``fetch()``'s, e.g.
    the report's CAD process's (issue 40); any other design's is computed where asked."""

    def source(clutch: DrumClutch, materials: MaterialChoice) -> MassReport | None:
        if (clutch, materials) != (design.clutch, design.materials):
            return None  # not this design's: brep_mass computes it
        return mass_report(fetch())

    with brep_mass_from(source):
        yield
