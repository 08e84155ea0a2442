"""The trade-offs on the fast path: a Pareto set of designs (``pareto``: NSGA-II over the
search box and the drum count, the rendering figure, transparency, continuous torque and
mass its objectives, every limit a constraint), with members spread over the front."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from geometry.materials import SLOTS, MaterialChoice
from geometry.validation import ParameterError, check_choice, check_int
from mrclutch.at_hand import mr_at_hand
from mrclutch.design import ClutchDesign
from mrclutch.optimize.box import range_edges, search_box
from mrclutch.optimize.limits import CONTINUOUS, Constraints, active_limits, evaluate_rows
from mrclutch.robust_search import stable_stiffness_batch

#: The Pareto search's objectives: name → (column, +1 maximised / −1 minimised). The first
#: is the rendering figure (``rendering``: bandwidth or zwidth).
PARETO_OBJECTIVES: dict[str, tuple[str, float]] = {
    "transparency": ("backdrive_force_N", -1.0),
    "continuous": (CONTINUOUS, 1.0),
    "mass": ("clutch_mass_kg", -1.0),
}
#: The rendering figures the Pareto search can weigh.
RENDERING = {"bandwidth": "bandwidth_hz", "zwidth": "zwidth_area_N2_s_per_m2"}
#: How many members ``pareto`` hands back by default (spread over the front).
DEFAULT_MEMBERS = 14
#: NSGA-II's default population and generations: the 10⁴ designs of 100 × 100 in half the
#: generations (issue 40: a generation's fast-path call costs mostly per call, not per
#: design), its front's hypervolume that of 100 × 100 on seeds 0–2 (``python -m
#: benchmarks.bench_optimize --hypervolume`` prints both).
DEFAULT_POP_SIZE = 200
DEFAULT_GENERATIONS = 50
#: At most this many worst-case checks per member asked for (each ≈ 9 ms a design).
MAX_ROBUST = 4


@dataclass(frozen=True)
class Member:
    """One design of the Pareto set, with its fast-path row (evaluate_rows' columns)."""

    design: ClutchDesign
    row: Mapping[str, float]
    active: tuple[str, ...]  # limits within ACTIVE of binding
    edges: tuple[str, ...]  # search-range edges it touches, each as advice


@dataclass(frozen=True)
class ParetoSet:
    members: tuple[Member, ...]  # spread over the front, best rendering first
    objectives: tuple[tuple[str, str, float], ...]  # (name, column, sense)
    front_size: int  # non-dominated designs meeting every limit on the fast path
    evaluations: int
    dropped_unstable: int  # front members unstable at their K (stability checked after)
    dropped_robust: int  # front members failing the worst-case verdict
    box: Mapping[str, tuple[float, float]]
    box_source: Mapping[str, str]
    drum_counts: tuple[int, ...]
    robust: str  # how the verdict was taken ("nominal: …" or "worst case …")
    front: Mapping[str, np.ndarray]  # every front design's objective columns (for plots)


def pareto(
    base: ClutchDesign,
    *,
    rendering: str = "bandwidth",
    constraints: Constraints | None = None,
    bounds: dict[str, tuple[float, float]] | None = None,
    drum_counts: Sequence[int] = (1, 2, 3, 4),
    seed: int = 0,
    pop_size: int = DEFAULT_POP_SIZE,
    generations: int = DEFAULT_GENERATIONS,
    members: int = DEFAULT_MEMBERS,
    robust: Any = None,
    materials: Mapping[str, Sequence[str]] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ParetoSet:
    """The trade-offs on the fast path: NSGA-II (pymoo) over the search box and the drum
    count, maximising the rendering figure and the continuous torque above the drag,
    minimising the backdrive force and the clutch mass, every limit of ``constraints``
    a constraint (passivity in the search; stability, design by design, on the front
    afterwards, as ``optimize``). Every design evaluated is kept; the non-dominated ones
    meeting every limit form the front, of which ``members`` are picked spread over it
    (each objective's best, then the farthest from those picked, objectives normalised).

    ``robust``: None (the nominal verdict) or a callable (fields, base) → columns
    ``ROBUST_COLUMNS`` (worst-case largest stable and passive K over the uncertainty), a
    limit on the front's members.

    ``materials``: categorical axes, a part's material (``geometry.materials.SLOTS``) →
    the names to choose among (e.g. {"fluid": ["MRF-122EG", "MRF-140CG"]}): each one more
    search variable, rounded to an index as the drum count is (issue 33).

    ``progress``: called (generations done, ``generations``) after each generation."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    check_choice("rendering", rendering, tuple(RENDERING))
    check_int("members", members, 1, 200)
    check_int("pop_size", pop_size, 4, 10_000)
    check_int("generations", generations, 1, 10_000)
    cons = (constraints if constraints is not None else Constraints()).resolved(base)
    box, source = search_box(base, bounds)
    counts = tuple(drum_counts)
    for n in counts:
        check_int("drum_counts", n, 1, 20)
    names = list(box)
    cats: dict[str, tuple[str, ...]] = {}
    for slot, choices in (materials or {}).items():
        if slot not in SLOTS or isinstance(choices, str) or not choices:
            raise ParameterError(f"materials: {slot!r}: give a part ({', '.join(SLOTS)}) and "
                                 "a list of material names")  # fmt: skip
        cats[slot] = tuple(getattr(MaterialChoice(**{slot: c}), slot) for c in choices)
    objectives = (("rendering", RENDERING[rendering], 1.0),
                  *((k, col, s) for k, (col, s) in PARETO_OBJECTIVES.items()))  # fmt: skip
    zw = rendering == "zwidth"
    seen: list[tuple[np.ndarray, dict[str, np.ndarray]]] = []

    def fields_of(x: np.ndarray) -> dict[str, np.ndarray]:
        f = {k: x[:, i] for i, k in enumerate(names)}
        idx = np.clip(np.rint(x[:, len(names)]), 0, len(counts) - 1).astype(np.int64)
        f["n_drums"] = np.asarray(counts, dtype=np.int64)[idx]
        for c, (slot, choices) in enumerate(cats.items(), len(names) + 1):
            k = np.clip(np.rint(x[:, c]), 0, len(choices) - 1).astype(np.int64)
            f[slot] = np.asarray(choices, dtype=object)[k]
        return f

    def objective_matrix(r: Mapping[str, np.ndarray]) -> np.ndarray:
        cols = [-s * np.nan_to_num(np.asarray(r[c], dtype=float), nan=np.inf, posinf=np.inf)
                for _, c, s in objectives]  # fmt: skip
        return np.nan_to_num(np.stack(cols, -1), nan=1e30, posinf=1e30, neginf=-1e30)

    class Clutches(Problem):  # type: ignore[misc]
        def __init__(self) -> None:
            terms = len(cons.terms(_SearchRows()))  # the limits, no design evaluated
            super().__init__(
                n_var=len(names) + 1 + len(cats),
                n_obj=len(objectives),
                n_ieq_constr=terms,
                xl=np.array([box[k][0] for k in names] + [-0.5] * (1 + len(cats))),
                xu=np.array(
                    [box[k][1] for k in names]
                    + [len(counts) - 0.5]
                    + [len(c) - 0.5 for c in cats.values()]
                ),
            )

        def _evaluate(self, x: np.ndarray, out: dict, *args: Any, **kwargs: Any) -> None:
            f = fields_of(x)
            r = rows(f)
            seen.append((x.copy(), r))
            out["F"] = objective_matrix(r)
            g = np.stack(list(cons.terms(r).values()), -1)
            out["G"] = np.minimum(g, 1e30)

    def rows(f: Mapping[str, np.ndarray], stability: bool = False,
             c: Constraints = cons) -> dict[str, np.ndarray]:  # fmt: skip
        """evaluate_rows, K and the bandwidth at the worst case's K where ``robust``."""
        r = evaluate_rows(f, base, c, stability=stability, zwidth=zw)
        if robust is not None:
            r.update(robust.proxy(f, base, r))
        return r

    # pymoo calls its callback unchecked: none is passed without a progress report
    tick = {} if progress is None else {"callback": lambda alg: progress(alg.n_gen, generations)}
    minimize(Clutches(), NSGA2(pop_size=pop_size), ("n_gen", generations), seed=seed,
             verbose=False, **tick)  # fmt: skip
    x_all = np.concatenate([x for x, _ in seen])
    r_all = {k: np.concatenate([r[k] for _, r in seen]) for k in seen[0][1]}
    evaluations = len(x_all)
    ok = cons.violation(r_all) == 0
    x_ok = x_all[ok]
    r_ok = {k: v[ok] for k, v in r_all.items()}
    f_all = objective_matrix(r_ok)

    def front_of(x: np.ndarray, f: np.ndarray) -> np.ndarray:
        if not len(f):
            return np.zeros(0, dtype=np.intp)
        nd = NonDominatedSorting().do(f, only_non_dominated_front=True)
        # one of each set of equal designs (the same rounded fields)
        _, first = np.unique(np.round(x[nd], 12), axis=0, return_index=True)
        return np.sort(np.asarray(nd)[first])

    # the front with stability (design by design) checked on its members and the robust
    # verdict on the members picked; failures leave and the front is taken again (designs
    # they dominated may enter) until the picked members all pass
    n_ok = len(x_ok)
    alive = np.ones(n_ok, bool)
    stable_ok = np.full(n_ok, -1)  # 1 passes, 0 fails, -1 not computed yet
    robust_ok = np.full(n_ok, -1)
    checked: list[tuple[np.ndarray, dict[str, np.ndarray]]] = []  # each full check's batch
    drop_s = drop_r = 0
    while True:
        idx = np.flatnonzero(alive)
        nd = idx[front_of(x_ok[idx], f_all[idx])]
        if not nd.size:
            pick = nd
            break
        todo = nd[stable_ok[nd] < 0]
        if todo.size and cons.stable:
            good = r_ok["K_N_per_m"][todo] < _stable_K(base, r_ok, todo) * (1 - 1e-9)
            stable_ok[todo] = good
        elif todo.size:
            stable_ok[todo] = 1
        bad = nd[stable_ok[nd] == 0]
        if bad.size:
            drop_s += bad.size
            alive[bad] = False
            continue
        pick = nd[_spread(f_all[nd], members)]
        todo = pick[robust_ok[pick] < 0]
        if robust is not None and np.sum(robust_ok >= 0) >= MAX_ROBUST * members:
            pick = pick[robust_ok[pick] == 1]  # the budget of worst-case checks is spent
            break
        if todo.size and robust is not None:
            fl = fields_of(x_ok[todo])
            r = rows(fl, stability=cons.stable)
            r.update(robust.full(fl, base, r))
            robust_ok[todo] = cons.violation(r) == 0
            checked.append((todo, r))
        elif todo.size:
            robust_ok[todo] = 1
        bad = pick[robust_ok[pick] == 0]
        if bad.size:
            drop_r += bad.size
            alive[bad] = False
            continue
        break
    pick = pick[np.argsort(f_all[pick, 0], kind="stable")]  # best rendering first
    f_front, x_front = f_all[nd], x_ok[nd]
    front = {c: -s * f_front[:, i] for i, (_, c, s) in enumerate(objectives)}
    how = ("nominal (K = K_max; without --nominal: the worst case over the uncertainty "
           "ranges)" if robust is None else "worst case over the uncertainty ranges: each "
           "renders K = min(K_max, worst-case largest passive and stable K), its bandwidth "
           f"at that K; {drop_r} front designs failed the full check")  # fmt: skip
    if not pick.size:
        return ParetoSet((), objectives, 0, evaluations, drop_s, drop_r, box, source, counts,
                         how, front)  # fmt: skip
    fl = fields_of(x_ok[pick])
    same = [(t, r) for t, r in checked if np.array_equal(np.sort(t), np.sort(pick))]
    if same:  # the members' rows as their full check took them, a batch of these designs
        # (rows that do not depend on the batch's order): not evaluated a second time
        t, r = same[0]
        at = {int(i): j for j, i in enumerate(t)}
        r_pick = {k: v[[at[int(i)] for i in pick]] for k, v in r.items()}
    else:
        r_pick = rows(fl, stability=cons.stable)
        if robust is not None:
            r_pick.update(robust.full(fl, base, r_pick))
    out_members = []
    for j in range(len(pick)):
        values = {k: float(fl[k][j]) for k in names}
        clutch = replace(base.clutch, n_drums=int(fl["n_drums"][j]), **values)
        mats = replace(base.materials, **{slot: str(fl[slot][j]) for slot in cats})
        d = replace(base, clutch=clutch, name=f"{base.name}-pareto", materials=mats)
        row = {k: float(v[j]) for k, v in r_pick.items()}
        out_members.append(Member(d, row, active_limits(cons, r_pick, j),
                                  range_edges(d, box, source, counts)))  # fmt: skip
    return ParetoSet(tuple(out_members), objectives, len(x_front), evaluations, drop_s, drop_r,
                     box, source, counts, how, front)  # fmt: skip


class _SearchRows(dict):  # type: ignore[type-arg]
    """The search's rows as ``Constraints.terms`` reads them, to count its limits without
    evaluating a design (a fast-path call costs mostly per call: one more generation's):
    every column it reads is there (ones), and none of those whose presence it tests: the
    search takes no stable K (``evaluate_rows`` without stability) and no worst-case column
    (``WorstCase.proxy`` adds none)."""

    def __missing__(self, key: str) -> np.ndarray:
        return np.ones(1)

    def __contains__(self, key: object) -> bool:
        return False


def _stable_K(base: ClutchDesign, r: Mapping[str, np.ndarray], idx: np.ndarray) -> np.ndarray:
    """The largest stable K (N/m) of rows ``idx`` of the search's own rows ``r`` (valid
    designs), from their figures at the hand (``mr_at_hand``, as ``evaluate_batch`` forms
    them), by ``stable_stiffness_batch``: the column ``evaluate_batch(stability=True)``
    gives, without evaluating the designs a second time."""
    inertia = r["rotor_inertia_kg_m2"][idx] + r["fluid_inertia_kg_m2"][idx]
    hp = mr_at_hand(base, inertia, r["drag_damping_N_m_s"][idx], r["max_torque_N_m"][idx],
                    r["clutch_mass_kg"][idx], r["torque_delay_s"][idx])  # fmt: skip
    return stable_stiffness_batch(hp)


def _spread(f: np.ndarray, k: int) -> list[int]:
    """k indices of the rows of f spread over the front: each column's best first, then
    greedily the row farthest (Euclidean, columns scaled to [0, 1]) from those picked."""
    n = len(f)
    if n <= k:
        return list(range(n))
    lo, hi = f.min(0), f.max(0)
    z = (f - lo) / np.where(hi > lo, hi - lo, 1.0)
    picked: list[int] = []
    for i in range(f.shape[1]):
        j = int(np.argmin(z[:, i]))
        if j not in picked and len(picked) < k:
            picked.append(j)
    dist = np.min(np.linalg.norm(z[:, None, :] - z[None, picked, :], axis=-1), axis=1)
    while len(picked) < k:
        j = int(np.argmax(dist))
        picked.append(j)
        dist = np.minimum(dist, np.linalg.norm(z - z[j], axis=-1))
    return picked
