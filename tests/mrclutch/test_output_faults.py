"""Fault injection for the output layer (geometry.atomic): a full disk under every writer,
a closed or full standard output, targets that are not regular files.

The disk fills at the layer's fsync (where a delayed-allocation or network file system
reports ENOSPC) or, where the kernel lets a user mount one, on a real 256 KiB tmpfs. Each
writer must end in one line naming the file and the reason, exit 2, and leave no file."""

import errno
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from geometry.atomic import OutputError, atomic_path, write_bytes, write_text
from mrclutch.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
ENOSPC = os.strerror(errno.ENOSPC)


def _fd_path(fd: int) -> str:
    try:
        return os.readlink(f"/proc/self/fd/{fd}")
    except OSError:
        return ""


@pytest.fixture
def disk_full(monkeypatch):
    """``disk_full(suffix)``: from now on flushing a file whose name ends in ``suffix`` (a
    temporary's suffix is its target's) fails with ENOSPC."""
    real = os.fsync

    def arm(suffix: str = "") -> None:
        def fsync(fd: int) -> None:
            if _fd_path(fd).endswith(suffix) and not os.path.isdir(_fd_path(fd)):
                raise OSError(errno.ENOSPC, ENOSPC)
            real(fd)

        monkeypatch.setattr(os, "fsync", fsync)

    if not Path("/proc/self/fd").is_dir():
        pytest.skip("needs /proc/self/fd to name the file being flushed")
    return arm


#: Notes a command may print before its answer: the numba kernel's one-off compilation
#: (issue 31) on a machine whose cache is cold.
NOTES = (
    "mrclutch: compiling the reluctance network's solver",
    "mrclutch: compiling the network's torque reading",
    "mrclutch: compiled in ",
)  # magnetics.network.solve


def _one_line(err: str, *fragments: str) -> None:
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(NOTES)]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for f in fragments:
        assert f in lines[0], lines[0]


# ---- the layer itself ------------------------------------------------------------------


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, disk_full):
    dest = tmp_path / "a.json"
    dest.write_text("old")
    disk_full(".json")
    with pytest.raises(OutputError) as exc:
        write_text(dest, "new")
    assert str(exc.value) == f"{dest}: cannot write ({ENOSPC})"
    assert dest.read_text() == "old" and sorted(tmp_path.iterdir()) == [dest]


def test_an_oserror_in_the_body_is_one_line_and_the_temporary_goes(tmp_path):
    dest = tmp_path / "sub" / "x.png"
    with pytest.raises(OutputError, match=r"x\.png: cannot write \(Read-only file system\)"):
        with atomic_path(dest) as tmp:
            tmp.write_bytes(b"half")
            raise OSError(errno.EROFS, os.strerror(errno.EROFS))
    assert list((tmp_path / "sub").iterdir()) == []


def test_a_successful_write_is_flushed_then_renamed(tmp_path, monkeypatch):
    seen = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (seen.append(_fd_path(fd)), real(fd))[1])
    dest = write_bytes(tmp_path / "p.bin", b"abc")
    assert dest.read_bytes() == b"abc"
    assert oct(dest.stat().st_mode & 0o777) == oct(0o666 & ~_umask())
    assert any(Path(p).name.startswith(".p-") for p in seen)  # the temporary, before rename
    assert str(tmp_path) in seen  # then the folder's entry


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


def test_a_fifo_is_refused_not_replaced_and_a_link_is_written_through(tmp_path):
    fifo = tmp_path / "pipe.png"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match=r"pipe\.png: is a FIFO, not a regular file; not"):
        write_bytes(fifo, b"x")
    assert Path(fifo).is_fifo()
    target = tmp_path / "real.txt"
    target.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    write_text(link, "new")
    assert link.is_symlink() and target.read_text() == "new"


@pytest.mark.parametrize("option", [["compare", "--plot", "/dev/null"]])
def test_cli_refuses_a_device_node_before_any_work(option, capsys):
    assert main(option) == 2
    _one_line(capsys.readouterr().err, "/dev/null: is a character device", "not replaced")
    assert Path("/dev/null").is_char_device()


# ---- every writer on a full disk -------------------------------------------------------


def test_png_plot_on_a_full_disk(tmp_path, disk_full, capsys):
    disk_full(".png")
    out = tmp_path / "c.png"
    assert main(["compare", "--plot", str(out)]) == 2
    _one_line(capsys.readouterr().err, f"{out}: cannot write ({ENOSPC})")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", [".step", ".stl"])
def test_step_and_stl_export_on_a_full_disk(tmp_path, disk_full, capsys, suffix):
    disk_full(suffix)
    out = tmp_path / "cad"
    with _no_resource_warning():
        assert main(["export", "--out", str(out), "--tolerance-mm", "0.2", "--no-progress"]) == 2
    _one_line(capsys.readouterr().err, f"{suffix}: cannot write ({ENOSPC})")
    assert list(tmp_path.iterdir()) == []  # the folder it made, and what it wrote, are gone


class _no_resource_warning:
    """Fails when a file is left open (pytest turns ResourceWarning into an error only
    where the object is collected; collect here)."""

    def __enter__(self):
        import gc
        import warnings

        self._w = warnings.catch_warnings(record=True)
        self.caught = self._w.__enter__()
        warnings.simplefilter("always", ResourceWarning)
        gc.collect()
        return self

    def __exit__(self, *exc):
        import gc

        gc.collect()
        self._w.__exit__(*exc)
        leaks = [w for w in self.caught if issubclass(w.category, ResourceWarning)]
        assert not leaks, leaks[0].message
        return False


def test_html_report_on_a_full_disk(tmp_path, disk_full, capsys, monkeypatch):
    import mrclutch.cli.report as rep
    import mrclutch.report_data as report_data

    monkeypatch.setattr(report_data, "FEM_CHECK_CURRENTS", (7.0,))  # one FEM solve is enough
    monkeypatch.setattr(rep, "_view", lambda cad_side, design, path: write_bytes(path, b"png"))
    disk_full(".html")
    out = tmp_path / "rep"
    args = ["report", "--out", str(out), "--fidelity", "fast", "--no-progress"]
    assert main(args) == 2
    _one_line(capsys.readouterr().err, f"{out / 'report.html'}: cannot write ({ENOSPC})")
    assert list(tmp_path.iterdir()) == []  # staging folder gone, nothing moved in


SPEC = """
[sweep]
mode = "grid"
chunk_size = 4
[parameters]
gap_mm = {min = 0.2, max = 0.5, count = 3}
n_drums = {min = 1, max = 3}
"""


@pytest.mark.parametrize("name", ["r.csv", "r.parquet"])
def test_sweep_csv_and_parquet_on_a_full_disk(tmp_path, disk_full, capsys, name):
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC)
    out = tmp_path / "o" / name
    disk_full("")  # the first file the sweep writes fails
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress"]) == 2
    _one_line(capsys.readouterr().err, f"cannot write ({ENOSPC})", "o/")
    assert [p.name for p in tmp_path.iterdir()] == ["s.toml"] or not any((tmp_path / "o").iterdir())


# ---- standard output -------------------------------------------------------------------


def _cli(args: list[str], **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mrclutch", *args], capture_output=True,
                          text=True, env=ENV, cwd=ROOT, timeout=120, **kw)  # fmt: skip


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_json_to_a_full_disk_is_one_line():
    with open("/dev/full", "w") as full:
        r = subprocess.run([sys.executable, "-m", "mrclutch", "evaluate", "--json"],
                           stdout=full, stderr=subprocess.PIPE, text=True, env=ENV,
                           timeout=120)  # fmt: skip
    assert r.returncode == 2
    _one_line(r.stderr, f"standard output: cannot write ({ENOSPC})")


def test_a_closed_pipe_ends_quietly():
    p = subprocess.Popen([sys.executable, "-m", "mrclutch", "evaluate", "--json"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)  # fmt: skip
    first = p.stdout.read(1)  # `| head -c 1`: read one byte, then close the pipe
    p.stdout.close()
    err = p.stderr.read().decode()
    p.stderr.close()
    assert p.wait(timeout=120) in (0, 141)
    assert first == b"{" and err == ""


# ---- a real full disk (a 256 KiB tmpfs in a private mount namespace) --------------------


def _can_mount_tmpfs() -> bool:
    if shutil.which("unshare") is None:
        return False
    r = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k none /mnt"],
                       capture_output=True)  # fmt: skip
    return r.returncode == 0


@pytest.mark.slow
@pytest.mark.skipif(not _can_mount_tmpfs(), reason="cannot mount a tmpfs (no user namespaces)")
def test_every_writer_on_a_real_full_tmpfs(tmp_path):
    """A PNG on a full disk leaves nothing; a sweep that fills the disk keeps only whole,
    recorded chunks (no partial row), and once space is freed --resume completes it to the
    bytes of a run that never failed. 450 designs (123 KB of CSV) in chunks of 16: the disk
    fills after a few chunks all the same, and chunks of 4 (113 of them, each flushed and
    recorded) cost 2.5× the CPU time of one sweep."""
    spec = tmp_path / "s.toml"
    big = SPEC.replace("count = 3", "count = 150").replace("chunk_size = 4", "chunk_size = 16")
    assert "count = 150" in big and "chunk_size = 16" in big
    spec.write_text(big)
    assert main(["sweep", str(spec), "--out", str(tmp_path / "r.csv"), "--no-progress"]) == 0
    script = f"""
set -u
mount -t tmpfs -o size=256k none /mnt || exit 99
run() {{ name=$1; shift; {sys.executable} -m mrclutch "$@" >/dev/null 2>{tmp_path}/err.$name;
  echo "$name $? $(ls -A /mnt | tr '\\n' ' ')"; }}
dd if=/dev/zero of=/mnt/fill bs=1k count=220 2>/dev/null
run png compare --plot /mnt/c.png
run csv sweep {spec} --out /mnt/r.csv --no-progress
run parquet sweep {spec} --out /mnt/r.parquet --no-progress
rm /mnt/fill
run csv-resumed sweep {spec} --out /mnt/r.csv --resume --no-progress
mkdir {tmp_path}/back && cp /mnt/r.csv {tmp_path}/back/
"""
    r = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True,
                       env=ENV, cwd=ROOT, timeout=300)  # fmt: skip
    assert r.returncode == 0, r.stderr
    rows = {ln.split()[0]: ln.split()[1:] for ln in r.stdout.splitlines()}
    assert rows["png"] == ["2", "fill"]
    _one_line((tmp_path / "err.png").read_text(), f"/mnt/c.png: cannot write ({ENOSPC})")
    assert rows["csv"][:2] == ["2", "fill"]  # whole chunks kept: r.csv and its record
    _one_line((tmp_path / "err.csv").read_text(), "/mnt/r.csv", f"({ENOSPC})", "--resume")
    assert rows["csv-resumed"][0] == "0"
    assert (tmp_path / "back" / "r.csv").read_bytes() == (tmp_path / "r.csv").read_bytes()
    assert rows["parquet"] == ["2", "fill", "r.csv", "r.csv.meta.json"]  # no part fitted: none left
    _one_line((tmp_path / "err.parquet").read_text(), "/mnt/r.parquet", f"({ENOSPC})")
