"""FEMM 4.2 hand-off: the clutch as an axisymmetric magnetics problem (``.fem``) and the
equivalent Lua script (``.lua``) that draws it, solves it at each current and prints the
yield torque the tool's way. No FEMM is needed to write them; ``read_fem`` reads a
``.fem`` back (the tests check every region, material and B–H point is there).

What is written ([femm42]: the ``.fem`` layout FEMM 4.2 saves, its Lua commands):

- every region of the section (``geometry.outline``: rectangles split where their
  corners meet, so the mesh is conforming), lengths in millimetres, r as FEMM's x;
- one block property per material: μr for the linear ones, for a non-linear one its B–H
  table in FEMM's conventions (B in T then H in A/m per line, the first point the
  origin) plus one point 1 T past the table's end on the tool's slope μ0
  (``magnetics.materials.BHCurve``: the polarisation is saturated), so FEMM's own
  extrapolation and the tool's agree;
- the coil as a series circuit "coil" of ``coil_turns`` turns at the current;
- A = 0 on the same air box as the tool's FEM (``magnetics.fem.grid``: 2× the clutch's
  larger size beyond it on every side but the axis, where FEMM sets A = 0 itself): the
  two solvers then solve one problem, and a difference between them is the solvers';
- mesh size: the tool's reference element size (0.25 mm) or half a region's thinner
  side, whichever is smaller, in every region of the clutch; FEMM's automatic mesh in air.

Yield torque, the tool's way (``magnetics.fem.post.FEMSolution.gap_yield_torque``,
"mid-line"): on each sheared gap's mid-radius line over its wetted length,
T_k = 2π r_k² ∫ τy(|H_r|) dz with τy = τ_max·tanh(6.33e-6·|H|) [carlson] and H_r the
field across the gap (FEMM's H1), summed over the gaps; the script takes the midpoints
of cells of at most 0.05 mm.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from geometry.outline import Outline, section_outline
from geometry.section import Section
from magnetics.fem.grid import DEFAULT_SIZE, _lines
from magnetics.fluid import MRFluid
from magnetics.materials import FLUIDS, BHCurve, Magnetic, magnetic

#: B (T) added past a B–H table's last point on the slope μ0 (module docstring)
EXTENSION_T = 1.0
#: longest step along a gap's mid-line in the torque recipe, m
LINE_STEP = 0.05e-3
MU0 = 4e-7 * math.pi


def fem_box(section: Section) -> tuple[float, float, float]:
    """(r_max, z_min, z_max) of the tool's FEM air box (``magnetics.fem.grid``), m."""
    rs, zs = _lines(section, DEFAULT_SIZE, "uniform")
    return float(rs[-1]), float(zs[0]), float(zs[-1])


def bh_points(m: BHCurve) -> list[tuple[float, float]]:
    """(B T, H A/m) of ``m`` in FEMM's conventions: the origin, the table, and one point
    EXTENSION_T past its end on the slope μ0 (module docstring)."""
    pts = [(0.0, 0.0), *zip(m.b_table, m.h_table, strict=True)]
    b, h = pts[-1]
    return [*pts, (b + EXTENSION_T, h + EXTENSION_T / MU0)]


def _mm(x: float) -> str:
    return f"{x * 1e3:.10g}"


def _num(x: float) -> str:
    return f"{x:.10g}"


def mesh_size(label: Any) -> float:
    """Element size (m) of a face: the reference size or half its thinner side."""
    r0, r1, z0, z1 = label.bounds
    return min(DEFAULT_SIZE, 0.5 * min(r1 - r0, z1 - z0))


@dataclass(frozen=True)
class Problem:
    """What the hand-off files describe: the outline, each face's material, the
    materials' data, the coil and the gaps' torque lines."""

    name: str
    outline: Outline
    materials: tuple[str, ...]  # "air" first, then the section's, sorted
    magnetic: Mapping[str, Magnetic]
    fluid: MRFluid
    turns: int
    current: float
    coil_area: float  # m²
    #: per sheared gap: (mid radius, z0, z1, cells) of its torque line, m
    gap_lines: tuple[tuple[float, float, float, int], ...]


def problem(section: Section, current: float, name: str = "clutch",
            materials: Mapping[str, Magnetic] | None = None) -> Problem:  # fmt: skip
    """The hand-off problem of ``section`` at ``current`` (A)."""
    outline = section_outline(section, fem_box(section))
    names = ("air", *sorted({g.material for g in section.regions}))
    mags = {n: magnetic(n, materials) for n in names}
    fluid_name = section.region(f"gap{section.gaps[0].index}").material
    lines = tuple(
        (g.r_mean, g.z0, g.z1, max(1, math.ceil((g.z1 - g.z0) / LINE_STEP - 1e-9)))
        for g in section.gaps
    )
    return Problem(name, outline, names, mags, FLUIDS[fluid_name], section.clutch.coil_turns,
                   float(current), section.region("coil").area, lines)  # fmt: skip


def write_fem(p: Problem) -> str:
    """The ``.fem`` text of ``p`` (FEMM 4.2's own layout, [femm42])."""
    out = [
        "[Format]      =  4.0",
        "[Frequency]   =  0",
        "[Precision]   =  1e-008",
        "[MinAngle]    =  30",
        "[DoSmartMesh] =  1",
        "[Depth]       =  1",
        "[LengthUnits] =  millimeters",
        "[ProblemType] =  axisymmetric",
        "[Coordinates] =  cartesian",
        "[ACSolver]    =  0",
        "[PrevType]    =  0",
        '[PrevSoln]    =  ""',
        f'[Comment]     =  "mrclutch export of {p.name}: coil {p.turns} turns at '
        f"{p.current:g} A. Yield torque the tool's way: run {p.name}.lua (docs/handoff.md)\"",
        "[PointProps]   = 0",
        "[BdryProps]   = 1",
        "  <BeginBdry>",
        '    <BdryName> = "A=0"',
        "    <BdryType> = 0",
        *(f"    <{k}> = 0" for k in ("A_0", "A_1", "A_2", "Phi", "c0", "c0i", "c1", "c1i",
                                     "Mu_ssd", "Sigma_ssd", "innerangle", "outerangle")),
        "  <EndBdry>",
        f"[BlockProps]  = {len(p.materials)}",
    ]  # fmt: skip
    for name in p.materials:
        m = p.magnetic[name]
        mu = 1.0 if isinstance(m, BHCurve) else m.mu_r
        pts = bh_points(m) if isinstance(m, BHCurve) else []
        out += ["  <BeginBlock>", f'    <BlockName> = "{name}"', f"    <Mu_x> = {_num(mu)}",
                f"    <Mu_y> = {_num(mu)}"]  # fmt: skip
        out += [f"    <{k}> = 0" for k in ("H_c", "H_cAngle", "J_re", "J_im", "Sigma", "d_lam",
                                            "Phi_h", "Phi_hx", "Phi_hy", "LamType")]  # fmt: skip
        out += ["    <LamFill> = 1", "    <NStrands> = 0", "    <WireD> = 0",
                f"    <BHPoints> = {len(pts)}"]  # fmt: skip
        out += [f"      {_num(b)}\t{_num(h)}" for b, h in pts]
        out.append("  <EndBlock>")
    out += ["[CircuitProps]  = 1", "  <BeginCircuit>", '    <CircuitName> = "coil"',
            f"    <TotalAmps_re> = {_num(p.current)}", "    <TotalAmps_im> = 0",
            "    <CircuitType> = 1", "  <EndCircuit>"]  # fmt: skip
    o = p.outline
    out.append(f"[NumPoints] = {len(o.nodes)}")
    out += [f"{_mm(r)}\t{_mm(z)}\t0\t0" for r, z in o.nodes]
    out.append(f"[NumSegments] = {len(o.segments)}")
    out += [f"{a}\t{b}\t-1\t{1 if o.on_box((a, b)) else 0}\t0\t0" for a, b in o.segments]
    out += ["[NumArcSegments] = 0", "[NumHoles] = 0", f"[NumBlockLabels] = {len(o.labels)}"]
    for lab in o.labels:
        block = p.materials.index(lab.material) + 1
        size = "-1" if lab.role == "air" else _mm(mesh_size(lab))
        coil = lab.role == "coil"
        out.append(f"{_mm(lab.r)}\t{_mm(lab.z)}\t{block}\t{size}\t{1 if coil else 0}\t0\t0\t"
                   f"{p.turns if coil else 1}\t0")  # fmt: skip
    return "\n".join(out) + "\n"


def _lua_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def write_lua(p: Problem, currents: Sequence[float] | None = None) -> str:
    """The FEMM 4.2 Lua script of ``p`` (Lua 4.0, FEMM's dialect): draw, assign, save
    ``<name>.fem``, then for each current solve and print the yield torque per gap and in
    all, the tool's way (module docstring)."""
    cur = [p.current] if currents is None else [float(c) for c in currents]
    o = p.outline
    L = [
        f"-- mrclutch export of {p.name}: FEMM 4.2 axisymmetric magnetostatics, lengths in mm.",
        "-- Open in FEMM (File > Open Lua Script). It draws the section, assigns the materials",
        "-- and the coil, saves the .fem beside FEMM's working folder, then solves at each",
        "-- current below and prints the yield torque the tool's way (docs/handoff.md):",
        "-- T = sum over gaps of 2*pi*r^2 * integral of tau_y(|H_r|) dz on the gap's mid-line.",
        f"currents = {{{', '.join(_num(c) for c in cur)}}}",
        f"ncurrents = {len(cur)}",
        "newdocument(0)",
        'mi_probdef(0, "millimeters", "axi", 1e-8, 0, 30)',
    ]
    for name in p.materials:
        m = p.magnetic[name]
        mu = 1.0 if isinstance(m, BHCurve) else m.mu_r
        L.append(f"mi_addmaterial({_lua_str(name)}, {_num(mu)}, {_num(mu)}, 0, 0, 0, 0, 0, 1, "
                 "0, 0, 0, 0, 0)")  # fmt: skip
        if isinstance(m, BHCurve):
            L += [f"mi_addbhpoint({_lua_str(name)}, {_num(b)}, {_num(h)})" for b, h in bh_points(m)]
    L += [f'mi_addcircprop("coil", {_num(cur[0])}, 1)',
          'mi_addboundprop("A=0", 0, 0, 0, 0, 0, 0, 0, 0, 0)']  # fmt: skip
    L += [f"mi_addnode({_mm(r)}, {_mm(z)})" for r, z in o.nodes]
    for a, b in o.segments:
        (ra, za), (rb, zb) = o.nodes[a], o.nodes[b]
        L.append(f"mi_addsegment({_mm(ra)}, {_mm(za)}, {_mm(rb)}, {_mm(zb)})")
        if o.on_box((a, b)):
            L += [f"mi_selectsegment({_mm(0.5 * (ra + rb))}, {_mm(0.5 * (za + zb))})",
                  'mi_setsegmentprop("A=0", 0, 1, 0, 0)', "mi_clearselected()"]  # fmt: skip
    for lab in o.labels:
        coil = lab.role == "coil"
        auto, size = (1, "0") if lab.role == "air" else (0, _mm(mesh_size(lab)))
        L += [f"mi_addblocklabel({_mm(lab.r)}, {_mm(lab.z)})",
              f"mi_selectlabel({_mm(lab.r)}, {_mm(lab.z)})",
              f"mi_setblockprop({_lua_str(lab.material)}, {auto}, {size}, "
              f"{_lua_str('coil' if coil else '<None>')}, 0, 0, {p.turns if coil else 1})",
              "mi_clearselected()"]  # fmt: skip
    gaps = ", ".join(f"{{{_mm(r)}, {_mm(z0)}, {_mm(z1)}, {n}}}" for r, z0, z1, n in p.gap_lines)
    L += [
        f"mi_saveas({_lua_str(p.name + '.fem')})",
        f"-- gaps: {{mid radius mm, z0 mm, z1 mm, cells}}; {p.fluid.name}: Carlson's law [carlson]",
        f"gaps = {{{gaps}}}",
        f"ngaps = {len(p.gap_lines)}",
        f"taumax = {_num(p.fluid.tau_y_max)}",
        "kh = 6.33e-6",
        "pi = 3.14159265358979",
        "for c = 1, ncurrents do",
        '  mi_modifycircprop("coil", 1, currents[c])',
        "  mi_analyze(1)",
        "  mi_loadsolution()",
        "  total = 0",
        "  for g = 1, ngaps do",
        "    r = gaps[g][1]",
        "    z0 = gaps[g][2]",
        "    dz = (gaps[g][3] - z0) / gaps[g][4]",
        "    s = 0",
        "    for j = 1, gaps[g][4] do",
        "      hr, hz = mo_geth(r, z0 + (j - 0.5) * dz)",
        "      s = s + taumax * (1 - 2 / (exp(2 * kh * abs(hr)) + 1)) * dz",
        "    end",
        "    t = 2 * pi * r * r * s * 1e-9",
        "    total = total + t",
        '    print("I = " .. currents[c] .. " A, gap " .. (g - 1) .. ": " .. t .. " N*m")',
        "  end",
        '  print("I = " .. currents[c] .. " A: yield torque " .. total .. " N*m")',
        "  mo_close()",
        "end",
    ]
    return "\n".join(L) + "\n"


# ---- reading a .fem back -------------------------------------------------------------------
@dataclass(frozen=True)
class FemFile:
    """What ``read_fem`` found: header keys (lower case), boundary, block and circuit
    properties (dicts of their keys, lower case; a block's ``bh`` its (B, H) points),
    points (x, y), segments (n0, n1, boundary index), block labels."""

    header: dict[str, str]
    boundaries: list[dict[str, Any]]
    blocks: list[dict[str, Any]]
    circuits: list[dict[str, Any]]
    points: list[tuple[float, float]]
    segments: list[tuple[int, int, int]]
    labels: list[dict[str, Any]]


def _val(v: str) -> Any:
    v = v.strip()
    if v.startswith('"'):
        return v.strip('"')
    try:
        return float(v)
    except ValueError:
        return v


def read_fem(text: str) -> FemFile:
    """Parse a FEMM 4.2 magnetics ``.fem`` (the sections ``write_fem`` writes and FEMM
    saves); ValueError on a count that does not match its section."""
    lines = text.splitlines()
    header: dict[str, str] = {}
    props: dict[str, list[dict[str, Any]]] = {"bdry": [], "block": [], "circuit": []}
    points: list[tuple[float, float]] = []
    segments: list[tuple[int, int, int]] = []
    labels: list[dict[str, Any]] = []
    cur: dict[str, Any] | None = None
    i = 0
    while i < len(lines):
        s = lines[i].strip()
        i += 1
        if not s:
            continue
        low = s.lower()
        if low.startswith("<begin"):
            cur = {"kind": low[6:-1]}
            continue
        if low.startswith("<end"):
            if cur is None or cur["kind"] not in props:
                raise ValueError(f"line {i}: {s} without its <Begin…>")
            props[cur.pop("kind")].append(cur)
            cur = None
            continue
        key, _, val = s.partition("=")
        key = key.strip().lower()
        if key.startswith("<") and cur is not None:
            k = key.strip("<>")
            cur[k] = _val(val)
            if k == "bhpoints":
                n = int(cur[k])
                cur["bh"] = [tuple(float(x) for x in lines[i + j].split()[:2]) for j in range(n)]
                i += n
            continue
        if not key.startswith("["):
            raise ValueError(f"line {i}: unexpected {s!r}")
        name = key.strip("[]")
        rows: list[list[str]] = []
        if name in ("numpoints", "numsegments", "numarcsegments", "numholes", "numblocklabels"):
            n = int(val)
            if i + n > len(lines):
                raise ValueError(f"[{name}] = {n}: fewer lines follow")
            rows = [lines[i + j].split() for j in range(n)]
            if any(not r or r[0].startswith("[") for r in rows):
                raise ValueError(f"[{name}] = {n}: fewer lines follow")
            i += n
        if name == "numpoints":
            points = [(float(r[0]), float(r[1])) for r in rows]
        elif name == "numsegments":
            segments = [(int(r[0]), int(r[1]), int(r[3])) for r in rows]
        elif name == "numblocklabels":
            labels = [{"x": float(r[0]), "y": float(r[1]), "block": int(r[2]),
                       "meshsize": float(r[3]), "circuit": int(r[4]), "turns": int(r[7])}
                      for r in rows]  # fmt: skip
        elif name.endswith("props"):
            continue
        elif not name.startswith("num"):
            header[name] = str(_val(val))
    declared = {"bdryprops": "bdry", "blockprops": "block", "circuitprops": "circuit"}
    for key, kind in declared.items():
        n = int(float(_val(text.lower().split(f"[{key}]", 1)[1].split("=", 1)[1].split()[0])))
        if n != len(props[kind]):
            raise ValueError(f"[{key}] = {n}, but {len(props[kind])} found")
    for b in props["block"]:
        if len(b.get("bh", [])) != int(b.get("bhpoints", 0)):
            raise ValueError(f"block {b.get('blockname')}: BHPoints count does not match")
    return FemFile(header, props["bdry"], props["block"], props["circuit"], points, segments,
                   labels)  # fmt: skip
