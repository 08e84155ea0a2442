"""Issue 40: the Pareto search's shortcuts give the numbers of the long way, row for row.
The limits' transient runs once over a batch of every drum count and fluid, not once per
region table; the front's stability is read from the search's own rows, not from the
designs evaluated a second time; the members' rows are those of their worst-case check, not
evaluated a third time; the search's count of limits is taken without evaluating a design."""

from dataclasses import replace

import numpy as np

from mrclutch.design import design_preset
from mrclutch.optimize import Constraints, evaluate_rows, limit_columns, pareto, robust_verdict
from mrclutch.optimize.pareto import _SearchRows, _stable_K
from mrclutch.pipeline import evaluate_batch

PAPER = design_preset("paper")
KEYS = ("gap", "drum_thickness", "drum_inner_diameter", "zone_length", "n_drums")


def _mixed(n: int = 12) -> dict[str, np.ndarray]:
    """n designs over drum counts 1–4 and two fluids, the first row refused (gap 0.1 µm)."""
    rng = np.random.default_rng(7)
    f = {k: np.full(n, getattr(PAPER.clutch, k)) for k in KEYS}
    f["gap"] = rng.uniform(0.25e-3, 0.6e-3, n)
    f["gap"][0] = 1e-7
    f["zone_length"] = rng.uniform(4e-3, 9e-3, n)
    f["n_drums"] = np.arange(n) % 4 + 1
    f["fluid"] = np.array(["MRF-122EG", "MRF-140CG"], dtype=object)[np.arange(n) // 2 % 2]
    return f


def test_limit_columns_of_a_mixed_batch_are_each_rows_own():
    """Each row's coil power, time at the peak and time at a duty, taken in one batch of
    four drum counts and two fluids (one transient a fluid limit), equals the row taken
    alone, to the bit; a refused row is NaN (its duty time too)."""
    f = _mixed()
    r = evaluate_batch(f, PAPER)
    assert r["valid"][0] == 0 and np.all(r["valid"][1:] == 1)
    duty = 0.8 * float(np.nanmin(r["max_torque_N_m"]))
    cols = limit_columns(f, PAPER, r, duty)
    for j in range(1, len(f["gap"])):
        one = limit_columns({k: v[[j]] for k, v in f.items()}, PAPER,
                            {k: v[[j]] for k, v in r.items()}, duty)  # fmt: skip
        for k in ("coil_power_W", "time_at_peak_s", "time_at_duty_s"):
            assert cols[k][j] == one[k][0], (k, j)
            assert np.isfinite(cols[k][j]) and cols[k][j] > 0, (k, j)
    assert all(np.isnan(cols[k][0]) for k in ("coil_power_W", "time_at_peak_s", "time_at_duty_s"))
    # the two fluids' limits differ, so the rows went through two transients, not one
    assert len({round(t, 9) for t in cols["time_at_peak_s"][1:]}) > 1
    no_duty = limit_columns(f, PAPER, r)
    assert np.all(np.isinf(no_duty["time_at_duty_s"]))  # no duty cycle asked for: inf
    assert np.array_equal(no_duty["time_at_peak_s"], cols["time_at_peak_s"], equal_nan=True)


def test_front_stability_from_the_search_rows_is_a_fresh_evaluations():
    """The largest stable K read from the rows the search already has (``_stable_K``)
    equals ``evaluate_batch(stability=True)``'s column on the same designs evaluated
    again, to the bit, for a subset of rows in any order."""
    f = _mixed()
    cons = replace(Constraints().resolved(PAPER), stable=False)
    r = evaluate_rows(f, PAPER, cons)
    idx = np.array([7, 2, 5, 11, 1])
    sub = {k: v[idx] for k, v in f.items()}
    again = evaluate_batch(sub, PAPER, stability=True)["max_stable_K_N_per_m"]
    got = _stable_K(PAPER, r, idx)
    assert np.all(np.isfinite(got) & (got > 0))
    assert np.array_equal(got, again)


def test_the_search_counts_the_limits_its_rows_give():
    """``_SearchRows`` gives ``Constraints.terms`` the limits, in order, that the search's
    own rows give (``evaluate_rows`` without stability, the worst case's proxy), with each
    optional limit on or off."""
    f = _mixed(4)
    wc = robust_verdict(PAPER)
    for cons in (Constraints(), Constraints(stable=False, passive=False, min_continuous_torque=0,
                 peak_time=0), Constraints(duty_torque=0.1, duty_time=5.0, max_residual_torque=1e-3,
                 max_ripple_force=0.1, min_life=10.0)):  # fmt: skip
        cons = cons.resolved(PAPER)
        for robust in (None, wc):
            r = evaluate_rows(f, PAPER, cons)
            if robust is not None:
                r.update(robust.proxy(f, PAPER, r))
            assert list(cons.terms(_SearchRows())) == list(cons.terms(r))


def test_the_members_rows_are_their_batchs_fresh_evaluation():
    """A small worst-case Pareto run: the members' rows (read from their worst-case check)
    equal the members' designs evaluated again as one batch in the members' order
    (``evaluate_rows`` with stability, the proxy, the full worst case: the long way),
    column for column, to the bit. (Alone, a design's network Newton stops at its own
    tolerance: its torque may differ in the last bits from a batch's.)"""
    wc = robust_verdict(PAPER)
    ps = pareto(PAPER, robust=wc, drum_counts=(2, 3), pop_size=16, generations=3, members=3)
    cons = Constraints().resolved(PAPER)
    assert len(ps.members) == 3 and ps.dropped_robust == 0
    f = {k: np.array([getattr(m.design.clutch, k) for m in ps.members]) for k in KEYS}
    r = evaluate_rows(f, PAPER, cons, stability=True)
    r.update(wc.proxy(f, PAPER, r))
    r.update(wc.full(f, PAPER, r))
    for j, m in enumerate(ps.members):
        assert sorted(r) == sorted(m.row)
        for k, v in r.items():
            assert np.array_equal(float(v[j]), m.row[k], equal_nan=True), k
