"""Issue 45 item 5 (the sweep's half): ``--repair`` on a full disk and Ctrl-C under
``--dask-local`` each end in one line; the data on disk stays whole."""

import errno
import os
import signal
import subprocess
import sys
import time

import pytest

from mrclutch.cli.main import main

ENOSPC = os.strerror(errno.ENOSPC)
SPEC = """\
[sweep]
mode = "random"
samples = 6
seed = 2
base = "paper"
chunk_size = 2

[parameters]
gap_mm = {min = 0.3, max = 0.6}
"""
#: Notes a run may print besides its answer (the network kernel's one-off compilation; the
#: estimate of a long sweep).
NOTES = ("mrclutch: compiling", "mrclutch: compiled in ", "mrclutch sweep: 6e+04 designs")


def _lines(err: str) -> list[str]:
    return [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(NOTES)]


def test_repair_on_a_full_disk_is_one_line_and_keeps_the_data(tmp_path, monkeypatch, capsys):
    """The disk is full: the lock file cannot take the process id (ENOSPC from its write:
    a traceback before) and the repaired file cannot be flushed. One line, exit 2; the
    damaged file is left as it was, and a repair with space restores it."""
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC)
    out = tmp_path / "r.csv"
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress"]) == 0
    whole = out.read_bytes()
    lines = whole.decode().splitlines(keepends=True)
    lines[3] = lines[3].replace(",1,", ",0,", 1)  # a row of chunk 1 altered
    damaged = "".join(lines).encode()
    assert damaged != whole
    out.write_bytes(damaged)
    capsys.readouterr()

    real_pwrite = os.pwrite

    def full_pwrite(fd, data, offset):
        if os.readlink(f"/proc/self/fd/{fd}").endswith(".lock"):
            raise OSError(errno.ENOSPC, ENOSPC)
        return real_pwrite(fd, data, offset)

    def full_fsync(fd):
        raise OSError(errno.ENOSPC, ENOSPC)

    if not os.path.isdir("/proc/self/fd"):
        pytest.skip("needs /proc/self/fd to name the file written")
    monkeypatch.setattr(os, "pwrite", full_pwrite)
    monkeypatch.setattr(os, "fsync", full_fsync)
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress", "--repair"]) == 2
    err = capsys.readouterr().err
    assert len(_lines(err)) == 1 and ENOSPC in err and "Traceback" not in err, err
    assert out.read_bytes() == damaged
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary
    monkeypatch.undo()
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress", "--repair"]) == 0
    assert out.read_bytes() == whole


def test_ctrl_c_under_dask_local_is_one_line(tmp_path):
    """Ctrl-C signals the whole process group (workers too): the command ends in one line,
    exit 130, whole chunks kept (each worker printed a traceback before: 38–63 lines)."""
    pytest.importorskip("distributed")
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC.replace("samples = 6", "samples = 60000").replace(
        "chunk_size = 2", "chunk_size = 2000"))  # fmt: skip
    out = tmp_path / "r.csv"
    cmd = [sys.executable, "-m", "mrclutch", "sweep", str(spec), "--out", str(out),
           "--no-progress", "--dask-local", "2"]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # fmt: skip
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline and proc.poll() is None:
        if out.exists() and out.read_text().count("\n") > 2001:  # a chunk written
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C
    _, err = proc.communicate(timeout=120)
    if proc.returncode != 0 and "LocalCluster" in err and "OSError" in err:
        pytest.skip(f"distributed cannot start a cluster here: {err[-300:]}")
    if proc.returncode == 0:
        pytest.skip("the sweep finished before it could be interrupted")
    assert proc.returncode == 130, err
    assert _lines(err) == [ln for ln in _lines(err) if "interrupted after" in ln], err
    assert len(_lines(err)) == 1 and "Traceback" not in err, err
    rows = out.read_text().count("\n") - 1
    assert 0 < rows < 60000 and rows % 2000 == 0
