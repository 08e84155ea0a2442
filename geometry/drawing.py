"""The r–z section for the machine shop: a DXF (ezdxf) with one layer per part and
material, and a dimensioned 2-D drawing (SVG, matplotlib) of the drums, gaps and housing
with the process tolerances.

DXF: every region of the section (``geometry.outline``, so shared edges are drawn once per
face) as a closed LWPOLYLINE on layer ``<part>-<material>`` (e.g. ``rotor-steel_1018``),
in millimetres, x = r, y = z; the axis on layer ``AXIS``. ezdxf is imported only when a
DXF is written.

Drawing: the half-section with the diameters of every drum wall, the core and the shell,
the gaps' widths and the zones' and band's lengths, each diameter with the tolerance band
± T/2 and a note of the runout R (TIR) a design's ``[process]`` states (mrclutch.process).
"""

from __future__ import annotations

import io

from geometry.materials import COLOUR
from geometry.section import Section


def layer_name(part: str, material: str) -> str:
    """The DXF layer of a region: ``<part>-<material>``."""
    return f"{part}-{material}"


def section_dxf(section: Section) -> str:
    """The DXF text (R2010) of ``section`` (module docstring)."""
    import ezdxf

    doc = ezdxf.new("R2010", setup=False)
    doc.units = ezdxf.units.MM
    msp = doc.modelspace()
    for g in section.regions:
        name = layer_name(g.part, g.material)
        if name not in doc.layers:
            rgb = COLOUR.get(g.material, (0.5, 0.5, 0.5))
            layer = doc.layers.add(name)
            layer.rgb = tuple(round(255 * c) for c in rgb)
        pts = [(g.r0, g.z0), (g.r1, g.z0), (g.r1, g.z1), (g.r0, g.z1)]
        msp.add_lwpolyline(
            [(r * 1e3, z * 1e3) for r, z in pts], close=True, dxfattribs={"layer": name}
        )
    doc.layers.add("AXIS")
    msp.add_line(
        (0.0, section.z_min * 1e3 - 2), (0.0, section.z_max * 1e3 + 2), dxfattribs={"layer": "AXIS"}
    )
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue()


def section_drawing(section: Section, path: str, tolerance: float, runout: float) -> None:
    """A dimensioned SVG of ``section`` into the temporary file ``path`` (the caller's
    output layer renames it); ``tolerance`` (IT band T) and ``runout`` (TIR R) in m."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    mm = 1e3
    fig, ax = plt.subplots(figsize=(11, 8.5))
    for g in section.regions:
        colour = COLOUR.get(g.material, (0.5, 0.5, 0.5))
        ax.add_patch(
            Rectangle(
                (g.r0 * mm, g.z0 * mm),
                (g.r1 - g.r0) * mm,
                (g.z1 - g.z0) * mm,
                facecolor=colour,
                edgecolor="k",
                linewidth=0.4,
                alpha=0.35 if g.role == "fluid" else 0.8,
            )
        )
    ax.axvline(0.0, color="k", linestyle="-.", linewidth=0.6)
    tol = f"±{tolerance * mm / 2:.3g}"
    top = section.z_max * mm
    # diameters of every radial station of the stack, the core and the shell, above
    radii = sorted({round(x, 12) for gp in section.gaps for x in (gp.r_inner, gp.r_outer)})
    radii.append(section.r_max)
    for k, r in enumerate(radii):
        y = top + 2.0 + 1.6 * k
        ax.annotate("", (0.0, y), (r * mm, y), arrowprops={"arrowstyle": "<->", "lw": 0.5})
        ax.text(r * mm + 0.3, y, f"Ø{2 * r * mm:.3f} {tol}", va="center", fontsize=6)
    # gap widths, at the gaps' mid-height
    for gp in section.gaps:
        zm = 0.5 * (gp.z0 + gp.z1) * mm
        ax.annotate(
            "",
            (gp.r_inner * mm, zm),
            (gp.r_outer * mm, zm),
            arrowprops={"arrowstyle": "<->", "lw": 0.5},
        )
        ax.text(
            gp.r_mean * mm, zm + 0.4, f"{gp.width * mm:.3f}", ha="center", fontsize=5, rotation=90
        )
    # zones and band along z, left of the axis
    x = -2.0
    edges = [section.zones[0].z0, section.zones[0].z1, section.zones[1].z0, section.zones[1].z1]
    for a, b, what in zip(edges[:-1], edges[1:], ("zone A", "band", "zone B"), strict=True):
        ax.annotate("", (x, a * mm), (x, b * mm), arrowprops={"arrowstyle": "<->", "lw": 0.5})
        ax.text(
            x - 0.4,
            0.5 * (a + b) * mm,
            f"{what} {(b - a) * mm:.3f}",
            ha="right",
            va="center",
            fontsize=6,
        )
    length = (section.z_max - section.z_min) * mm
    ax.text(
        0.0,
        section.z_min * mm - 3.0,
        f"lengths in mm; diameters {tol} mm (tolerance band {tolerance * mm:.3g} mm); "
        f"drum runout ≤ {runout * mm:.3g} mm TIR; overall length {length:.3f}; "
        "half section, axis at r = 0",
        fontsize=7,
    )
    ax.set_aspect("equal")
    ax.set_xlim(-12.0, section.r_max * mm + 14.0)
    ax.set_ylim(section.z_min * mm - 5.0, top + 4.0 + 1.6 * len(radii))
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("z (mm)")
    with plt.rc_context({"svg.fonttype": "none"}):  # text stays text: searchable, editable
        fig.savefig(path, format="svg")
    plt.close(fig)
