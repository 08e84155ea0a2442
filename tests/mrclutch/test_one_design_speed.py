"""One design's evaluation without work done twice (issue 40 item 1): each shortcut gives
the answer of the path it replaces, bit for bit (the commands' outputs are byte-identical
before and after; benchmarks/bench_waits.py times them)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from mrclutch import robust
from mrclutch.design import ClutchDesign
from mrclutch.fast_batch import evaluate_batch
from mrclutch.hand_box import hand_box_batch
from mrclutch.haptics.actuator import TABLE2_MR
from mrclutch.robust_search import box_search


@pytest.mark.parametrize("field", ["b1", "delay"])
@pytest.mark.parametrize("scale", [0.3, 1.0, 4.0])
def test_passive_threshold_grid_in_one_call_is_the_scalar_calls(monkeypatch, field, scale):
    """The passive threshold's 13-point grid in one vectorised call (robust._VECTORISED)
    gives the value and sense of 13 scalar calls exactly (a K between the grid's limits,
    so a crossing is root-found from the grid's values)."""
    p = replace(TABLE2_MR, m1=float(TABLE2_MR.m1) * scale, delay=2e-3)
    K = 0.7 * float(robust.max_passive_stiffness(p))
    fast = robust.threshold(p, K, "passive", field)
    monkeypatch.setattr(robust, "_VECTORISED", frozenset())
    slow = robust.threshold(p, K, "passive", field)
    assert fast is not None and slow is not None
    assert fast == slow  # value and sense, to the bit


def test_worst_and_best_in_one_search_are_the_two_searches():
    """The worst and the best search over one box as two designs of one ``box_search``
    (a sense each, ``robust._rows_once``): fn runs once a zoom, their common first grid is
    asked once, and both results equal those of the two searches alone, to the bit."""
    calls = []

    def fn(x):
        calls.append(x.shape)
        return np.sin(3 * x[..., 0]) + x[..., 1] * np.cos(2 * x[..., 2])

    lo, hi = np.array([[0.0, -1.0, 0.5]]), np.array([[2.0, 1.0, 1.5]])
    ref = [box_search(fn, lo, hi, sense=s, points=3, zooms=2) for s in (-1, 1)]
    assert len(calls) == 6
    calls.clear()
    v, a = box_search(robust._rows_once(fn), np.repeat(lo, 2, 0), np.repeat(hi, 2, 0),
                      sense=np.array([-1, 1]), points=3, zooms=2)  # fmt: skip
    assert calls == [(1, 27, 3), (2, 27, 3), (2, 27, 3)]  # the first grid once, then both
    for i, (rv, ra) in enumerate(ref):
        assert v[i] == rv[0] and np.array_equal(a[i], ra[0])
    assert v[0] < v[1]  # the smallest and the largest, not one of them twice


def test_z_width_and_area_rows_are_their_own_in_a_shared_call():
    """``robust_verdicts`` asks the worst's and the best's zoom grids of the Z-width and
    the rendering area in one call: each point's value there equals its value asked alone
    (the paper pair's box, random points), to the bit."""
    from mrclutch.design import design_preset
    from mrclutch.haptics.model import rendering_area
    from mrclutch.haptics.zwidth import zwidth
    from mrclutch.pipeline import evaluate

    ev = evaluate(design_preset("paper"))
    box = robust.robust_box(ev).box
    lo = np.array([box.m1[1][0], box.b1[1][0], box.delay[1][0]])
    hi = np.array([box.m1[2][0], box.b1[2][0], box.delay[2][0]])
    x = lo + (hi - lo) * np.random.default_rng(3).random((2, 27, 3))
    K = float(ev.haptic["K_N_per_m"])
    for fn in (lambda p: zwidth(p)["zwidth_area_N2_s_per_m2"], lambda p: rendering_area(p, K)):
        both = fn(box.params(x[..., 0], x[..., 1], x[..., 2]))
        for i in range(2):
            alone = fn(box.params(x[i : i + 1, :, 0], x[i : i + 1, :, 1], x[i : i + 1, :, 2]))
            assert np.array_equal(both[i : i + 1], alone)


def test_hand_box_nominal_rows_in_the_corners_call_are_their_own():
    """hand_box_batch solves the nominal rows in the corners' fast-path call: the box is
    the one built from a separate nominal call, bit for bit (each row's figures are its
    own), for three designs at once."""
    base = ClutchDesign()
    f = {k: np.full(3, float(v)) for k, v in vars(base.clutch).items()}
    f["gap"] = f["gap"] * np.array([0.8, 1.0, 1.25])
    merged = hand_box_batch(f, base)
    separate = hand_box_batch(f, base, nominal=evaluate_batch(f, base))
    for name in ("m1", "b1", "delay", "K"):
        for a, b in zip(getattr(merged, name), getattr(separate, name), strict=True):
            assert np.array_equal(a, b, equal_nan=True), name
    assert np.array_equal(merged.valid, separate.valid)
    assert math.isfinite(float(merged.K[0][1])) and float(merged.K[2][0]) > float(merged.K[1][0])


def test_the_catalogue_commands_load_no_design_machinery(fresh_python):
    """``haptic`` and ``compare`` on the catalogue (no design) answer from the haptic model
    alone: neither the pipeline, the verdict, the design (its duty, dynamics, network) nor
    the plots are imported (issue 40: 84 project modules before, 27 after); a design's
    ``haptic`` still loads the pipeline."""
    code = (
        "import sys\nfrom mrclutch.cli.main import main\n"
        "for argv in (['haptic'], ['compare'], ['haptic', '--json', '--delay-ms', '2']):\n"
        "    assert main(argv) == 0, argv\n"
        "print(' '.join(sys.modules), file=sys.stderr)\n"
        "assert main(['haptic', '--preset', 'paper']) == 0\n"
        "print('|', ' '.join(sys.modules), file=sys.stderr)"
    )
    catalogue, design = fresh_python(code).stderr.split("|")
    loaded = set(catalogue.split())
    assert "mrclutch.haptics.model" in loaded and "mrclutch.nulls" in loaded  # they ran
    for heavy in ("mrclutch.pipeline", "mrclutch.verdict", "mrclutch.design", "mrclutch.duty",
                  "magnetics.network", "magnetics.dynamics", "mrclutch.cli.plots"):  # fmt: skip
        assert heavy not in loaded, heavy
    assert "mrclutch.pipeline" in set(design.split())


def test_haptic_delay_bound_is_the_design_files():
    """``haptic --delay-ms``'s bound, kept in the command module so the catalogue does not
    load mrclutch.operating, is the design file's MAX_DELAY."""
    from mrclutch.cli.commands.haptic import MAX_DELAY_S
    from mrclutch.operating import MAX_DELAY

    assert MAX_DELAY_S == MAX_DELAY


def test_median_rows_is_numpys_median():
    """The network's continuation order reads each block's median by ``_median_rows``:
    np.median along the rows, bit for bit (odd and even counts, ties)."""
    from magnetics.network.solve import _median_rows

    rng = np.random.default_rng(3)
    for n in range(1, 24):
        a = np.abs(rng.standard_normal((n, 5)) * 10.0 ** rng.uniform(-3, 3, (n, 5)))
        a[: n // 3] = a[0]  # ties
        assert np.array_equal(_median_rows(a), np.median(a, axis=0)), n


def test_single_design_answers_do_not_import_numpy_ma(fresh_python):
    """numpy.ma (≈ 20 ms to import) is loaded by np.median's NaN check and np.unique's
    masked-array check; no interactive command of one design calls either (the network's
    continuation order, the hand scan's polynomial degrees). One process a command: what
    a process runs first decides which network rows run uncompiled (compiled.uncompiled)."""
    for argv in (["evaluate", "--preset", "paper"], ["torque", "--preset", "paper"]):
        code = (
            "import sys\nfrom mrclutch.cli.main import main\n"
            f"assert main({argv!r}) == 0\n"
            "print(' '.join(sys.modules), file=sys.stderr)"
        )
        loaded = set(fresh_python(code).stderr.split())
        assert "magnetics.network.solve" in loaded and "numpy.ma" not in loaded, argv


def test_evaluate_builds_the_feel_and_torque_response_circuit_once(monkeypatch):
    """pipeline.evaluate builds the design's magnetic circuit once, for the clutch figures'
    thermal rating, the torque response and the feel's loop (c83662b: clutch_figures
    takes it, where it built its own): 1 path_from_regions call, not 3; and feel_figures
    and clutch_figures with that circuit handed over equal them building it."""
    from geometry.section import build_section
    from magnetics import circuit, dynamics
    from mrclutch import feel, pipeline
    from mrclutch.clutch import clutch_figures

    calls = []
    real = circuit.path_from_regions

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(circuit, "path_from_regions", counted)
    monkeypatch.setattr(dynamics, "path_from_regions", counted)
    design = ClutchDesign()
    ev = pipeline.evaluate(design)
    assert len(calls) == 1
    f = ev.clutch
    args = (design, f.max_torque, f.yield_torque, f.off_state_torque, 1.0)
    path = circuit.path_from_section(build_section(design.clutch, design.materials))
    assert feel.feel_figures(*args, path) == feel.feel_figures(*args)
    assert clutch_figures(design, path=path) == clutch_figures(design) == f


def test_passivity_batch_is_metrics_batch_passivity_bit_for_bit():
    """The duty's hot holds read a pair's passivity at K by passivity_batch, not the full
    metrics_of (bandwidths, the stability scan): the same passive flags and max passive K
    as metrics_batch, bit for bit, on designs around the paper's pair, K below and above."""
    from mrclutch.haptics.actuator import HapticParams
    from mrclutch.haptics.model import metrics_batch, passivity_batch

    rng = np.random.default_rng(7)
    n = 12
    b1, m1 = float(TABLE2_MR.b1), float(TABLE2_MR.m1)
    p = HapticParams.stack([replace(TABLE2_MR, b1=b1 * s, m1=m1 * t)
                            for s, t in rng.uniform(0.2, 5.0, (n, 2))])  # fmt: skip
    K = rng.uniform(0.2, 3.0, n) * np.asarray(robust.max_passive_stiffness(p))
    full = metrics_batch(p, K)
    got = passivity_batch(p, K)
    assert full["passive"].any() and not full["passive"].all()
    for key in ("passive", "max_passive_K_N_per_m"):
        assert got[key].dtype == full[key].dtype
        assert got[key].tobytes() == full[key].tobytes()


def test_fast_path_without_the_continuous_torque_changes_no_other_column():
    """``evaluate_batch(..., continuous=False)`` (what the hand box asks: it reads no
    continuous torque) leaves that column NaN and every other column as the full call
    gives it, to the bit, on designs of two drum counts and one the validation refuses."""
    base = ClutchDesign()
    f = {k: np.full(4, float(v)) for k, v in vars(base.clutch).items()}
    f["gap"] = f["gap"] * np.array([0.8, 1.0, 1.25, 0.1])
    f["n_drums"] = np.array([1.0, 2.0, 2.0, 1.0])
    full, cut = evaluate_batch(f, base), evaluate_batch(f, base, continuous=False)
    assert list(full) == list(cut)
    assert np.isfinite(full["continuous_torque_N_m"][:3]).all()
    assert np.isnan(cut["continuous_torque_N_m"]).all()
    for k in full:
        if k != "continuous_torque_N_m":
            assert np.array_equal(full[k], cut[k], equal_nan=True), k
