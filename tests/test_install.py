"""The README's two Quick start lines in one environment, in either order (issue 39): the
compiled kernel's cache lives in the user's cache folder, never inside the installed
package, so replacing the wheel by an editable install (or back) leaves no folder that
Python would take for ``magnetics.network``."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Solves 300 designs at two currents (600 rows: past the uncompiled budget, so numba
#: compiles the solver and the torque reading) and says where the package was imported from.
_COMPILE = """
import sys
import numpy as np
import magnetics
from geometry.params import preset
from magnetics.torque import network_torque_batch
f = {k: np.full(300, float(v)) for k, v in vars(preset("paper")).items()}
f["gap"] = np.linspace(0.3e-3, 0.5e-3, 300)
t = network_torque_batch(f, [2.0, 7.0])
print(magnetics.__file__, "numba" in sys.modules, repr(float(t.sum())))
"""


def _run(args: list[str], env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess:
    run = subprocess.run(args, env=env, cwd=cwd, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, f"{args}: exit {run.returncode}\n{run.stdout}\n{run.stderr}"
    return run


def quick_start_lines() -> list[str]:
    """The README's Quick start commands as written (the fenced block after "## Quick
    start"), comments cut: the main job's line, then the tests' line."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text.split("## Quick start", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    return [line.split("#", 1)[0].strip() for line in block.splitlines() if line.strip()]


#: What the tests' line's ``python -m pytest`` runs in the fresh venv: one file that imports
#: the network package (the import that failed), in one process, and of it the closed-form
#: and batch-of-one solves (2 s; its FEM comparisons cost 15 s more and say nothing about the
#: install). The whole suite is what .ci/run runs with that same line; here it would run this
#: test inside itself.
SMOKE = (
    "-n 0 -p no:randomly -p no:cacheprovider tests/magnetics/test_network.py"
    " -k 'closed_form or independent_nodal_solve or batch_of_one'"
)


def _venv_pip(venv: Path) -> None:
    """The venv's ``pip`` command: the console script ``ensurepip`` writes (pip's own
    entry point run by the venv's python, so it installs into the venv), with pip's code
    from this environment's site-packages (``--system-site-packages``) instead of a copy:
    ensurepip installing its wheel cost 7 s of CPU (16 s wall on the shared machine)."""
    script = venv / "bin" / "pip"
    script.write_text(f"#!{venv / 'bin' / 'python'}\nimport sys\n"
                      "from pip._internal.cli.main import main\nsys.exit(main())\n")  # fmt: skip
    script.chmod(0o755)


def test_the_quick_start_is_two_lines_a_main_job_and_the_tests():
    """What the install test runs is the README's block: two lines, the main job first."""
    main_job, tests = quick_start_lines()
    assert main_job.startswith("pip install . && mrclutch report"), main_job
    assert tests == 'pip install -e ".[dev]" && python -m pytest', tests


@pytest.mark.slow
@pytest.mark.skipif(
    not os.environ.get("CI") and not os.environ.get("MRCLUTCH_INSTALL_TEST"),
    reason="builds the package three times and compiles twice (minutes): run in .ci/run "
    "(CI set) or with MRCLUTCH_INSTALL_TEST=1",
)
def test_quick_start_lines_in_either_order_in_one_venv(tmp_path):
    """The README's Quick start run as written (``quick_start_lines``), both lines in one
    fresh venv (``--system-site-packages``: the dependencies of this environment, so only
    the build backend is fetched, as pip does) in a copy of the working tree (its files git
    does not ignore): the main job's line (``pip install . && mrclutch report …``) writes
    its report; a solve that compiles caches its kernels in $XDG_CACHE_HOME/mrclutch/numba,
    none in site-packages; the tests' line on top (``pip install -e ".[dev]" && python -m
    pytest``, its pytest limited to ``SMOKE`` by PYTEST_ADDOPTS) passes, and then
    ``mrclutch evaluate --preset paper`` runs (it failed with ``cannot import name
    'Network'`` when the cache lived in the package), site-packages holds no ``magnetics``
    folder and the solve compiles for the source copy with the same torque; the main job's
    line again, on top of the editable install, writes its report."""
    ls = ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"]
    files = subprocess.run(ls, cwd=ROOT, capture_output=True, check=True).stdout.decode()
    files = files.split("\0")
    src = tmp_path / "src"
    for name in filter(None, files):
        if (ROOT / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, src / name)
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip",
                    str(venv)], check=True, timeout=120)  # fmt: skip
    py = venv / "bin" / "python"
    _venv_pip(venv)
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    # PIP_NO_WARN_CONFLICTS=0 (pip sets a "no-" option's destination to the value given:
    # warn_about_conflicts = 0, as --no-warn-conflicts): no closing scan of every installed
    # distribution for conflicts (~2.2 s of CPU an install here, 181 of them), which only
    # prints warnings; the exit status, all this test reads, is the same without it
    env.update(XDG_CACHE_HOME=str(tmp_path / "cache"), PATH=f"{venv / 'bin'}:{env['PATH']}",
               OPENBLAS_NUM_THREADS="1", PIP_DISABLE_PIP_VERSION_CHECK="1",
               PIP_NO_WARN_CONFLICTS="0")  # fmt: skip
    site = Path(_run([str(py), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                     env, tmp_path).stdout.strip())  # fmt: skip
    cache = tmp_path / "cache" / "mrclutch" / "numba"
    evaluate = ["mrclutch", "evaluate", "--preset", "paper", "--no-uncertainty"]

    main_job, tests = quick_start_lines()
    shell = ["bash", "-c"]

    _run([*shell, main_job], env, src)  # the README's first line, as written
    assert (src / "report" / "report.html").is_file(), "the main job wrote its report"
    first = _run([str(py), "-c", _COMPILE], env, tmp_path)
    where, numba, torque = first.stdout.split()
    assert Path(where).is_relative_to(site) and numba == "True"
    assert list(cache.rglob("*.nbi")), "the compiled kernels are cached in the user's folder"
    assert not list((site / "magnetics").rglob("*.nb[ic]")), "no kernel cache in the package"

    # the README's second line, as written, on top (its pytest limited to SMOKE, below)
    ran = _run([*shell, tests], {**env, "PYTEST_ADDOPTS": SMOKE}, src)
    assert " passed" in ran.stdout and " failed" not in ran.stdout, ran.stdout[-2000:]
    assert not (site / "magnetics").exists(), "the wheel's package folder is gone"
    out = _run(evaluate, env, tmp_path)
    assert "K_max" in out.stdout or "N/m" in out.stdout, out.stdout
    again = _run([str(py), "-c", _COMPILE], env, tmp_path)
    where, numba, torque_again = again.stdout.split()
    assert Path(where).is_relative_to(src) and torque_again == torque
    assert not list(src.rglob("*.nb[ic]")), "no kernel cache in the source tree either"

    shutil.rmtree(src / "report")
    _run([*shell, main_job], env, src)  # and the first line again, on top of the editable
    assert (src / "report" / "report.html").is_file()
    _run(evaluate, env, tmp_path)
