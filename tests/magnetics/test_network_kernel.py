"""The network's compiled kernel (issue 31, magnetics.network.solve): the torques of the
NumPy Newton it replaced, numba loaded only by what solves the network, and compiled once
per machine."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

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
    torque, which solves the network, imports it (the check can fail)."""
    cmds = ["--help", "haptic", "inertia {tmp}/tet.stl --density 7850",
            "export --preset paper --out {tmp}/cad --tolerance-mm 0.05"]  # fmt: skip
    run = subprocess.run([sys.executable, "-c", _IMPORTS, *cmds], env=ENV, capture_output=True,
                         text=True, timeout=300)  # fmt: skip
    lines = run.stderr.strip().splitlines()[-len(cmds) :]
    assert [ln.split(": exit")[0] for ln in lines] == cmds, run.stderr
    for ln in lines:
        assert ln.endswith("exit 0, numba False"), ln
    run = subprocess.run([sys.executable, "-c", _IMPORTS, "torque --preset paper --current 2"],
                         env=ENV, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert run.stderr.strip().splitlines()[-1].endswith("exit 0, numba True"), run.stderr


_LOADS = """
import json, sys
import numpy as np
from geometry.params import preset
from magnetics.torque import torque_curve
import magnetics.network.solve as solve
from magnetics.network.torque import _reader

t = torque_curve(preset("paper"), [2.0, 7.0]).yield_torque
k = solve._kernels()
kernels = [k[n] for n in solve._KERNELS] + [_reader()]
misses = sum(len(d.stats.cache_misses) for d in kernels)
hits = sum(len(d.stats.cache_hits) for d in kernels)
print(json.dumps({"misses": misses, "hits": hits, "t": list(t)}))
"""


def test_a_later_process_compiles_nothing():
    """Once the kernels are in numba's cache (the first process on a machine compiles and
    writes them), a process loads every kernel from it: no cache miss, nothing on stderr,
    the same torque."""
    runs = [subprocess.run([sys.executable, "-c", _LOADS], env=ENV, capture_output=True,
                           text=True, timeout=600, check=True) for _ in range(2)]  # fmt: skip
    first, second = (json.loads(r.stdout) for r in runs)
    assert second["misses"] == 0 and second["hits"] >= 3, second
    assert runs[1].stderr == ""
    assert second["t"] == first["t"] and all(t > 0 for t in first["t"])
