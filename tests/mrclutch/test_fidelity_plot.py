"""The speed-against-accuracy chart's labels: on crowded points and on references stacked
at one time on the error floor, no two label boxes overlap, every label lies inside the
axes (so inside the figure), and a label moved off its marker is joined to it by a line."""

import itertools

import numpy as np
import pytest

from mrclutch.cli.plots.fidelity import ERROR_FLOOR, _crossing, _intersect, fidelity_figure
from mrclutch.fidelity import Row

QUANTITIES = ("inertia", "torque", "stability", "bandwidth", "eddy_delay")


def _crowded() -> list[Row]:
    """18 points packed in 0.1–1 s × 1e-3–1e-1 with labels as long as the real ones, and
    the chart's far corners populated so the axes keep their usual span."""
    rng = np.random.default_rng(3)
    rows = [Row(QUANTITIES[k % 5], f"method number {k}", f"setting {k / 7:.2f} mm",
                float(10 ** rng.uniform(-1, 0)), 1.0, float(10 ** rng.uniform(-3, -1)),
                False) for k in range(18)]  # fmt: skip
    rows += [Row("bandwidth", "lumped", "√(K/(m1+m2))", 4e-6, 1.0, 6e-3, False),
             Row("stability", "padé", "order 4", 1e-3, 1.0, 3e-10, False)]  # fmt: skip
    return rows


def _floor() -> list[Row]:
    """Five references within 10 % of 1 ms on the floor (drawn on top of each other by the
    old rotated labels), two references at 1 s, and a point under the legend (at the
    left, half-way up the log axis) whose label must clear it."""
    rows = [Row(QUANTITIES[k], "exact reference", f"variant {k}", 1e-3 * (1 + 0.025 * k),
                1.0, 0.0, True) for k in range(5)]  # fmt: skip
    rows += [Row("torque", "fem", "size 0.25 mm", 1.0, 1.0, 0.0, True),
             Row("eddy_delay", "harmonic fem", "size 0.25 mm", 1.05, 1.0, 0.0, True),
             Row("torque", "linear circuit", "initial μr", 1e-5, 1.0, 0.4, False),
             Row("stability", "padé", "order 2", 1.2e-5, 1.0, 3e-7, False)]  # fmt: skip
    return rows


#: The paper preset's methods at the times of a loaded 2-core machine: 26 labels, ten of
#: them in 0.5–5 s × 1e-3–1e-1, three pairs of references nearly on top of each other.
PAPER_LIKE = [
    ("inertia", "analytic", "section integrals", 0.000552, 3.22e-15),
    ("inertia", "mesh", "tolerance 0.1 mm", 1.44, 0.0125),
    ("inertia", "mesh", "tolerance 0.03 mm", 1.04, 0.00432),
    ("inertia", "mesh", "tolerance 0.01 mm", 1.84, 0.00155),
    ("inertia", "mesh", "tolerance 0.003 mm", 4.96, 0.000433),
    ("inertia", "brep", "OpenCascade", 0.88, 0),
    ("torque", "linear circuit", "initial μr", 0.0624, 0.396),
    ("torque", "saturating circuit", "B-H curves", 0.0536, 0.00461),
    ("torque", "reluctance network", "ladder from the section", 0.16, 0.0155),
    ("torque", "fem", "size 1 mm", 0.488, 0.0417),
    ("torque", "fem", "size 0.5 mm", 0.6, 0.0121),
    ("torque", "fem", "size 0.35 mm", 1.12, 0.00356),
    ("torque", "fem", "size 0.25 mm", 2.72, 0),
    ("stability", "padé", "order 1", 0.0088, 0.00127),
    ("stability", "padé", "order 2", 0.008, 3.43e-07),
    ("stability", "padé", "order 4", 0.0096, 2.56e-10),
    ("stability", "time stepping", "h = τ/2", 0.0128, 0.000338),
    ("stability", "time stepping", "h = τ/5", 0.08, 5.41e-05),
    ("stability", "time stepping", "h = τ/20", 0.344, 3.38e-06),
    ("stability", "exact delay", "D-subdivision", 0.00328, 0),
    ("bandwidth", "lumped", "√(K/(m1+m2))", 3.12e-05, 0.00594),
    ("bandwidth", "full response", "k_eff zero", 0.0048, 0),
    ("eddy_delay", "diffusion 1-D", "1-D cuts per part", 0.016, 0.0991),
    ("eddy_delay", "harmonic fem", "size 1 mm", 0.672, 0.0427),
    ("eddy_delay", "harmonic fem", "size 0.5 mm", 1.04, 0.0106),
    ("eddy_delay", "harmonic fem", "size 0.25 mm", 2.32, 0),
]


def _paper_like() -> list[Row]:
    return [Row(q, m, s, t, 1.0, e, e == 0) for q, m, s, t, e in PAPER_LIKE]


@pytest.mark.parametrize(
    ("rows", "lines_clear"),
    [(_crowded(), False), (_floor(), True), (_paper_like(), True)],
    ids=["crowded", "floor", "paper-like"],
)
def test_labels_do_not_overlap_and_stay_inside(rows, lines_clear):
    import matplotlib.pyplot as plt
    from matplotlib.text import Text

    fig = fidelity_figure(rows, title="labels")
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        ax = fig.axes[0]
        notes = [t for t in ax.texts if t.get_text()]
        leaders = [t.arrow_patch.get_path().vertices for t in ax.texts if not t.get_text()]
        assert sorted(n.get_text() for n in notes) == sorted(
            f"{r.method} {r.setting}" + (" (ref)" if r.reference else "") for r in rows
        )  # every point labelled once
        boxes = [Text.get_window_extent(n, renderer) for n in notes]
        for (i, a), (j, b) in itertools.combinations(enumerate(boxes), 2):
            assert not a.overlaps(b), (notes[i].get_text(), notes[j].get_text())
        frame, page = ax.get_window_extent(renderer), fig.bbox
        legend = ax.get_legend().get_window_extent(renderer)
        r_marker = 8 / 2 * fig.dpi / 72  # marker radius [px]
        for n, b in zip(notes, boxes, strict=True):
            assert page.x0 <= b.x0 and b.x1 <= page.x1 and page.y0 <= b.y0 and b.y1 <= page.y1
            assert frame.x0 <= b.x0 and b.x1 <= frame.x1 and frame.y0 <= b.y0
            assert b.y1 <= frame.y1, n.get_text()
            assert not b.overlaps(legend), n.get_text()
        # Each label is beside its marker, joined to it by a line, or one line of a
        # stacked list (flush edge, next line) that is.
        dots = [ax.transData.transform(n.xy) for n in notes]
        ok = [max(b.x0 - x, x - b.x1, b.y0 - y, y - b.y1) < 4 * r_marker
              or any(np.hypot(*(v[-1] - (x, y))) < 4 * r_marker for v in leaders)
              for (x, y), b in zip(dots, boxes, strict=True)]  # fmt: skip
        for _ in notes:
            ok = [k or any(ok[m] and (abs(b.y0 - c.y1) < 3 or abs(c.y0 - b.y1) < 3)
                           and min(abs(b.x0 - c.x0), abs(b.x1 - c.x1),
                                   abs(b.x0 + b.x1 - c.x0 - c.x1) / 2) < 1
                           for m, c in enumerate(boxes))
                  for k, b in zip(ok, boxes, strict=True)]  # fmt: skip
        assert all(ok), [n.get_text() for n, k in zip(notes, ok, strict=True) if not k]
        assert len(leaders) < len(notes)  # labels sit beside their markers where they can
        shown = np.array([(b.x0, b.y0, b.x1, b.y1) for b in boxes])
        for v in leaders if lines_clear else ():  # no line through a label but its own end
            seg = np.array([[*v[0], *v[-1]]])
            seg[0, :2] += 2.0 * (v[-1] - v[0]) / np.hypot(*(v[-1] - v[0]))
            assert not _crossing(seg, shown).any()
        floor_y = ax.transData.transform((1.0, ERROR_FLOOR))[1]
        assert frame.y0 < floor_y  # the floor is inside the axes, the references visible
    finally:
        plt.close(fig)


def test_segment_box_crossing():
    box = np.array([(0.0, 0.0, 2.0, 1.0)])
    meets = [
        (-1.0, 0.5, 3.0, 0.5),  # straight through
        (1.0, 0.5, 5.0, 5.0),  # starts inside
        (-1.0, -1.0, 0.5, 0.5),  # enters across a corner
        (1.0, -3.0, 1.0, 3.0),  # vertical, through it
    ]
    misses = [
        (-1.0, 0.5, -0.1, 0.5),  # stops short
        (-1.0, 2.0, 3.0, 1.5),  # passes above
        (3.0, -1.0, 3.0, 2.0),  # vertical, beside it
        (-1.0, 0.0, 0.0, 2.0),  # misses the corner (x = -0.5 at y = 1)
        (2.5, 0.5, 4.0, 0.5),  # horizontal, beyond its right side
    ]
    got = _crossing(np.array(meets + misses), box)[:, 0]
    assert got.tolist() == [True] * len(meets) + [False] * len(misses)


def test_segments_cross_only_properly():
    a = np.array([(0.0, 0.0, 2.0, 2.0)])
    b = np.array(
        [
            (0.0, 2.0, 2.0, 0.0),  # an X
            (0.0, 0.0, 2.0, 0.0),  # shares the start only
            (3.0, 0.0, 3.0, 5.0),  # beyond the end
            (1.0, 0.0, 1.0, 0.5),  # stops below the diagonal
        ]
    )
    assert _intersect(a, b)[0].tolist() == [True, False, False, False]
