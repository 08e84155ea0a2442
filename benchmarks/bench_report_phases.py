"""Where the report's time goes, in both of its processes (issue 40: report ≤ 8 s).

    python benchmarks/bench_report_phases.py [--preset paper] [--out DIR]

Runs ``mrclutch report`` once in this process and prints a timeline: for each step of the
report's own process (its ``tick`` lines) and each task of its CAD process
(``mrclutch.cli.report_cad``: build123d's import with the B-rep mass, the CAD files, the
view's pixels), the wall time since the start and the process's CPU time, and every wait
of the report for a CAD result with how long it lasted. The report's process is the
critical path when it never waits; the CAD process when the waits are long. The CAD
process runs as the report starts it, with its deferred imports (``defer_imports``), from
a small wrapper that adds its timestamps. Times are this machine's under its load (the
load average is printed); compare the CPU columns. Each line also gives the megabytes the
process has read from the disk so far (``read_bytes`` of ``/proc/self/io``: 0 when the
libraries are in the page cache; a cold cache, after a reboot or
``echo 3 > /proc/sys/vm/drop_caches``, reads OpenCascade's and VTK's libraries from the
disk). ``PYTHONPATH=DIR`` with the working
folder DIR times another checkout (one without the deferral runs its CAD process without).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The CAD process, timed: the module's own ``__main__`` steps, each task wrapped.
CHILD = r"""
import os, sys, time
t0 = float(os.environ["BENCH_REPORT_T0"])
sys.path.insert(0, os.environ["BENCH_REPORT_DIR"])
from bench_report_phases import _disk as disk  # this script's own reading of the disk
def log(what):
    print(f"cad    {time.time() - t0:7.2f} s  cpu {time.process_time():6.2f} s  disk {disk()}  "
          f"{what}", file=sys.stderr, flush=True)
log("started")
import mrclutch.cli.report_cad as rc
log("its modules imported")
jobs = rc._jobs
def timed(design, folder):
    def wrap(name, job):
        def run():
            log(f"{name} begins")
            value = job()
            log(f"{name} done")
            return value
        return run
    return {name: wrap(name, job) for name, job in jobs(design, folder).items()}
rc._jobs = timed
from multiprocessing.connection import Connection
rc._die_with(int(sys.argv[3]))
getattr(rc, "defer_imports", lambda: None)()  # none before 2026-11-28's
rc._serve(Connection(int(sys.argv[1]), writable=False),
          Connection(int(sys.argv[2]), readable=False))
"""


def _disk() -> str:
    """Megabytes this process has read from the disk (``/proc/self/io``), or ``?``."""
    try:
        with open("/proc/self/io") as f:
            io = dict(line.split(": ") for line in f.read().splitlines())
        return f"{int(io['read_bytes']) / 1e6:6.0f} MB"
    except (OSError, KeyError, ValueError):
        return "     ? MB"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--out", type=Path, default=None, help="report folder (default: temporary)")
    args = ap.parse_args()
    t0 = time.time()
    os.environ["BENCH_REPORT_T0"] = repr(t0)
    os.environ["BENCH_REPORT_DIR"] = str(Path(__file__).resolve().parent)

    def log(what: str) -> None:
        print(f"report {time.time() - t0:7.2f} s  cpu {time.process_time():6.2f} s  "
              f"disk {_disk()}  {what}", file=sys.stderr, flush=True)  # fmt: skip

    print(f"load average before: {os.getloadavg()[0]:.2f}", file=sys.stderr)
    log("started")
    real_popen = subprocess.Popen

    class Popen(real_popen):  # type: ignore[misc, valid-type]
        def __init__(self, cmd, *a, **k):  # type: ignore[no-untyped-def]
            if "mrclutch.cli.report_cad" in cmd:  # [python, -m, module, fds, parent]
                i = cmd.index("-m")
                cmd = [*cmd[:i], "-c", CHILD, *cmd[i + 2 :]]
                log("CAD process started")
            super().__init__(cmd, *a, **k)

    subprocess.Popen = Popen  # type: ignore[misc]
    import mrclutch.cli.commands.report_command as command
    import mrclutch.cli.report_cad as rc
    from mrclutch.cli.main import main as cli

    log("report's modules imported")
    result = rc.CadProcess.result

    def waited(self, name):  # type: ignore[no-untyped-def]
        t = time.time()
        value = result(self, name)
        log(f"waited {time.time() - t:.2f} s for the CAD process's {name}")
        return value

    rc.CadProcess.result = waited  # type: ignore[method-assign]
    write = command.write_report

    def write_report(design, out, **kw):  # type: ignore[no-untyped-def]
        tick = kw["progress"]
        kw["progress"] = lambda msg: (log(f"step: {msg[:60]}"), tick(msg))
        return write(design, out, **kw)

    command.write_report = write_report
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp) / "report"
        code = cli(["report", "--preset", args.preset, "--out", str(out), "--no-progress"])
    log(f"ended (exit {code})")
    print(f"load average after: {os.getloadavg()[0]:.2f}", file=sys.stderr)


if __name__ == "__main__":
    main()
