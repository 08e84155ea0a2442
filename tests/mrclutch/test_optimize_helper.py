"""Issue 40: the Pareto members judged by this process and one helper process together
(``members.judge_beside``) get ``judge_all``'s answer, each judged once, in order; at
reference fidelity this process reads the B-rep masses the helper weighed, and so do the
helper's own judgements; the command's output with its helper is the output without
(``--workers 0``); the helper ends without its interpreter's teardown."""

import json
import multiprocessing
import os
from concurrent.futures import BrokenExecutor, Executor, ProcessPoolExecutor
from dataclasses import replace

from geometry.mass import brep_mass
from mrclutch import members
from mrclutch.cli.commands import optimize_pareto as pareto_cmd
from mrclutch.cli.main import main
from mrclutch.design import design_preset

PAPER = design_preset("paper")
_REAL_FAST = members.fast_check


def _designs(n: int) -> list:
    return [replace(PAPER, clutch=replace(PAPER.clutch, gap=PAPER.clutch.gap * (1 + 0.05 * i)))
            for i in range(n)]  # fmt: skip


def _fast_with_pid(design):
    """``fast_check`` marked with the process that ran it."""
    return {**_REAL_FAST(design), "pid": os.getpid()}


def _in_helper() -> bool:
    """Whether this runs in the helper process (a pool's worker has a parent process)."""
    return multiprocessing.parent_process() is not None


def _dumped(data: list[dict]) -> list[str]:
    return [json.dumps({k: v for k, v in d.items() if k != "pid"}, sort_keys=True, default=str)
            for d in data]  # fmt: skip


def test_both_processes_judge_and_the_answer_is_judge_alls(monkeypatch):
    """Three designs on the fast path: the shared judging's list equals ``judge_all``'s in
    this process, design for design, to the printed digit (NaN included); the helper judged
    some from the back and this process the others from the front; ``done`` counts up to
    three."""
    designs = _designs(3)
    want = _dumped(members.judge_all(designs, "fast"))
    monkeypatch.setattr(members, "fast_check", _fast_with_pid)
    counts: list[int] = []
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as helper:
        got = members.judge_beside(designs, "fast", helper, counts.append)
    assert _dumped(got) == want
    pids = [d["pid"] for d in got]
    here = [i for i, p in enumerate(pids) if p == os.getpid()]
    there = [i for i, p in enumerate(pids) if p != os.getpid()]
    assert here and there and here[0] == 0 and there[-1] == 2
    assert max(here) < min(there)  # the front here, the back there: they met once
    assert counts[-1] == 3 and counts == sorted(counts)


class _Broken(Executor):
    """A helper that died: every submission refused (BrokenExecutor)."""

    def submit(self, fn, /, *args, **kwargs):
        raise BrokenExecutor("the helper process died")


def test_a_broken_helper_leaves_every_judgement_to_this_process():
    """Where the helper breaks (died, or a spawn that could not start), every design is
    judged here and the answer is still ``judge_all``'s, in order."""
    designs = _designs(2)
    got = members.judge_beside(designs, "fast", _Broken())
    assert _dumped(got) == _dumped(members.judge_all(designs, "fast"))


def _weighed_there(design):
    """A stand-in for ``brep_of``: plain MassData naming the process that weighed it."""
    return ("brep", {"rotor": (0.01, 1e-6)}, (f"weighed in {os.getpid()}",))


def _mass_check(design):
    """A stand-in for ``reference_check``: where the B-rep mass came from (this process
    asks ``brep_mass``; the helper returns only its id, weighing nothing)."""
    if _in_helper():
        return {"pid": os.getpid()}
    rep = brep_mass(design.clutch, materials=design.materials)
    return {"pid": os.getpid(), "notes": list(rep.notes), "mass": rep.parts["rotor"].mass}


def test_at_reference_this_process_reads_the_helpers_b_rep_masses(monkeypatch):
    """At reference fidelity the helper weighs every design first and this process's
    judgements take those masses (``report_data.design_mass_from``): none weighed here."""
    monkeypatch.setattr(members, "brep_of", _weighed_there)
    monkeypatch.setattr(members, "reference_check", _mass_check)
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as helper:
        got = members.judge_beside(_designs(4), "reference", helper)
    here = [d for d in got if d["pid"] == os.getpid()]
    assert here and len(here) < 4
    for d in here:
        (note,) = d["notes"]
        assert note.startswith("weighed in ") and int(note.split()[-1]) != os.getpid()
        assert d["mass"] == 0.01


def _fast_as_reference(design):
    """A stand-in for ``reference_check`` (the fast path's judgement, which weighs no
    B-rep), run wherever the member is judged."""
    return members.fast_check(design)


def _paper_fast(base, fidelity, wc):
    """A stand-in for ``paper_beside`` at reference fidelity: its fast-path judgement."""
    return members.paper_beside(base, "fast", wc)


def test_the_command_with_its_helper_prints_what_it_prints_alone(monkeypatch, capsys):
    """A small seeded Pareto run at reference fidelity (its judgement, the paper's and the
    B-rep's stand-ins: module functions, so the helper runs them too): the JSON with the
    helper process (the default) equals the JSON with ``--workers 0`` but for the timings,
    and the helper judged the paper preset and some members."""
    real = pareto_cmd.pareto
    monkeypatch.setattr(pareto_cmd, "pareto",
                        lambda *a, **k: real(*a, **{**k, "pop_size": 16, "generations": 4,
                                                    "members": 3}))  # fmt: skip
    monkeypatch.setattr(members, "reference_check", _fast_as_reference)
    monkeypatch.setattr(members, "brep_of", _weighed_there)
    monkeypatch.setattr(pareto_cmd, "paper_beside", _paper_fast)
    submitted: list[str] = []
    real_submit = ProcessPoolExecutor.submit

    def submit(self, fn, *args, **kwargs):  # a member's check by its own name
        submitted.append((args[0] if fn is members.judged_there else fn).__name__)
        return real_submit(self, fn, *args, **kwargs)

    monkeypatch.setattr(ProcessPoolExecutor, "submit", submit)
    argv = ["optimize", "--drums", "2", "--seed", "3", "--json", "--no-progress"]
    out = []
    for extra in ([], ["--workers", "0"]):
        assert main([*argv, *extra]) == 0
        data = json.loads(capsys.readouterr().out)
        for k in ("optimisation_time_s", "reference_time_s"):
            data.pop(k)
        out.append(json.dumps(data, sort_keys=True))
    assert out[0] == out[1]
    assert len(json.loads(out[0])["members"]) == 3
    assert submitted[0] == "_paper_fast" and submitted.count("_weighed_there") == 3
    assert "_fast_as_reference" in submitted  # the helper judged some members
    submitted.clear()
    assert main([*argv, "--no-verify"]) == 0  # the fast path: no helper
    assert submitted == [] and json.loads(capsys.readouterr().out)["fidelity"] == "fast"


def test_the_helpers_own_judgement_reads_the_b_rep_it_weighed(monkeypatch):
    """A design ``brep_of`` weighed in this process is judged (``judged_there``) with that
    mass, not weighed again, and the mass is used once."""
    weighed: list[str] = []

    def weigh(design):
        weighed.append(f"weighing {len(weighed) + 1}")
        return ("brep", {"rotor": (0.01, 1e-6)}, (weighed[-1],))

    monkeypatch.setattr(members, "design_brep_mass", weigh)
    monkeypatch.setattr(members, "_WEIGHED", {})
    (d,) = _designs(1)
    assert members.brep_of(d)[2] == ("weighing 1",)
    got = members.judged_there(_mass_check, d)
    assert got["notes"] == ["weighing 1"] and got["mass"] == 0.01  # the weighed mass, read
    assert weighed == ["weighing 1"] and members._WEIGHED == {}  # weighed once, used once


class _Kept:
    """An object whose finaliser writes a file: run when the interpreter tears down the
    module holding it, not where the process ends without that teardown."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __del__(self, _open=open) -> None:
        with _open(self.path, "w") as f:
            f.write("torn down")


_KEEP: list = []


def _keep_till_exit(path: str) -> int:
    """In the helper: a ``_Kept`` held by this module till the process ends."""
    _KEEP.append(_Kept(path))
    return os.getpid()


def test_the_helper_ends_without_its_interpreters_teardown(tmp_path):
    """A helper started by ``members.helper_start`` ends with status 0 once its pool is shut
    down, without tearing its modules down: an object it holds is never finalised there,
    where a worker started without it finalises the same object at its exit."""
    ctx = multiprocessing.get_context("spawn")
    for start, marked in ((members.helper_start, False), (None, True)):
        mark = tmp_path / f"{start is None}.txt"
        pool = ProcessPoolExecutor(1, mp_context=ctx, initializer=start)
        pid = pool.submit(_keep_till_exit, str(mark)).result()
        (proc,) = pool._processes.values()
        pool.shutdown()
        assert proc.pid == pid and proc.exitcode == 0
        assert mark.exists() is marked
