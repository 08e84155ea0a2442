"""The report's CAD process (mrclutch.cli.report_cad, issue 40): what it computes comes back
as if computed here — its results, its errors as the same exception, its warnings — and it
never outlives the report: killed when the report stops or waits no more, ended by the
kernel when the report is killed, out of reach of a terminal's Ctrl-C."""

import os
import signal
import subprocess
import sys
import time
import warnings
from dataclasses import replace
from multiprocessing import Pipe
from types import MappingProxyType

import pytest

import geometry.mass as mass_mod
import mrclutch.cli.report_cad as rc
from geometry.mass import MassReport, PartMass, brep_mass, brep_mass_from
from mrclutch.design import design_preset
from mrclutch.report_data import mass_data, mass_report

PAPER = design_preset("paper")


def _gone(pid: int, within: float = 20.0) -> bool:
    """True once ``pid`` has ended (no such process, or a zombie nobody reaped)."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            with open(f"/proc/{pid}/stat") as f:
                if f.read().rpartition(")")[2].split()[0] == "Z":
                    return True
        except FileNotFoundError:
            return True
        time.sleep(0.05)
    return False


def _maps(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/maps") as f:
            return f.read()
    except (FileNotFoundError, ProcessLookupError):
        return ""


def test_brep_mass_from_hands_back_its_source_s_report_for_the_clutch_it_knows(monkeypatch):
    known = MassReport("brep", MappingProxyType({"rotor": PartMass(1.0, 2.0)}), ("elsewhere",))
    asked = []

    def source(clutch, materials):
        asked.append((clutch, materials))
        return known if clutch == PAPER.clutch else None

    monkeypatch.setattr(mass_mod, "material_solids", lambda clutch, s: {})  # no build123d
    other = replace(PAPER.clutch, n_drums=PAPER.clutch.n_drums + 1)
    with brep_mass_from(source):
        assert brep_mass(PAPER.clutch, materials=PAPER.materials) is known
        computed = brep_mass(other, materials=PAPER.materials)  # None: computed here
        given = brep_mass(PAPER.clutch, solids={}, materials=PAPER.materials)  # solids given
    assert asked == [(PAPER.clutch, PAPER.materials), (other, PAPER.materials)]
    assert computed is not known and given is not known and computed.rotor_mass == 0.0
    assert brep_mass(PAPER.clutch, materials=PAPER.materials) is not known  # outside: here
    assert len(asked) == 2


def test_a_mass_report_survives_the_pipe():
    parts = {"rotor": PartMass(0.1, 2e-5), "coil": PartMass(0.3, 1e-4)}
    rep = MassReport("brep", MappingProxyType(parts), ("a note",))
    back = mass_report(mass_data(rep))
    assert back == rep and back.rotor_inertia == rep.rotor_inertia


def test_the_child_sends_each_result_with_its_warnings_and_stops_at_the_first_error(
    monkeypatch, tmp_path
):
    def warn():
        warnings.warn("a numerical warning", RuntimeWarning, stacklevel=1)
        return "mass"

    def fail():
        raise OSError(28, "No space left on device", str(tmp_path / "clutch.step"))

    monkeypatch.setattr(rc, "_jobs", lambda design, folder: {
        "mass": warn, "cad": fail, "view": lambda: pytest.fail("ran after an error")})  # fmt: skip
    requests_r, requests_w = Pipe(duplex=False)
    results_r, results_w = Pipe(duplex=False)
    requests_w.send((PAPER, str(tmp_path)))
    rc._serve(requests_r, results_w)
    name, ok, value, caught = results_r.recv()
    assert (name, ok, value) == ("mass", True, "mass")
    assert [(m, c) for m, c, _, _ in caught] == [("a numerical warning", RuntimeWarning)]
    name, ok, value, caught = results_r.recv()
    assert (name, ok, type(value), value.filename) == ("cad", False, OSError,
                                                       str(tmp_path / "clutch.step"))  # fmt: skip
    with pytest.raises(EOFError):  # closed after the error: the view never ran
        results_r.recv()


def test_an_error_there_is_the_same_exception_here_and_every_later_task_s(tmp_path):
    cad = rc.CadProcess(None, tmp_path, lambda: None)  # None has no .clutch: the mass fails
    try:
        with pytest.raises(AttributeError, match="clutch"):
            cad.result("mass")
        with pytest.raises(AttributeError, match="clutch"):
            cad.result("view")
        with pytest.raises(ValueError, match="one of mass, cad, view"):
            cad.result("step")
    finally:
        cad.close()
    assert list(tmp_path.iterdir()) == []


def test_a_child_that_died_is_an_error_naming_its_exit_code(tmp_path):
    cad = rc.CadProcess(PAPER, tmp_path, lambda: None)
    try:
        os.kill(cad.pid, signal.SIGKILL)
        with pytest.raises(RuntimeError, match=r"exit code -9\) before its mass"):
            cad.result("mass")
    finally:
        cad.close()


def test_an_interrupted_wait_kills_the_child_at_close_and_ctrl_c_never_reaches_it(tmp_path):
    def check():
        raise KeyboardInterrupt

    cad = rc.CadProcess(PAPER, tmp_path, check)
    pid = cad.pid
    try:
        assert os.getsid(pid) == pid  # a session of its own: not the terminal's group
        with pytest.raises(KeyboardInterrupt):
            cad.result("mass")  # build123d takes seconds to import: the check comes first
    finally:
        cad.close()
    assert _gone(pid, within=0.1)  # close() killed and reaped it
    assert list(tmp_path.iterdir()) == []  # before it wrote anything


def test_the_child_ends_when_the_report_is_killed(tmp_path):
    """SIGKILL of the report's process leaves no CAD process writing into its staging
    folder (PR_SET_PDEATHSIG)."""
    script = ("import sys, time\nfrom mrclutch.cli.report_cad import CadProcess\n"
              "from mrclutch.design import design_preset\n"
              "cad = CadProcess(design_preset('paper'), sys.argv[1], lambda: None)\n"
              "print(cad.pid, flush=True)\ntime.sleep(120)\n")  # fmt: skip
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    parent = subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], env=env,
                              stdout=subprocess.PIPE, text=True)  # fmt: skip
    try:
        child = int(parent.stdout.readline())
        deadline = time.monotonic() + 120  # until it loads OpenCascade: past its set-up,
        while "OCP" not in _maps(child) and time.monotonic() < deadline:  # seconds of
            time.sleep(0.05)  # build123d's import still to go
        assert "OCP" in _maps(child)
        parent.kill()
        parent.wait()
        assert _gone(child, within=1.0), "the CAD process outlived the report"
    finally:
        parent.kill()
        parent.stdout.close()
