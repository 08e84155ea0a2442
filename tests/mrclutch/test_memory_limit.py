"""Issue 44: no accepted single-design command peaks over 1 GiB. The FEM is the one model
whose memory grows with the input (its grid); before any mesh is built its estimate
(magnetics.fem.grid.memory_estimate: 100 MB + 6 kB a grid node) is checked against the
budget beside what the process already holds (its resident set: OpenCascade and VTK alone
are ~0.5 GiB), default 1 GiB in all. benchmarks/bench_memory.py measures the commands."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from geometry.section import build_section
from geometry.validation import ParameterError
from magnetics.fem import grid
from mrclutch.cli.main import main
from mrclutch.design import design_preset
from mrclutch.torque_curves import FEM_SIZE

ROOT = Path(__file__).resolve().parents[2]

#: one solve in a fresh process: its resident set before (imports done) and its peak after
PROBE = """
import json, sys
import scipy.sparse.linalg, skfem  # the imports are not the solve's
from geometry.section import build_section
from magnetics.fem import solve_fem
from magnetics.fem.grid import held_memory, memory_estimate
from mrclutch.design import design_preset
sec = build_section(design_preset("paper").clutch)
size = float(sys.argv[1])
before = held_memory()
try:
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")  # the peak resident set counts from here (Linux)
except OSError:
    pass  # the peak since start: an upper bound of the solve's
sol = solve_fem(sec, 5.0, size=size)
status = dict(line.split(":", 1) for line in open("/proc/self/status"))
peak = int(status["VmHWM"].split()[0]) * 1024
print(json.dumps({"before": before, "peak": peak, "nodes": memory_estimate(sec, size)[0],
                  "estimate": memory_estimate(sec, size)[1], "iterations": sol.iterations}))
"""


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")
def test_the_fem_memory_estimate_bounds_the_measured_peak_of_a_solve():
    """Paper preset, 0.125 mm, 5 A (Newton from zero, several factorisations): 31 702 grid
    nodes, estimate 100 MB + 6000 B × 31 702 = 290.2 MB; measured on the development
    machine 130 MB above the resident set before the solve (4.1 kB a node: grid and basis,
    the forms' stored parts, SuperLU's factors, a step's temporaries). The estimate must
    bound the measurement; and its per-node part must not be loose by more than 4× (else it
    refuses designs that fit: 6000 B × 31 702 / 4 = 47.6 MB ≤ 130 MB)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.run([sys.executable, "-c", PROBE, "0.125e-3"], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=300, check=True)  # fmt: skip
    m = json.loads(run.stdout.splitlines()[-1])
    used = m["peak"] - m["before"]
    assert m["nodes"] == 31702 and m["iterations"] >= 3
    assert m["estimate"] == pytest.approx(grid.BYTES_FIXED + grid.BYTES_PER_NODE * 31702)
    assert 0 < used <= m["estimate"], m
    assert used >= grid.BYTES_PER_NODE * m["nodes"] / 4, m


def test_the_default_budget_is_one_gib_in_all(monkeypatch):
    """MRCLUTCH_FEM_MEMORY_GB unset: 1 GiB = 1 073 741 824 B (less where the machine has
    under 2 GiB or an address-space limit); an unreadable value falls back to it."""
    monkeypatch.delenv("MRCLUTCH_FEM_MEMORY_GB", raising=False)
    assert grid.DEFAULT_MEMORY_GB == 1.0
    assert 0 < grid.memory_budget() <= 2**30
    monkeypatch.setenv("MRCLUTCH_FEM_MEMORY_GB", "lots")
    assert 0 < grid.memory_budget() <= 2**30


def test_what_the_process_holds_counts_against_the_budget(monkeypatch):
    """Budget = the solve's own estimate exactly: it fits with nothing held, and not with
    1 MiB held; the refusal names the estimate, what is held and the smallest size that
    fits (which then fits beside that 1 MiB)."""
    sec = build_section(design_preset("paper").clutch)
    nodes, need = grid.memory_estimate(sec, 0.25e-3)
    monkeypatch.setenv("MRCLUTCH_FEM_MEMORY_GB", repr(need / 2**30))
    grid.check_memory(sec, 0.25e-3, held=0.0)
    with pytest.raises(ParameterError, match=r"beside the 0\.00098 GiB this process holds") as e:
        grid.check_memory(sec, 0.25e-3, held=2**20)
    msg = str(e.value)
    assert f"{nodes:.3g} grid nodes need about {need / 2**30:.2g} GiB" in msg
    fits = float(msg.rsplit(" is ", 1)[1].split()[0]) * 1e-3
    assert fits > 0.25e-3
    grid.check_memory(sec, fits, held=2**20)  # the size named fits beside what is held
    assert grid.held_memory() > 2**20  # this process (Python, NumPy) holds more than 1 MiB
    with pytest.raises(ParameterError, match="this process holds"):
        grid.check_memory(sec, 0.25e-3)  # held: the resident set now


def test_an_fem_that_fits_alone_but_not_beside_the_process_is_one_line(monkeypatch, capsys):
    """``torque --method fem`` with the budget at the solve's estimate + 1 MiB: alone it
    would fit, beside this process's resident set (> 1 MiB) it does not: exit 2, one line
    naming the GiB and the budget's variable, no traceback, nothing on stdout."""
    sec = build_section(design_preset("paper").clutch)
    need = grid.memory_estimate(sec, FEM_SIZE)[1]
    monkeypatch.setenv("MRCLUTCH_FEM_MEMORY_GB", repr((need + 2**20) / 2**30))
    code = main(["torque", "--preset", "paper", "--method", "fem", "--json"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "this process holds" in err and "GiB budget (MRCLUTCH_FEM_MEMORY_GB)" in err
    # the smallest size that fits, or (more held than room for the coarsest) no size at all
    assert "smallest size that fits is" in err or "at any element size" in err
