"""The network's compiled kernel (issue 31, magnetics.network.compiled): the torques of the
NumPy Newton it replaced, numba loaded only by what solves the network, and compiled once
per machine."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from geometry.params import preset
from magnetics.network import compiled

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "benchmarks"
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


def test_torques_equal_the_stored_reference_of_the_numpy_newton():
    """10⁴ random designs at 2, 4, 7 A: the kernel's torques equal those the NumPy Newton
    gave (commit 76ddb7b, stored by benchmarks/make_network_reference.py) within 1e-9
    relative (measured: 7.8e-16)."""
    sys.path.insert(0, str(BENCH))
    try:
        import make_network_reference as ref
    finally:
        sys.path.remove(str(BENCH))
    from magnetics.network.torque import network_torque_batch

    stored = np.load(ref.DATA)
    assert stored["torque"].shape == (ref.DESIGNS, len(ref.CURRENTS))
    t = network_torque_batch(ref.fields(), stored["currents"])
    assert np.all(np.isfinite(t)) and np.all(t > 0)
    np.testing.assert_allclose(t, stored["torque"], rtol=1e-9, atol=0.0)


_IMPORTS = """
import sys, tempfile
from pathlib import Path
from mrclutch.cli.main import main

tmp = Path(tempfile.mkdtemp())
stl = tmp / "tet.stl"  # a 10 mm tetrahedron, ASCII STL
v = ["0 0 0", "10 0 0", "0 10 0", "0 0 10"]
faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
stl.write_text("solid t\\n" + "".join(
    f"facet normal 0 0 0\\nouter loop\\n" + "".join(f"vertex {v[i]}\\n" for i in f)
    + "endloop\\nendfacet\\n" for f in faces) + "endsolid t\\n")
out = []
for argv in sys.argv[1:]:
    args = argv.replace("{tmp}", str(tmp)).split()
    try:
        code = main(args)
    except SystemExit as e:
        code = e.code
    out.append(f"{argv}: exit {code}, numba {'numba' in sys.modules}")
print("\\n".join(out), file=sys.__stderr__)
"""


@pytest.mark.slow
def test_commands_that_do_not_solve_the_network_never_import_numba():
    """--help, haptic, inertia (a file weighed) and export run without importing numba;
    nor does torque on one design, which solves the network with the kernels' own Python
    (a few rows: issue 40); a solve of many rows imports it (the check can fail). One
    fresh process runs them in turn (numba, once imported, stays: each line reads what
    its command and those before it imported), then the solve of many rows."""
    cmds = ["--help", "haptic", "inertia {tmp}/tet.stl --density 7850",
            "export --preset paper --out {tmp}/cad --tolerance-mm 0.05",
            "torque --preset paper --current 2"]  # fmt: skip
    run = subprocess.run([sys.executable, "-c", _IMPORTS + _MANY, *cmds], env=ENV,
                         capture_output=True, text=True, timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stderr
    # the commands' lines (a first compile's notice may follow them: the many rows')
    lines = [ln for ln in run.stderr.splitlines() if ": exit " in ln]
    assert [ln.split(": exit")[0] for ln in lines] == cmds, run.stderr
    for ln in lines:
        assert ln.endswith("exit 0, numba False"), ln
    assert run.stdout.split()[-1] == "True", run.stdout


#: 300 designs at two currents (600 rows, past ``compiled._PY_ROWS``): the compiled kernels.
_MANY = """
import numpy as np
from geometry.params import preset
from magnetics.torque import network_torque_batch
f = {k: np.full(300, float(v)) for k, v in vars(preset("paper")).items()}
f["gap"] = np.linspace(0.3e-3, 0.5e-3, 300)
assert np.all(network_torque_batch(f, [2.0, 7.0]) > 0)
print("numba" in sys.modules)
"""


_LOADS = """
import json, os, sys
from pathlib import Path
import numpy as np
from geometry.params import preset
from magnetics.torque import torque_curve
import magnetics.network.compiled as compiled
import magnetics.network.torque as nt

compiled._PY_ROWS = nt._PY_CELLS = 0  # the compiled kernels for every solve
t = torque_curve(preset("paper"), [2.0, 7.0]).yield_torque
k = compiled._kernels()
kernels = [k["_solve_rows"], nt._reader()]
misses = sum(len(d.stats.cache_misses) for d in kernels)
hits = sum(len(d.stats.cache_hits) for d in kernels)
package = Path(compiled.__file__).parent
overloads = {name: len(k[name].overloads) for name in compiled._SIGNATURES}
overloads["_read_rows"] = len(kernels[1].overloads)
try:  # another layout (a read-only view): an error, not a second overload
    ni = np.zeros((1, 1))
    ni.flags.writeable = False
    k["_solve_rows"](np.zeros((1, 1)), np.zeros(1, np.int64), 1, 1, np.zeros((4, 1, 3)),
                     np.zeros(4), np.zeros(4, np.int64), ni, np.zeros((1, 1), np.int64),
                     np.zeros((0, 1, 1)), False, np.zeros((0, 1)), 1e-10, 60,
                     np.zeros((1, 1, 8)), np.ones(1, np.bool_), np.zeros((17, 8)))
    other = "ran"
except TypeError:
    other = "refused"
beside = {n: [len(k[n].stats.cache_hits), len(k[n].stats.cache_misses)]
          for n in compiled._BESIDE}
print(json.dumps({"misses": misses, "hits": hits, "t": list(t), "overloads": overloads,
                  "beside": beside, "cores": len(os.sched_getaffinity(0)),
                  "other": other, "after": len(k["_solve_rows"].overloads),
                  "cache": str(compiled.cache_dir()),
                  "paths": [d.stats.cache_path for d in kernels],
                  "in_package": [Path(d.stats.cache_path).is_relative_to(package)
                                 for d in kernels]}))
"""


def test_a_later_process_compiles_nothing(tmp_path):
    """Once the kernels are in numba's cache (the first process on a machine compiles and
    writes them), a process loads every kernel from it: no cache miss, nothing on stderr,
    the same torque. The cache is the user's cache folder (here ``XDG_CACHE_HOME``), never
    the package's folder (issue 39: a cache left there outlives a reinstall)."""
    env = {k: v for k, v in ENV.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    runs = [subprocess.run([sys.executable, "-c", _LOADS], env=env, capture_output=True,
                           text=True, timeout=600, check=True) for _ in range(2)]  # fmt: skip
    first, second = (json.loads(r.stdout) for r in runs)
    assert first["misses"] >= 2 and "compiled in" in runs[0].stderr, runs[0].stderr
    # one overload of each kernel the solve and the reading call (issue 40: the literal
    # material rows compiled 32 of 13 kernels), none of the flux linkage's own, and a call
    # of another type refused, not compiled
    want = {name: 1 for name in compiled._SIGNATURES if name != "_tangent_rows"}
    assert first["overloads"] == {**want, "_tangent_rows": 0, "_read_rows": 1}
    assert first["other"] == "refused" and first["after"] == 1
    # on 2 cores the Thomas solve compiled in a second process meanwhile: this one loaded
    # it from the cache that process wrote (a hit, no miss), then compiled what calls it
    if first["cores"] >= 2:
        assert first["beside"] == {n: [1, 0] for n in compiled._BESIDE}, first["beside"]
    # the notice's estimate, then the time it took
    notice = re.search(r"mrclutch: compiling the reluctance network's solver \(numba, once "
                       r"on this machine\): ~\d+ s left of ~\d+ s …\n", runs[0].stderr)  # fmt: skip
    assert notice and re.search(r"compiled in \d+\.\d s", runs[0].stderr), runs[0].stderr
    # a later process loads the solver alone (its cached code holds what it calls)
    none = dict.fromkeys(compiled._SIGNATURES, 0)
    assert second["overloads"] == {**none, "_solve_rows": 1, "_read_rows": 1}
    assert second["misses"] == 0 and second["hits"] == 2, second
    assert runs[1].stderr == ""
    assert second["t"] == first["t"] and all(t > 0 for t in first["t"])
    assert first["cache"] == str(tmp_path / "mrclutch" / "numba" / f"opt{compiled._OPT}")
    assert list((tmp_path / "mrclutch" / "numba").rglob("*.nbi"))
    assert all(Path(p).is_relative_to(tmp_path) for p in first["paths"]), first["paths"]
    assert first["in_package"] == [False, False]


def _notices(monkeypatch, capsys, weights, ends, entry_weight, entry_end):
    """What ``compiled._Clock`` prints for an entry of ``entry_weight`` whose callees have
    ``weights`` (bytecode) and compile events ending at ``ends`` seconds (a callee not in
    ``ends`` loads from the cache), the entry's own compile ending at ``entry_end``; and
    the clock."""
    now = [0.0]
    monkeypatch.setattr(compiled, "time", types.SimpleNamespace(perf_counter=lambda: now[0]))
    monkeypatch.setattr(compiled, "_weight", lambda d: d.w)
    callees = [types.SimpleNamespace(w=w) for w in weights]
    entry = types.SimpleNamespace(w=entry_weight)
    end = {id(d): t for d, t in zip(callees, ends, strict=False) if t is not None}
    clock = compiled._Clock(entry, "the test's kernel",
                            tuple((d, f"s{i}") for i, d in enumerate(callees)))  # fmt: skip

    def one(d, sig):  # a compile event for those in ``end``; the others load from the cache
        if id(d) in end:
            clock.on_start(types.SimpleNamespace(data={"dispatcher": d}))
            now[0] = end[id(d)]
            clock.on_end(types.SimpleNamespace(data={"dispatcher": d}))

    monkeypatch.setattr(compiled, "_one", one)
    clock.on_start(types.SimpleNamespace(data={"dispatcher": entry}))
    now[0] = entry_end
    clock.on_end(types.SimpleNamespace(data={"dispatcher": entry}))
    clock.finish()
    return capsys.readouterr().err.splitlines(), clock


def test_the_compile_notice_estimates_the_time_left(monkeypatch, capsys):
    """``compiled._Clock``: the entry's compile compiles what it calls first; past
    ``_COMPILE_NOTICE_S`` the notice says the time since the first kernel's end times the
    bytecode left over the bytecode compiled since (a kernel loaded from the cache leaves the
    count), once; the time it
    took after. Kernels of bytecode 100 (0.5 s), 300 (loaded), 200 (done at 2 s), the entry
    400 (done at 4 s); the rate from the first kernel's end (its time holds the process's
    first-compile start): (2 − 0.5) s · (700 − 300)/(300 − 100) = 3 s left of 5 s."""
    err, clock = _notices(monkeypatch, capsys, (100, 300, 200), (0.5, None, 2.0), 400, 4.0)
    assert err[0] == ("mrclutch: compiling the test's kernel (numba, once on this machine): "
                      "~3 s left of ~5 s …")  # fmt: skip
    assert err[1].startswith("mrclutch: compiled in 4.0 s (cached in ") and len(err) == 2
    assert clock.total == 700 and clock.done == 700


def test_the_compile_notice_waits_for_its_share_of_the_bytecode(monkeypatch, capsys):
    """The estimate waits until ``_NOTICE_SHARE`` (15 %) of the bytecode after the first
    kernel is compiled: after the first (100, 0.5 s), 80 of the 600 left (13 %, 1.5 s) is
    not enough, 100 (17 %, 2.1 s) is: (2.1 − 0.5) s · (700 − 200)/100 = 8 s left of 10 s."""
    err, _ = _notices(monkeypatch, capsys, (100, 80, 20), (0.5, 1.5, 2.1), 500, 9.0)
    assert err[0] == ("mrclutch: compiling the test's kernel (numba, once on this machine): "
                      "~8 s left of ~10 s …")  # fmt: skip
    assert len(err) == 2


def test_the_compile_notice_has_no_estimate_when_nothing_is_left(monkeypatch, capsys):
    """The callees all load from the cache and the entry alone compiles (4 s): the timer's
    call after its end (it may fire before ``finish`` cancels it) says that it compiles and
    gives no estimate: no rate (nothing compiled since the first kernel) and nothing left.
    Before, the estimate divided by the zero bytecode compiled since (a CI failure)."""
    err, clock = _notices(monkeypatch, capsys, (100, 200), (None, None), 400, 4.0)
    assert clock.total == clock.done == 400 and clock.warm == (4.0, 400)
    clock.opening()  # the timer's late call
    err += capsys.readouterr().err.splitlines()
    assert err[0].startswith("mrclutch: compiled in 4.0 s")
    assert err[1:] == ["mrclutch: compiling the test's kernel (numba, once on this machine) …"]
    assert not clock.said


def test_each_kernel_runs_uncompiled_within_its_own_budget(monkeypatch):
    """``compiled.uncompiled``: a kernel's batches run as plain Python while their rows stay
    within its budget and its compiled entry is not loaded; the solver's being loaded
    leaves the reader's budget as it was."""
    monkeypatch.setattr(compiled, "_loaded", set())
    monkeypatch.setattr(compiled, "_used", {})
    assert compiled.uncompiled("reader", 10, 20) and compiled.uncompiled("reader", 10, 20)
    assert not compiled.uncompiled("reader", 1, 20)  # past its budget
    compiled._loaded.add("network")
    assert not compiled.uncompiled("network", 0, 20)
    assert compiled.uncompiled("other", 5, 20)
    compiled._loaded.add("other")
    assert not compiled.uncompiled("other", 0, 20)


def test_cache_folder_is_the_users_and_numba_cache_dir_wins(monkeypatch, tmp_path):
    """``cache_dir``: NUMBA_CACHE_DIR if set, else $XDG_CACHE_HOME/mrclutch/numba, else
    ~/.cache/mrclutch/numba, in a folder per LLVM optimisation level (numba's cache index
    holds no level: code compiled at NUMBA_OPT=0 would be served at 2)."""
    from magnetics.network import compiled

    monkeypatch.delenv("NUMBA_OPT", raising=False)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "nb"))
    assert compiled.cache_dir() == tmp_path / "nb"
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert compiled.cache_dir() == tmp_path / "xdg" / "mrclutch" / "numba" / "opt2"
    monkeypatch.setenv("NUMBA_OPT", "0")  # the user's level: its own folder
    assert compiled.cache_dir() == tmp_path / "xdg" / "mrclutch" / "numba" / "opt0"
    monkeypatch.delenv("NUMBA_OPT")
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert compiled.cache_dir() == tmp_path / "home" / ".cache" / "mrclutch" / "numba" / "opt2"


_OPT_SEEN = """
import json, os
from magnetics.network import compiled
numba = compiled.numba_module()
print(json.dumps([int(numba.config.OPT), numba.config.CACHE_DIR, os.environ["NUMBA_OPT"]]))
"""


@pytest.mark.parametrize("user", [None, "3", "0"])
def test_the_kernels_compile_at_the_projects_llvm_level_unless_the_user_sets_one(tmp_path, user):
    """``compiled.numba_module``: numba's optimisation level is the project's (2: the rows
    bit-identical to numba's default 3, a first compile ≈ 0.9 s CPU shorter) or, where the
    user set ``NUMBA_OPT``, the user's; its cache in that level's folder; and the variable
    set for a process this one starts (the second process that compiles beside it)."""
    env = {k: v for k, v in ENV.items() if k not in ("NUMBA_CACHE_DIR", "NUMBA_OPT")}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    if user is not None:
        env["NUMBA_OPT"] = user
    run = subprocess.run([sys.executable, "-c", _OPT_SEEN], env=env, capture_output=True,
                         text=True, timeout=120, check=True)  # fmt: skip
    level, cache, inherited = json.loads(run.stdout)
    want = "2" if user is None else user
    assert compiled._OPT == "2" and level == int(want) and inherited == want
    assert cache == str(tmp_path / "mrclutch" / "numba" / f"opt{want}")


def test_uncompiled_small_batches_give_the_compiled_answer(monkeypatch):
    """A few rows run the kernels' own Python (``compiled.uncompiled``), many rows the compiled
    kernels: the same functions, so the same loop fluxes and torques (to 1e-12 relative;
    both are IEEE double arithmetic in the same order) on 3 designs at 3 currents; once the
    compiled kernel is loaded, or the process's budget is spent, every solve is compiled."""
    from magnetics.network import compiled
    from magnetics.network import torque as nt
    from magnetics.torque import network_torque_batch

    f = {k: np.full(3, float(v)) for k, v in vars(preset("paper")).items()}
    f["gap"] = np.array([0.3e-3, 0.4e-3, 0.5e-3])
    cur = [1.0, 3.0, 7.0]
    monkeypatch.setattr(compiled, "_loaded", set())
    monkeypatch.setattr(nt, "_loaded", compiled._loaded)
    monkeypatch.setattr(compiled, "_used", {})
    py = network_torque_batch(f, cur)
    assert compiled._used == {"network": 9, "reader": 9 * 8} and not compiled._loaded
    monkeypatch.setattr(compiled, "_PY_ROWS", 0)
    monkeypatch.setattr(nt, "_PY_CELLS", 0)
    jit = network_torque_batch(f, cur)
    assert {"network", "reader"} <= compiled._loaded
    assert np.all(py > 0)
    np.testing.assert_allclose(py, jit, rtol=1e-12, atol=0.0)
    assert not compiled.uncompiled("network", 1, 10**9)  # loaded: compiled from now on


def test_an_interrupted_compile_leaves_no_second_process(monkeypatch):
    """``compiled._Clock``: Ctrl-C (or a failed compile) while this process compiles ends
    the second process that compiles ``beside`` kernels meanwhile, before it re-raises."""
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        monkeypatch.setattr(compiled, "_compile_beside", lambda names: child)
        monkeypatch.setattr(compiled, "_weight", lambda d: 100)
        monkeypatch.setattr(compiled, "_name", lambda d: d.name)
        a, entry = types.SimpleNamespace(name="_segment"), types.SimpleNamespace(name="x")
        clock = compiled._Clock(entry, "the test's kernel", ((a, "sa"),), ("_solve",))

        def one(d, sig):
            raise KeyboardInterrupt

        monkeypatch.setattr(compiled, "_one", one)
        with pytest.raises(KeyboardInterrupt):
            clock.on_start(types.SimpleNamespace(data={"dispatcher": entry}))
        clock.timer.cancel()
        assert child.poll() is not None  # ended, not left sleeping
    finally:
        child.kill()
        child.wait()
