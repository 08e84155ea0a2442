"""ONELAB hand-off: a Gmsh ``.geo`` of the section and a GetDP ``.pro`` of the same
non-linear axisymmetric magnetostatic problem as the tool's FEM, and ``solve_getdp``,
which meshes and solves them with the installed ``gmsh`` and ``getdp`` and reads the
yield torque from GetDP's field the tool's way (the project's external check in CI,
tests/magnetics/test_onelab.py; docs/handoff.md).

The ``.geo`` (Gmsh's OpenCASCADE kernel [gmsh]): one rectangle per region and the air box
of the tool's FEM (``femm.fem_box``), fragmented together so the mesh is conforming; a
physical surface per material and one for the coil, a physical curve for the axis and
the box (ψ = 0); lengths in metres; element size ``size`` in the clutch (the tool's
reference 0.25 mm by default), growing to the box.

The ``.pro`` [getdp] solves the tool's own weak form (magnetics.fem, [meunier2008] §5.3)
in the flux function ψ = r·A_φ on the r–z plane:

    ∫ ν(|B|)·(1/r)·∇ψ·∇v dr dz = ∫ J v dr dz,  |B| = |∇ψ|/r,  ψ = 0 on the axis and box,

by Newton–Raphson (the Jacobian's extra term 2·(dν/d|B|²)/r³·(∇ψ⊗∇ψ)), first-order
triangles, 6-point Gauss rules. ν(|B|²) is linear in |B|² between samples of the tool's
own B–H curve of each material (``h_of_b``, 0.01 T apart to 1 T past the table, then
μ0-sloped), so both solvers see the same curve; what differs is the mesh (unstructured
triangles against a tensor grid of quadrilaterals), the elements and the solver.
B_r = −(1/r)·∂ψ/∂z and B_z = (1/r)·∂ψ/∂r are printed along each gap's mid-line at the
midpoints of cells of at most 0.05 mm, and ``solve_getdp`` hands them to the tool's
``FEMSolution.gap_yield_torque`` ("mid-line" convention) — the torque is read the tool's
way by the tool's own function.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from geometry.section import Section
from geometry.validation import ParameterError
from magnetics.export.femm import Problem, problem
from magnetics.fem.grid import DEFAULT_SIZE
from magnetics.fem.post import FEMSolution
from magnetics.materials import BHCurve, Magnetic

FloatArray = NDArray[np.float64]
#: B step (T) of the ν(|B|²) samples, and how far past a table they go on the μ0 slope
NU_STEP_T = 0.01
NU_PAST_T = 1.0
#: the air box's element size, m
BOX_SIZE = 5e-3
#: Newton: largest number of iterations and the relative change of ψ that ends it
MAX_ITERATIONS = 60
TOLERANCE = 1e-7


def _ident(name: str) -> str:
    return "M_" + "".join(c if c.isalnum() else "_" for c in name)


def write_geo(p: Problem, size: float = DEFAULT_SIZE) -> str:
    """The Gmsh ``.geo`` of ``p`` (module docstring); ``size``: element size in the
    clutch, m."""
    o = p.outline
    assert o.box is not None
    rb, zb0, zb1 = o.box
    regions = [lab for lab in o.labels if lab.role != "air"]
    L = [
        f"// mrclutch export of {p.name}: the r-z section (x = r, y = z, metres) and the air",
        "// box of the tool's FEM; one physical surface per material (docs/handoff.md).",
        'SetFactory("OpenCASCADE");',
        f"h = {size:.10g};  // element size in the clutch, m",
        f"hbox = {BOX_SIZE:.10g};  // element size at the box, m",
    ]
    for k, lab in enumerate(regions, start=1):
        r0, r1, z0, z1 = lab.bounds
        L.append(f"Rectangle({k}) = {{{r0:.10g}, {z0:.10g}, 0, {r1 - r0:.10g}, {z1 - z0:.10g}}};"
                 f"  // {lab.name}")  # fmt: skip
    nb = len(regions) + 1
    L += [f"Rectangle({nb}) = {{0, {zb0:.10g}, 0, {rb:.10g}, {zb1 - zb0:.10g}}};  // air box",
          f"BooleanFragments{{ Surface{{{nb}}}; Delete; }}{{ Surface{{1:{nb - 1}}}; Delete; }}",
          "eps = 1e-6;  // m: below any region's size (>= 10 µm), above OCC's tolerance",
          "air() = Surface{:};"]  # fmt: skip
    by_mat: dict[str, list[str]] = {}
    for k, lab in enumerate(regions, start=1):
        r0, r1, z0, z1 = lab.bounds
        L.append(f"s{k}() = Surface In BoundingBox{{{r0:.10g} - eps, {z0:.10g} - eps, -eps, "
                 f"{r1:.10g} + eps, {z1:.10g} + eps, eps}};  // {lab.name}")  # fmt: skip
        L.append(f"air() -= s{k}();")
        by_mat.setdefault(lab.material, []).append(f"s{k}()")
    L.append('Physical Surface("air", 1) = air();')
    for j, (mat, ss) in enumerate(sorted(by_mat.items()), start=2):
        L.append(f'Physical Surface("{mat}", {j}) = {{{", ".join(ss)}}};')
    L += [
        'Physical Curve("axis_and_box", 100) = CombinedBoundary{ Surface{:}; };',
        "MeshSize{ PointsOf{ Surface{:}; } } = hbox;",
        f"MeshSize{{ PointsOf{{ Surface{{{', '.join(f's{k}()' for k in range(1, nb))}}}; }} }}"
        " = h;",
        "Mesh.MeshSizeFromCurvature = 0;",
    ]
    return "\n".join(L) + "\n"


def _nu_list(m: BHCurve) -> str:
    """ν samples as the flat list {|B|², ν, …} of GetDP's InterpolationLinear."""
    b_end = m.b_table[-1] + NU_PAST_T
    b = np.linspace(0.0, b_end, math.ceil(b_end / NU_STEP_T) + 1)
    b = np.append(b, [b_end + 10.0, b_end + 1000.0])  # the μ0 line, far out
    h = m.h_of_b(b)
    nu = np.empty_like(b)
    nu[1:] = h[1:] / b[1:]
    nu[0] = float(m.dh_db(np.array([0.0]))[0])  # ν(0) = dH/dB at the origin
    return ", ".join(f"{x:.10g}" for pair in zip(b**2, nu, strict=True) for x in pair)


def write_pro(p: Problem) -> str:
    """The GetDP ``.pro`` of ``p`` (module docstring). ``current_A`` is a constant that
    ``getdp -setnumber current_A I`` overrides; ``Gaps`` prints B along the gaps' lines."""
    nonlinear = [n for n in p.materials if isinstance(p.magnetic[n], BHCurve)]
    linear = [n for n in p.materials if n not in nonlinear]
    tags = {"air": 1} | {n: j for j, n in enumerate(sorted(set(p.materials) - {"air"}), 2)}
    G = ["Group {"]
    G += [f"  {_ident(n)} = Region[{tags[n]}];" for n in p.materials]
    G += [
        f"  Coil = Region[{tags['coil']}];",
        f"  Domain_NL = Region[{{{', '.join(_ident(n) for n in nonlinear)}}}];",
        f"  Domain_L = Region[{{{', '.join(_ident(n) for n in linear)}}}];",
        "  Domain = Region[{Domain_NL, Domain_L}];",
        "  Boundary = Region[100];",
        "}",
    ]
    F = [
        "Function {",
        "  mu0 = 4e-7 * Pi;",
        f"  DefineConstant[ current_A = {p.current:.10g} ];",
        f"  js[] = {p.turns} * current_A / {p.coil_area:.10g};  // A/m², smeared over the coil",
    ]
    for n in linear:
        F.append(f"  nu[{_ident(n)}] = 1 / ({p.magnetic[n].mu_r:.10g} * mu0);")  # type: ignore[union-attr]
    for n in nonlinear:
        F += [f"  L_{_ident(n)} = {{{_nu_list(p.magnetic[n])}}};",  # type: ignore[arg-type]
              f"  nu[{_ident(n)}] = InterpolationLinear[SquNorm[$1]]{{List[L_{_ident(n)}]}};",
              f"  dnudb2[{_ident(n)}] = "
              f"dInterpolationLinear[SquNorm[$1]]{{List[L_{_ident(n)}]}};"]  # fmt: skip
    F.append("}")
    ops = []
    for k, (r, z0, z1, n) in enumerate(p.gap_lines):
        dz = (z1 - z0) / n
        a, b = z0 + 0.5 * dz, z1 - 0.5 * dz
        ops.append(f"      Print[ b, OnLine {{ {{{r:.12g}, {a:.12g}, 0}} "
                   f"{{{r:.12g}, {b:.12g}, 0}} }}"
                   f" {{{max(n - 1, 1)}}}, Format SimpleTable, File \"gap{k}.txt\" ];")  # fmt: skip
    body = f"""
Constraint {{
  {{ Name Psi0; Case {{ {{ Region Boundary; Value 0.; }} }} }}
}}
FunctionSpace {{
  {{ Name H_psi; Type Form0;
    BasisFunction {{ {{ Name sn; NameOfCoef psin; Function BF_Node; Support Domain;
                       Entity NodesOf[All]; }} }}
    Constraint {{ {{ NameOfCoef psin; EntityType NodesOf; NameOfConstraint Psi0; }} }}
  }}
}}
Jacobian {{ {{ Name Vol; Case {{ {{ Region All; Jacobian Vol; }} }} }} }}
Integration {{ {{ Name Gauss6; Case {{ {{ Type Gauss; Case {{
  {{ GeoElement Triangle; NumberOfPoints 6; }}
  {{ GeoElement Line; NumberOfPoints 4; }} }} }} }} }} }}
// psi = r*A_phi on the r-z plane: the tool's weak form (magnetics.fem)
Formulation {{
  {{ Name MagSta_psi; Type FemEquation;
    Quantity {{ {{ Name psi; Type Local; NameOfSpace H_psi; }} }}
    Equation {{
      Galerkin {{ [ nu[{{d psi}} / X[]] / X[] * Dof{{d psi}}, {{d psi}} ];
                 In Domain; Jacobian Vol; Integration Gauss6; }}
      Galerkin {{ JacNL [ 2 * dnudb2[{{d psi}} / X[]] / X[]^3 * SquDyadicProduct[{{d psi}}]
                         * Dof{{d psi}}, {{d psi}} ];
                 In Domain_NL; Jacobian Vol; Integration Gauss6; }}
      Galerkin {{ [ -js[], {{psi}} ]; In Coil; Jacobian Vol; Integration Gauss6; }}
    }}
  }}
}}
Resolution {{
  {{ Name MagSta; System {{ {{ Name S; NameOfFormulation MagSta_psi; }} }}
    Operation {{
      InitSolution[S];
      IterativeLoop[{MAX_ITERATIONS}, {TOLERANCE:g}, 1] {{ GenerateJac[S]; SolveJac[S]; }}
      SaveSolution[S];
    }}
  }}
}}
PostProcessing {{
  {{ Name Mag; NameOfFormulation MagSta_psi;
    Quantity {{
      {{ Name psi; Value {{ Local {{ [ {{psi}} ]; In Domain; Jacobian Vol; }} }} }}
      {{ Name b; Value {{ Local {{ [ Vector[ -CompY[{{d psi}}], CompX[{{d psi}}], 0 ] / X[] ];
                                 In Domain; Jacobian Vol; }} }} }}
    }}
  }}
}}
PostOperation {{
  {{ Name Gaps; NameOfPostProcessing Mag;
    Operation {{
{chr(10).join(ops)}
    }}
  }}
  {{ Name Map; NameOfPostProcessing Mag;
    Operation {{ Print[ b, OnElementsOf Domain, File "b.pos" ]; }}
  }}
}}
"""
    head = (f"// mrclutch export of {p.name}: GetDP, axisymmetric non-linear magnetostatics in\n"
            f"// psi = r*A_phi (docs/handoff.md). gmsh {p.name}.geo -2; then\n"
            f"// getdp {p.name}.pro -msh {p.name}.msh -setnumber current_A 7 -solve MagSta"
            " -pos Gaps\n")  # fmt: skip
    return head + "\n".join(G) + "\n" + "\n".join(F) + body


def tools() -> tuple[str | None, str | None]:
    """Paths of the installed ``gmsh`` and ``getdp`` (None where missing)."""
    return shutil.which("gmsh"), shutil.which("getdp")


def _run(cmd: list[str], cwd: Path, what: str) -> None:
    res = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600)
    if res.returncode != 0 or "Error" in res.stderr:
        tail = (res.stderr or res.stdout).strip().splitlines()[-3:]
        raise RuntimeError(f"{what} failed (exit {res.returncode}): {' | '.join(tail)}")


def _profile(path: Path) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(z, |B|, |B_r|) of a GetDP SimpleTable of b along a line (x y z bx by bz)."""
    rows = np.loadtxt(path, ndmin=2)
    z, br, bz = rows[:, -5], rows[:, -3], rows[:, -2]
    return z, np.hypot(br, bz), np.abs(br)


def solve_getdp(section: Section, currents: Sequence[float], size: float = DEFAULT_SIZE,
                materials: Mapping[str, Magnetic] | None = None,
                workdir: str | Path | None = None) -> FloatArray:  # fmt: skip
    """Yield torque per gap (C, K) of ``section`` at each current (A), from GetDP's field
    on Gmsh's mesh of element ``size`` (m), read the tool's way (module docstring).
    RuntimeError when gmsh or getdp is missing or fails."""
    gmsh, getdp = tools()
    if gmsh is None or getdp is None:
        raise RuntimeError("gmsh and getdp must be installed (Debian: apt-get install gmsh getdp)")
    cur = [float(c) for c in currents]
    if not cur:
        raise ParameterError("currents: give at least one")
    p = problem(section, cur[0], "clutch", materials)
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        d = Path(tmp)
        (d / "clutch.geo").write_text(write_geo(p, size), encoding="utf-8")
        (d / "clutch.pro").write_text(write_pro(p), encoding="utf-8")
        _run([gmsh, "clutch.geo", "-2", "-format", "msh22", "-o", "clutch.msh", "-v", "2"], d,
             "gmsh")  # fmt: skip
        out = np.empty((len(cur), len(p.gap_lines)))
        for c, i in enumerate(cur):
            _run([getdp, "clutch.pro", "-msh", "clutch.msh", "-setnumber", "current_A", repr(i),
                  "-solve", "MagSta", "-pos", "Gaps", "-v", "2"], d, "getdp")  # fmt: skip
            profiles = []
            for k, (_r, z0, z1, n) in enumerate(p.gap_lines):
                z, b, br = _profile(d / f"gap{k}.txt")
                if z.size != n:
                    raise RuntimeError(f"getdp: gap{k}: {z.size} points printed, {n} expected")
                profiles.append((z, np.full(n, (z1 - z0) / n), b, br))
            sol = FEMSolution(i, *(np.empty(0),) * 6, (), np.empty(0, np.int64), 0, 0.0,
                              np.array([r for r, *_ in p.gap_lines]), tuple(profiles))  # fmt: skip
            out[c] = sol.gap_yield_torque(p.fluid, materials)
    return out
