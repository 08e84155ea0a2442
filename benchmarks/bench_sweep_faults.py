"""Sweep output under faults, on the real command line (issue 32's acceptance).

* a 2·10⁵-design sweep killed with SIGKILL at three points and resumed each time, for CSV
  and Parquet, against an uninterrupted run of the same spec: byte-identical (the results
  and their ``.meta.json`` record);
* two writers on one ``--out`` at once (a second one started while the uninterrupted run
  writes): the second is refused in one line, the first's file holds every design once;
* a damaged middle chunk (a CSV row deleted, a Parquet part truncated): ``--resume``
  refuses it naming the chunk, ``--repair`` restores the identical file recomputing that
  chunk only.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_sweep_faults.py [--designs 200000]
        [--format csv parquet]

Prints one line per check and exits 1 if any fails. The test suite runs the same checks on
small sweeps (tests/mrclutch/test_sweep_resume.py, test_output_faults.py).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}


def spec_text(designs: int, chunk: int) -> str:
    """A grid of ``designs`` designs: 4 drum counts × 100 gaps × the rest in thickness."""
    thick = designs // 400
    assert thick * 400 == designs, "--designs must be a multiple of 400"
    return f"""[sweep]
mode = "grid"
chunk_size = {chunk}
[parameters]
n_drums = {{min = 1, max = 4}}
gap_mm = {{min = 0.2, max = 0.5, count = 100}}
drum_thickness_mm = {{min = 0.1, max = 0.4, count = {thick}}}
"""


def sweep(spec: Path, out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "mrclutch", "sweep", str(spec), "--out", str(out),
         "--no-progress", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, cwd=ROOT,
    )  # fmt: skip


def finish(p: subprocess.Popen) -> tuple[int, str, str]:
    out, err = p.communicate(timeout=600)
    return p.returncode, out, err


def recorded(out: Path) -> int:
    try:
        return len(json.loads(out.with_name(out.name + ".meta.json").read_text())["chunks"])
    except (OSError, ValueError, KeyError):
        return 0


def files(out: Path) -> dict[str, bytes]:
    """Every byte of a result: the CSV or each part, and the ``.meta.json``."""
    meta = out.with_name(out.name + ".meta.json")
    got = {meta.name: meta.read_bytes()}
    if out.is_dir():
        got.update({p.name: p.read_bytes() for p in sorted(out.iterdir())})
    else:
        got[out.name] = out.read_bytes()
    return got


def same(a: Path, b: Path) -> bool:
    fa, fb = files(a), files(b)
    rename = {k.replace(a.name, b.name): v for k, v in fa.items()}
    return rename == fb


def _rows(out: Path) -> list[int]:
    """The design ids of a result, in file order."""
    if out.is_dir():
        import pyarrow.parquet as pq

        return pq.read_table(out, columns=["design_id"])["design_id"].to_pylist()
    return [int(line.split(b",", 1)[0]) for line in out.read_bytes().splitlines()[1:]]


def written(out: Path) -> int:
    """Bytes written so far: the CSV's size, or the parts' total (temporaries included)."""
    try:
        if out.is_dir():
            return sum(p.stat().st_size for p in out.iterdir())
        return out.stat().st_size
    except OSError:  # a part renamed while we looked
        return 0


def killed_three_times(spec: Path, out: Path, n_chunks: int, total: int
                       ) -> tuple[list[str], int]:  # fmt: skip
    """Start, SIGKILL when a quarter, a half and three quarters of the reference's bytes are
    on disk (wherever the writer is: inside a chunk's write, before its record), resuming in
    between, then resume to the end. Returns what each kill left."""
    notes = []
    for i, frac in enumerate((0.25, 0.5, 0.75)):
        p = sweep(spec, out, *(["--resume"] if i else []))
        while written(out) < frac * total and p.poll() is None:
            time.sleep(0.005)
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
        p.stdout.close()
        p.stderr.close()
        k = recorded(out)
        tail = ""
        if out.is_file():
            meta = json.loads(out.with_name(out.name + ".meta.json").read_text())
            end = meta["chunks"][-1]["offset"] + meta["chunks"][-1]["bytes"]
            tail = f", {out.stat().st_size - end} bytes past the record"
        notes.append(f"kill {i + 1} at {frac:.0%}: {k}/{n_chunks} chunks recorded{tail}")
    code, _, _ = finish(sweep(spec, out, "--resume"))
    return notes, code


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", type=int, default=200_000)
    ap.add_argument("--chunk", type=int, default=10_000)
    ap.add_argument("--format", nargs="+", choices=("csv", "parquet"), default=["csv", "parquet"])
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    a = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-sweep-faults-"))
    spec = work / "spec.toml"
    spec.write_text(spec_text(a.designs, a.chunk))
    n_chunks = -(-a.designs // a.chunk)
    ok = True

    def check(name: str, passed: bool, detail: str) -> None:
        nonlocal ok
        ok &= passed
        print(f"{'PASS' if passed else 'FAIL'}  {name}: {detail}", flush=True)

    try:
        for ext in a.format:
            # the uninterrupted run, with a second writer started on its --out while it runs
            ref = work / f"ref.{ext}"
            t = time.perf_counter()
            first = sweep(spec, ref)
            while not ref.with_name(ref.name + ".lock").exists() and first.poll() is None:
                time.sleep(0.01)
            code2, _, err2 = finish(sweep(spec, ref, "--overwrite"))
            code1, _, err1 = finish(first)
            t_ref = time.perf_counter() - t
            assert code1 == 0, err1
            size = sum(len(v) for v in files(ref).values())
            print(f"      uninterrupted {ext}: {a.designs} designs, {n_chunks} chunks, "
                  f"{size / 1e6:.1f} MB, {t_ref:.1f} s", flush=True)  # fmt: skip
            lines = [ln for ln in err2.splitlines() if ln.strip()]
            rows = _rows(ref)
            check(f"{ext}: two writers on one --out",
                  code2 == 2 and len(lines) == 1 and rows == list(range(a.designs)),
                  f"first exit {code1}, second exit {code2}: {lines[0] if lines else err2!r}; "
                  f"first's file holds designs 0..{a.designs - 1} once each: "
                  f"{rows == list(range(a.designs))}")  # fmt: skip

            out = work / f"killed.{ext}"
            total = sum(len(v) for k, v in files(ref).items() if not k.endswith(".meta.json"))
            notes, code = killed_three_times(spec, out, n_chunks, total)
            check(f"{ext}: SIGKILL ×3 then --resume", code == 0 and same(ref, out),
                  "; ".join(notes) + f"; byte-identical: {same(ref, out)}")  # fmt: skip

            bad = work / f"bad.{ext}"
            mid = n_chunks // 2
            if ext == "csv":
                shutil.copy(ref, bad)
                shutil.copy(ref.with_name(ref.name + ".meta.json"),
                            bad.with_name(bad.name + ".meta.json"))  # fmt: skip
                lines = bad.read_bytes().split(b"\n")
                row = 1 + mid * a.chunk + a.chunk // 2  # a row in the middle chunk
                bad.write_bytes(b"\n".join(lines[:row] + lines[row + 1 :]))
                damage = f"row {row - 1} deleted"
            else:
                shutil.copytree(ref, bad)
                shutil.copy(ref.with_name(ref.name + ".meta.json"),
                            bad.with_name(bad.name + ".meta.json"))  # fmt: skip
                part = sorted(bad.iterdir())[mid]
                part.write_bytes(part.read_bytes()[: len(part.read_bytes()) // 2])
                damage = f"{part.name} truncated to half"
            code, _, err = finish(sweep(spec, bad, "--resume"))
            lines = [ln for ln in err.splitlines() if ln.strip()]
            check(f"{ext}: damaged middle chunk ({damage}) --resume",
                  code == 2 and len(lines) == 1 and f"chunk {mid} " in lines[0],
                  f"exit {code}: {lines[0] if lines else err!r}")  # fmt: skip
            t = time.perf_counter()
            code, outp, err = finish(sweep(spec, bad, "--repair"))
            t_fix = time.perf_counter() - t
            check(f"{ext}: --repair", code == 0 and same(ref, bad),
                  f"exit {code}, {outp.splitlines()[0] if outp else err!r}, {t_fix:.1f} s "
                  f"(the whole sweep {t_ref:.1f} s); byte-identical: {same(ref, bad)}")  # fmt: skip
    finally:
        if a.keep:
            print(f"work folder: {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
