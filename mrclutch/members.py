"""The optimiser's designs judged as their files will say (issue 43: no decision logic under
``mrclutch/cli/``): each candidate or Pareto member as ``verdict.for_workshop`` ships it,
judged by the one verdict every command uses (``verdict.judge``) on the fast path and at
reference fidelity, the requirements it misses (``requirements.requirement_violations``),
which members are kept, the paper preset judged beside them, and the FEM check of the best.
The CLI (``mrclutch.cli.commands.optimize``, ``.pareto``) parses, calls these and prints.
"""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import BrokenExecutor, Executor
from contextlib import ExitStack
from dataclasses import replace
from typing import Any

import numpy as np

from magnetics.error_map import load as load_error_map
from mrclutch.design import ClutchDesign, design_preset
from mrclutch.optimize import (
    Candidate,
    Constraints,
    Member,
    Optimum,
    ParetoSet,
    WorstCase,
    active_limits,
    evaluate_rows,
    range_edges,
    search_box,
)
from mrclutch.pipeline import FAST_BANDWIDTH_ERROR
from mrclutch.report_data import design_brep_mass, design_mass_from
from mrclutch.requirements import requirement_violations
from mrclutch.uncertainty import Uncertainty
from mrclutch.verdict import for_workshop, judge, verdict_of
from mrclutch.verify import TORQUE, VerifiedRow, verify_designs


def reference_check(design: ClutchDesign) -> dict:
    """A design judged at reference fidelity (``verdict.judge``; a seam for the tests)."""
    return judge(design, "reference")


def fast_check(design: ClutchDesign) -> dict:
    """A design judged on the fast path (``verdict.judge``)."""
    return judge(design, "fast")


def judge_all(designs: list[ClutchDesign], fidelity: str, executor: Executor | None = None,
              done: Callable[[int], None] | None = None) -> list[dict]:  # fmt: skip
    """Every design judged (``verdict.judge``) at ``fidelity``, on ``executor`` (None:
    here); ``done(n)`` after each (a progress bar's)."""
    check = reference_check if fidelity == "reference" else fast_check
    out: list[dict] = []
    futures = None if executor is None else [executor.submit(check, d) for d in designs]
    for i, d in enumerate(designs):
        out.append(check(d) if futures is None else futures[i].result())
        if done is not None:
            done(i + 1)
    return out


#: The B-rep masses this process weighed (``brep_of``) and has not judged yet, by (clutch,
#: materials): a helper's own judgement of a design it weighed for the other process reads
#: its mass here (``judged_there``) instead of weighing it a second time (issue 40).
_WEIGHED: dict[tuple[Any, Any], Any] = {}


def brep_of(design: ClutchDesign) -> Any:
    """The design's exact B-rep mass as plain data (``report_data.design_brep_mass``): a
    helper process's task, so that this one never imports build123d (issue 40); kept for
    this process's own judgement of the design (``judged_there``)."""
    data = design_brep_mass(design)
    _WEIGHED[(design.clutch, design.materials)] = data
    return data


def judged_there(check: Callable[[ClutchDesign], dict], design: ClutchDesign) -> dict:
    """``check(design)`` in the helper process, the design's B-rep mass the one ``brep_of``
    weighed here if it did (read as this process reads the helper's masses:
    ``report_data.design_mass_from``), else weighed where ``check`` asks."""
    data = _WEIGHED.pop((design.clutch, design.materials), None)
    if data is None:
        return check(design)
    with design_mass_from(design, lambda: data):
        return check(design)


def helper_start() -> None:
    """A helper process's start (its pool's initializer): Ctrl-C is the parent's to handle
    (one line), ignored here until the parent stops it; and at its exit, every task's
    result sent, the process ends without the interpreter's teardown (``_exit_now``)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    atexit.register(_exit_now)


def _exit_now() -> None:
    """The helper's exit: its streams flushed, the process ended at once. The exit handlers
    its tasks' imports registered have run (later ones run first); those registered before
    it (multiprocessing's, run already by the worker's own exit; logging's, which has no
    handler here) and the teardown of its modules are skipped: freeing OpenCascade's,
    VTK's and numba's objects took ≈ 1–2 s CPU after the last result, on the path of the
    parent's ``shutdown`` and so of the command's wall time (issue 40)."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    os._exit(0)


def judge_beside(designs: list[ClutchDesign], fidelity: str, helper: Executor,
                 done: Callable[[int], None] | None = None) -> list[dict]:  # fmt: skip
    """``judge_all`` shared between this process and one ``helper`` process (an executor of
    one worker, e.g. started before the search so that its imports are behind it): this one
    judges from the first design on, the helper from the last back, until they meet; at
    reference fidelity the helper weighs every B-rep first (``brep_of``: ≈ 0.1 s CPU each)
    and this process reads its masses from there (``report_data.design_mass_from``) instead
    of importing build123d, as the helper's own judgements do (``judged_there``: each B-rep
    weighed once). Each design is judged by the same ``reference_check`` or
    ``fast_check`` wherever it runs, so the answer is ``judge_all``'s (and is, all judged
    here, where the helper breaks). ``done(n)`` after each of this process's judgements and
    at the end, ``n`` all judged so far."""
    try:
        return _judge_beside(designs, fidelity, helper, done)
    except BrokenExecutor:  # the helper died (or could not start): every design judged here
        return judge_all(designs, fidelity, None, done)


def _judge_beside(designs: list[ClutchDesign], fidelity: str, helper: Executor,
                  done: Callable[[int], None] | None) -> list[dict]:  # fmt: skip
    check = reference_check if fidelity == "reference" else fast_check
    n = len(designs)
    out: list[dict | None] = [None] * n
    masses = ([helper.submit(brep_of, d) for d in designs] if fidelity == "reference"
              else [])  # fmt: skip
    ends = {"front": 0, "back": n}
    lock = threading.Lock()
    failed: list[BaseException] = []

    def helper_side() -> None:  # claims from the back, one judgement at a time
        try:
            while True:
                with lock:
                    if ends["back"] <= ends["front"]:
                        return
                    ends["back"] -= 1
                    i = ends["back"]
                out[i] = helper.submit(judged_there, check, designs[i]).result()
        except BaseException as exc:  # re-raised here below, after the join
            failed.append(exc)

    thread = threading.Thread(target=helper_side, daemon=True)
    thread.start()
    try:
        while not failed:
            with lock:
                if ends["front"] >= ends["back"]:
                    break
                i = ends["front"]
                ends["front"] += 1
            with ExitStack() as stack:
                if masses:
                    stack.enter_context(design_mass_from(designs[i], masses[i].result))
                out[i] = check(designs[i])
            if done is not None:
                done(sum(r is not None for r in out))
    finally:
        thread.join()
    if failed:
        raise failed[0]
    if done is not None:
        done(n)
    return [r for r in out if r is not None]


def ranges(wc: WorstCase | None) -> Uncertainty | None:
    """The ranges the optimiser's worst case is taken over (None: ``--nominal``)."""
    return None if wc is None else wc.uncertainty


def check_candidate(design: ClutchDesign, cons: Constraints, verify: bool = True) -> dict:
    """One candidate (as its file will say: ``verdict.for_workshop``) judged on the fast path
    and (``verify``) at reference fidelity: its evaluations, its one verdict and the
    requirements it misses at the highest fidelity run."""
    fast = fast_check(design)
    data: dict = {
        "design_mm": design.clutch.to_mm(),
        "required": {"passive": cons.passive, "stable": cons.stable},
        "fast": fast,
        "fast_bandwidth_error_stated": FAST_BANDWIDTH_ERROR,
    }
    checked = fast
    if verify:
        ref = reference_check(design)
        b_fast, b_ref = fast["haptic"]["bandwidth_hz"], ref["haptic"]["bandwidth_hz"]
        data["reference"] = ref
        data["bandwidth_change_reference_vs_fast"] = b_ref / b_fast - 1
        checked = ref
    violations = requirement_violations(checked, cons, design)
    for ev in (fast, checked):  # the verdict from each evaluation's own data (the same
        ev["verdict"] = verdict_of(ev)  # as judge's; a seam's data gets one too)
    data["verdict"] = checked["verdict"]
    data["requirements_met"] = not violations
    data["violations"] = violations
    return data


def first_meeting(opt: Optimum, tries: int, wc: WorstCase | None, cons: Constraints,
                  verify: bool = True, done: Callable[[int], None] | None = None
                  ) -> tuple[Candidate, dict, list[dict]]:  # fmt: skip
    """The single-objective optimum's candidates checked best first (``check_candidate``)
    until one meets every requirement, at most ``tries``: the one chosen (the first that
    meets them, else the best), its check, and a record of each tried. ``done(n)`` after
    each check (a progress bar's)."""
    tried: list[dict] = []
    chosen: tuple[Candidate, dict] | None = None
    for rank, cand in enumerate(opt.candidates[:tries] or (Candidate(opt.design, opt.value),)):
        data = check_candidate(for_workshop(cand.design, ranges(wc))[0], cons, verify)
        tried.append({"rank": rank + 1, "n_drums": cand.design.clutch.n_drums,
                      "design_mm": cand.design.clutch.to_mm(), "objective_value": cand.value,
                      "fidelity": data["verdict"]["fidelity"],
                      "violations": data["violations"]})  # fmt: skip
        if chosen is None or (not data["violations"] and chosen[1]["violations"]):
            chosen = (cand, data)
        if done is not None:
            done(rank + 1)
        if not data["violations"]:
            break
    assert chosen is not None
    return chosen[0], chosen[1], tried


def limits_record(base: ClutchDesign, cons: Constraints) -> dict:
    """Every limit the optimiser enforced, as JSON (SI units in the key names)."""
    pr = base.process
    return {"min_torque_N_m": cons.min_torque, "max_mass_kg": cons.max_mass,
            "max_diameter_m": cons.max_diameter, "max_length_m": cons.max_length,
            "min_continuous_torque_above_drag_N_m": cons.min_continuous_torque,
            "max_coil_power_W": cons.max_power, "min_time_at_peak_s": cons.peak_time,
            "duty_torque_N_m": cons.duty_torque, "duty_time_s": cons.duty_time,
            "runout_m": pr.runout, "tolerance_m": pr.tolerance, "min_wall_m": pr.min_wall,
            "min_gap_m": pr.min_gap, "passive": cons.passive, "stable": cons.stable}  # fmt: skip


def optimum_limits(base: ClutchDesign, cons: Constraints, cand: Candidate, drums: Sequence[int],
                   bounds: Mapping[str, tuple[float, float]] | None) -> dict:  # fmt: skip
    """The chosen candidate's active limits and range edges on the fast path, and the
    limits enforced."""
    box, source = search_box(base, bounds)
    fl = {k: np.array([getattr(cand.design.clutch, k)]) for k in (*box, "n_drums")}
    row = evaluate_rows(fl, base, cons, stability=cons.stable)
    return {
        "active_limits": list(active_limits(cons, row, 0)),
        "edges": list(range_edges(cand.design, box, source, drums)),
        "limits": limits_record(base, cons),
    }


def paper_on(base: ClutchDesign) -> ClutchDesign:
    """The paper preset's clutch on ``base``'s operating point, transmission and process."""
    return replace(design_preset("paper"), operating=base.operating,
                   transmission=base.transmission, process=base.process)  # fmt: skip


def paper_beside(base: ClutchDesign, fidelity: str, wc: WorstCase | None) -> dict:
    """The paper preset's clutch (``paper_on``) judged at ``fidelity`` by the optimiser's
    rule (``verdict.for_workshop``), as its own designs are."""
    return judge(for_workshop(paper_on(base), ranges(wc))[0], fidelity)


def member_record(i: int, m: Member, ev: dict, violations: list[str]) -> dict:
    """Pareto member ``i`` as JSON: its fast-path row, its limits and its check."""
    return {"member": i, "n_drums": m.design.clutch.n_drums,
            "design_mm": m.design.clutch.to_mm(), "fast": dict(m.row),
            "active_limits": list(m.active), "edges": list(m.edges),
            "reference": ev, "violations": violations}  # fmt: skip


def shipped_members(ps: ParetoSet, wc: WorstCase | None) -> list[tuple[ClutchDesign, list[str]]]:
    """Each member as its file says (its ``[render]`` rule, its ranges, no bench), with the
    notes to print (``verdict.for_workshop``)."""
    return [for_workshop(m.design, ranges(wc)) for m in ps.members]


def judge_members(ps: ParetoSet, shipped: list[tuple[ClutchDesign, list[str]]],
                  cons: Constraints, fidelity: str, executor: Executor | None = None,
                  done: Callable[[int], None] | None = None,
                  helper: Executor | None = None) -> list[dict]:  # fmt: skip
    """Each shipped member judged by the one verdict every command uses at ``fidelity``
    (reference, or the fast path: --no-verify), with the requirements it misses there
    (``member_record``; kept: those with no violation). ``helper``: one process sharing
    the judgements with this one (``judge_beside``), else ``executor`` judges them all
    (None: here)."""
    designs = [d for d, _ in shipped]
    refs = (judge_beside(designs, fidelity, helper, done) if helper is not None
            else judge_all(designs, fidelity, executor, done))  # fmt: skip
    judged = zip(ps.members, refs, shipped, strict=True)
    return [member_record(i, m, ev, requirement_violations(ev, cons, d))
            for i, (m, ev, (d, _)) in enumerate(judged, 1)]  # fmt: skip


def reference_fem_size() -> float:
    """m: the FEM element size the checks solve at by default (the error map's reference)."""
    return load_error_map().reference_fem_size


def verify_candidates(top: Sequence[Candidate], base: ClutchDesign, cons: Constraints,
                      bounds: Mapping[str, tuple[float, float]] | None,
                      executor: Executor | None) -> list[VerifiedRow]:  # fmt: skip
    """The torque of the best candidates re-solved with the FEM at the reference size
    (``verify.verify_designs``), beside the fast path's and its error bound."""
    box, _ = search_box(base, bounds)
    f = {k: np.array([getattr(c.design.clutch, k) for c in top]) for k in (*box, "n_drums")}
    rows = evaluate_rows(f, base, cons)
    return verify_designs([c.design for c in top], list(range(1, len(top) + 1)),
                          [c.value for c in top], rows[TORQUE].tolist(),
                          rows["torque_error_bound"].tolist(), reference_fem_size(),
                          executor)  # fmt: skip


def verify_members(ps: ParetoSet, kept: Sequence[dict[str, Any]], n: int,
                   executor: Executor | None) -> list[VerifiedRow]:  # fmt: skip
    """The torque of the first ``n`` kept members re-solved with the FEM at the reference
    size (``verify.verify_designs``), beside the fast path's and its error bound."""
    top = [(r, ps.members[r["member"] - 1]) for r in kept[:n]]
    return verify_designs([m.design for _, m in top], [r["member"] for r, _ in top],
                          [m.row[ps.objectives[0][1]] for _, m in top],
                          [m.row[TORQUE] for _, m in top],
                          [m.row["torque_error_bound"] for _, m in top],
                          reference_fem_size(), executor)  # fmt: skip
