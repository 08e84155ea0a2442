"""Import-time work deferred (issue 40): the B–H curves' dense tables are built on first use,
not when the registry is read, and grouping designs by drum count does not pull in
numpy.ma. Both must give what the eager versions gave, to the bit."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

from geometry.regions import by_drum_count
from magnetics.materials import _TABLES, MATERIALS, MU0, BHCurve, pchip

ROOT = Path(__file__).resolve().parents[1]
CURVES = [m for m in MATERIALS.values() if isinstance(m, BHCurve)]


def _fresh(m: BHCurve) -> BHCurve:
    return BHCurve(m.name, m.b_table, m.h_table, m.source)


def test_the_registry_has_curves_to_check() -> None:
    assert len(CURVES) >= 5  # every steel and fluid of geometry/data/materials


@pytest.mark.parametrize("first", sorted(_TABLES))
def test_a_table_built_on_first_use_is_the_same_whichever_is_read_first(first: str) -> None:
    """Reading any one table first builds all eight, bit for bit those of an explicit
    build, and nothing is built before."""
    for m in CURVES:
        lazy, eager = _fresh(m), _fresh(m)
        assert not _TABLES & set(vars(lazy))  # construction builds nothing
        eager._build()
        getattr(lazy, first)
        for name in _TABLES:
            a, b = getattr(lazy, name), getattr(eager, name)
            assert np.array_equal(a, b), (m.name, first, name)


@pytest.mark.parametrize("m", CURVES, ids=lambda m: m.name)
def test_the_lazy_table_is_the_pchip_through_the_origin_and_the_points(m: BHCurve) -> None:
    """The dense table is the monotone PCHIP of H(B) through (0, 0) and the table points on
    4096 samples (exact at both ends), then the μ0 line: what the eager build computed."""
    b, h = np.array(m.b_table), np.array(m.h_table)
    grid = np.linspace(0.0, b[-1], 4096)
    hp, dp = pchip(np.r_[0.0, b], np.r_[0.0, h], grid)
    curve = _fresh(m)
    assert np.array_equal(curve._b[:-1], grid)
    assert np.array_equal(curve._h[:-1], np.maximum.accumulate(hp))
    assert np.array_equal(curve._dhdb[:-1], np.maximum(dp, 0.0))
    assert curve._h[0] == 0.0 and curve._h[-2] == h[-1]
    assert curve._dhdb[-1] == 1.0 / MU0
    # beyond the table H grows with slope 1/μ0 (H = H_last + ΔB/μ0)
    assert curve.h_of_b(b[-1] + 0.5) == pytest.approx(h[-1] + 0.5 / MU0, rel=1e-12)
    # the uniform copy is the same piecewise-linear curve
    bq = np.linspace(0.0, 1.2 * b[-1], 997)
    np.testing.assert_allclose(curve.h_dh(bq.copy())[0], curve.h_of_b(bq), rtol=1e-9, atol=1e-6)


def test_a_curve_copies_and_pickles_before_and_after_its_build() -> None:
    m = CURVES[0]
    for built in (False, True):
        c = _fresh(m)
        if built:
            c._build()
        for other in (copy.deepcopy(c), pickle.loads(pickle.dumps(c))):
            assert other == c
            assert np.array_equal(other.h_of_b([0.3, 1.1, 9.0]), m.h_of_b([0.3, 1.1, 9.0]))


def test_a_missing_attribute_is_still_an_attribute_error() -> None:
    c = _fresh(CURVES[0])
    assert not hasattr(c, "_no_such_table")
    assert not _TABLES & set(vars(c))  # asking for another name builds nothing


def test_a_bad_table_is_still_refused_at_construction() -> None:
    """The checks stay eager: a file's bad table fails where it is read, not at first use."""
    with pytest.raises(ValueError, match="strictly increasing"):
        BHCurve("bad", (1.0, 0.5), (10.0, 20.0), "")


@pytest.mark.parametrize("seed", range(6))
def test_drum_count_groups_equal_np_unique_grouping(seed: int) -> None:
    """The sorted distinct counts without np.unique: the same keys, order and rows as the
    np.unique grouping, on integers and floats, with and without a mask, 1-D and 2-D."""
    rng = np.random.default_rng(seed)
    n = rng.integers(1, 6, size=(40,) if seed % 2 else (5, 8))
    if seed >= 4:
        n = n.astype(float)
    ok = None if seed % 3 == 0 else rng.random(n.shape) < 0.6
    keep = np.ones(n.shape, bool) if ok is None else ok
    want = {int(v): np.flatnonzero(keep & (n == v)) for v in np.unique(n[keep])}
    got = by_drum_count(n, ok)
    assert list(got) == list(want)
    assert all(np.array_equal(got[k], want[k]) for k in want)


def test_drum_count_groups_of_nothing_and_of_one() -> None:
    assert by_drum_count(np.array([], int)) == {}
    assert by_drum_count(np.array([3, 3]), np.array([False, False])) == {}
    (rows,) = by_drum_count(np.array(2)).values()
    assert rows.tolist() == [0]


def test_the_interactive_commands_build_no_table_and_skip_numpy_ma(fresh_python) -> None:
    """``haptic``, ``compare`` and the analytic ``inertia`` read no B–H curve, so they build
    none of the nine tables, and none of them imports numpy.ma (~30 ms) nor the pipeline
    (the catalogue's haptic and compare load the haptic model alone, 8902463)."""
    code = (
        "import sys, io, contextlib\nfrom mrclutch.cli.main import main\n"
        "for argv in (['haptic'], ['compare'],\n"
        "             ['inertia', '--preset', 'paper', '--method', 'analytic']):\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        assert main(argv) == 0, argv\n"
        "from magnetics.materials import MATERIALS, _TABLES\n"
        "built = [n for n, m in MATERIALS.items() if _TABLES & set(vars(m))]\n"
        "print(built, 'numpy.ma' in sys.modules, 'mrclutch.pipeline' in sys.modules)"
    )
    p = fresh_python(code)
    assert p.stdout.split("\n")[-2] == "[] False False"


def test_the_analytic_inertia_loads_no_hand_off_nor_the_viewer(fresh_python) -> None:
    """``inertia`` has its own command module: ``inertia --method analytic`` imports neither
    ``export``'s hand-offs (mrclutch.handoff, and with them the pipeline and the FEM
    hand-off writers) nor ``view``'s renderer, and still answers. Nor the CAD export and a
    CAD file's weighing (geometry.export, mrclutch.weigh, mrclutch.solids), nor the circuit
    and the torque response: a design's amplifier and laminations are their own modules
    (magnetics.amplifier, magnetics.laminations; issue 40 item 1)."""
    code = (
        "import sys, io, contextlib\nfrom mrclutch.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()) as out:\n"
        "    assert main(['inertia', '--preset', 'paper', '--method', 'analytic']) == 0\n"
        "assert 'rotor inertia' in out.getvalue()\n"
        "print(sorted(m for m in ('mrclutch.handoff', 'mrclutch.cli.view', 'mrclutch.pipeline',"
        " 'mrclutch.cli.commands.handoff', 'magnetics.export', 'mrclutch.inertia',"
        " 'geometry.export', 'mrclutch.weigh', 'mrclutch.solids', 'magnetics.circuit',"
        " 'magnetics.dynamics', 'magnetics.eddy_lag') if m in sys.modules))"
    )
    p = fresh_python(code)
    assert p.stdout.strip() == "['mrclutch.inertia']"


def test_haptic_answers_without_numpy_polynomial(fresh_python) -> None:
    """``haptic`` (the MR pair's 1 ms delay) never multiplies a polynomial: it answers without
    numpy.polynomial (~4 ms CPU of its start, issue 40 item 1); ``compare``'s zero-delay motor
    takes its crossings as roots, so the same process loads it there."""
    code = (
        "import sys, io, contextlib\nfrom mrclutch.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()) as out:\n"
        "    assert main(['haptic']) == 0\n"
        "print('numpy.polynomial' in sys.modules)\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['compare']) == 0\n"
        "print('numpy.polynomial' in sys.modules)"
    )
    p = fresh_python(code)
    assert p.stdout.split() == ["False", "True"]
