"""The r–z section as a planar straight-line graph: the shape every hand-off file draws.

FEMM, Gmsh and a DXF drawing all want the section as nodes joined by segments, with no
node lying inside another segment (a "T-junction" would leave two faces unjoined), and
one label point inside each face. The section's rectangles (``geometry.section``) tile the
clutch and share edges only in part (a drum's edge runs past the gap ends beside it), so
every rectangle edge is split at every rectangle corner lying on it; the pieces shared by
two rectangles then coincide and are kept once.

With a ``box`` (r_max, z_min, z_max) the graph also has the outer air: the box's edges,
and one label in each connected piece of air (the cells of the tensor grid of all edges
that no region covers, joined across shared sides) — a hand-off solver needs a block in
each. Every region keeps its own label, so a region of one material beside another of
the same material stays its own face (the files name each region).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

from geometry.section import Section

_ROUND = 12  # m to 1e-12 m: edges computed by different sums of the same fields meet


@dataclass(frozen=True)
class Label:
    """A point inside one face and what the face is: a region's name, part, material and
    role (``geometry.regions``), or "air" (name ``air<k>``, part and material "air")."""

    name: str
    part: str
    material: str
    role: str
    r: float  # m
    z: float  # m
    #: the face's bounding rectangle (r0, r1, z0, z1), m (a region's own rectangle)
    bounds: tuple[float, float, float, float]


@dataclass(frozen=True)
class Outline:
    """Nodes (r, z) in metres, segments as index pairs (i < j), one label per face."""

    nodes: tuple[tuple[float, float], ...]
    segments: tuple[tuple[int, int], ...]
    labels: tuple[Label, ...]
    #: (r_max, z_min, z_max) of the air box, m, or None without one
    box: tuple[float, float, float] | None = None

    def on_box(self, seg: tuple[int, int]) -> bool:
        """Whether segment ``seg`` lies on the box's outer edges (not the axis r = 0)."""
        if self.box is None:
            return False
        rb, z0, z1 = self.box
        (ra, za), (rc, zc) = self.nodes[seg[0]], self.nodes[seg[1]]
        on_r = abs(ra - rb) < 1e-12 and abs(rc - rb) < 1e-12
        on_z = any(abs(za - z) < 1e-12 and abs(zc - z) < 1e-12 for z in (z0, z1))
        return on_r or on_z


def _rects(section: Section, box: tuple[float, float, float] | None
           ) -> list[tuple[float, float, float, float]]:  # fmt: skip
    out = [tuple(round(x, _ROUND) for x in (g.r0, g.r1, g.z0, g.z1)) for g in section.regions]
    if box is not None:
        rb, z0, z1 = box
        out.append((0.0, round(rb, _ROUND), round(z0, _ROUND), round(z1, _ROUND)))
    return out  # type: ignore[return-value]


def section_outline(section: Section, box: tuple[float, float, float] | None = None) -> Outline:
    """The planar straight-line graph of ``section`` (module docstring), with the air box
    ``box`` = (r_max, z_min, z_max) in metres when given (it must contain the section)."""
    rects = _rects(section, box)
    if box is not None:
        rb, zb0, zb1 = box
        if not (rb > section.r_max and zb0 < section.z_min and zb1 > section.z_max):
            raise ValueError(f"box {box!r} does not contain the section")
    corners = sorted({(r, z) for r0, r1, z0, z1 in rects for r in (r0, r1) for z in (z0, z1)})
    index = {p: i for i, p in enumerate(corners)}
    by_z: dict[float, list[float]] = {}
    by_r: dict[float, list[float]] = {}
    for r, z in corners:
        by_z.setdefault(z, []).append(r)
        by_r.setdefault(r, []).append(z)
    segs: set[tuple[int, int]] = set()
    for r0, r1, z0, z1 in rects:
        for z in (z0, z1):  # horizontal edges, split at every corner on them
            pts = sorted(r for r in by_z[z] if r0 <= r <= r1)
            segs.update(tuple(sorted((index[(a, z)], index[(b, z)])))
                        for a, b in itertools.pairwise(pts))  # fmt: skip
        for r in (r0, r1):  # vertical edges
            pts = sorted(z for z in by_r[r] if z0 <= z <= z1)
            segs.update(tuple(sorted((index[(r, a)], index[(r, b)])))
                        for a, b in itertools.pairwise(pts))  # fmt: skip
    labels = [
        Label(
            g.name,
            g.part,
            g.material,
            g.role,
            0.5 * (g.r0 + g.r1),
            0.5 * (g.z0 + g.z1),
            (g.r0, g.r1, g.z0, g.z1),
        )
        for g in section.regions
    ]
    if box is not None:
        labels += _air_labels(rects[:-1], rects[-1])
    return Outline(tuple(corners), tuple(sorted(segs)), tuple(labels), box)


def _air_labels(regions: list[tuple[float, float, float, float]],
                box: tuple[float, float, float, float]) -> list[Label]:  # fmt: skip
    """One label in each connected piece of the box not covered by a region."""
    rs = sorted({x for q in [*regions, box] for x in q[:2]})
    zs = sorted({x for q in [*regions, box] for x in q[2:]})
    nr, nz = len(rs) - 1, len(zs) - 1
    free = [[True] * nz for _ in range(nr)]
    for i in range(nr):
        rc = 0.5 * (rs[i] + rs[i + 1])
        for j in range(nz):
            zc = 0.5 * (zs[j] + zs[j + 1])
            free[i][j] = not any(r0 < rc < r1 and z0 < zc < z1 for r0, r1, z0, z1 in regions)
    seen = [[False] * nz for _ in range(nr)]
    out: list[Label] = []
    for i0, j0 in itertools.product(range(nr), range(nz)):
        if not free[i0][j0] or seen[i0][j0]:
            continue
        stack, cells = [(i0, j0)], []
        seen[i0][j0] = True
        while stack:  # flood fill over free cells sharing a side
            i, j = stack.pop()
            cells.append((i, j))
            for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                if 0 <= a < nr and 0 <= b < nz and free[a][b] and not seen[a][b]:
                    seen[a][b] = True
                    stack.append((a, b))
        # the label in the piece's largest cell (away from its edges)
        i, j = max(cells, key=lambda c: (rs[c[0] + 1] - rs[c[0]]) * (zs[c[1] + 1] - zs[c[1]]))
        bounds = (min(rs[c[0]] for c in cells), max(rs[c[0] + 1] for c in cells),
                  min(zs[c[1]] for c in cells), max(zs[c[1] + 1] for c in cells))  # fmt: skip
        out.append(Label(f"air{len(out)}", "air", "air", "air", 0.5 * (rs[i] + rs[i + 1]),
                         0.5 * (zs[j] + zs[j + 1]), bounds))  # fmt: skip
    return out
