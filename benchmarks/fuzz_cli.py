"""Fuzz the command line in process: ``mrclutch.cli.main.main([...])`` on random inputs.

    python benchmarks/fuzz_cli.py [--n 10000] [--seed 0] [--workers 2] [--mem-gb 4]

Each input is either a design file whose values are drawn from extremes (0, negative, NaN,
±inf, 1e±300, huge integers, fractions for integer fields, strings, booleans) run through a
fast command (``evaluate --fidelity fast``, ``haptic``, ``torque``, ``scale``, ``inertia``
is left out: CAD takes seconds), or random flags and values for those commands. The
reference fidelity, FEM and the file-writing options are left out for speed (their bad
input is covered by tests/mrclutch/test_cli_errors.py).

Counted, per input:

* ``traceback``: an exception escaping ``main`` (anything but SystemExit 0/2, or a return
  code other than 0, 2, 3 and 130);
* ``nan``: ``nan`` printed (text or JSON) without any ``note`` in the output;
* ``memory``: MemoryError, or the worker killed; each worker runs under
  ``resource.setrlimit(RLIMIT_AS)`` so a blowup fails fast instead of swapping;
* ``slow``: an input that took more than ``--timeout`` seconds (SIGALRM).

Workers are child processes (this script with ``--child``); the parent restarts a worker
after a crash at the next input and prints the counts and a few examples of each class.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import random
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Values a fuzzed field or flag takes (strings as they appear in TOML / on the command line).
EXTREMES = ["0", "-1", "-0.0", "nan", "inf", "-inf", "1e300", "-1e300", "1e-300", "1e-18",
            "1e18", "100000000000000000000000000000", "2.5", "0.5", "1", "7", "1e6", "-1e6",
            "3.0e-4", '"x"', "true", "[1, 2]", "{a = 1}"]  # fmt: skip
ARG_EXTREMES = ["0", "-1", "nan", "inf", "-inf", "1e300", "1e-300", "1e-18", "1e18", "2.5",
                "x", "", "1e999", "-0", "3", "0.001", "1000000"]  # fmt: skip
SECTIONS = ("clutch", "operating", "transmission", "amplifier", "support", "laminations")
COMMANDS = {  # command -> its flags that take a value (fuzzed) and its switches
    "evaluate": (["--accuracy"], ["--json"], ["--fidelity", "fast"]),
    "haptic": (
        ["--lever-mm", "--gearing", "--stiffness", "--delay-ms", "--workspace-mm"],
        ["--json"],
        [],
    ),
    "compare": (["--stiffness", "--delay-ms", "--workspace-mm"], ["--json"], []),
    "torque": (
        ["--current", "--speed-rpm", "--fluid-temperature-C"],
        ["--json"],
        ["--method", "circuit"],
    ),
    "scale": (["--factor"], ["--json"], []),
}
DESIGN_COMMANDS = ("evaluate", "torque", "scale")
OK_CODES = {0, 2, 3, 130}
NAN = re.compile(r"(?<![A-Za-z_])nan(?![A-Za-z_])", re.I)


def preset_keys() -> dict[str, list[str]]:
    """Every key of the paper preset's design file, by section."""
    import tomllib

    from mrclutch.design import design_preset, design_to_toml

    doc = tomllib.loads(design_to_toml(design_preset("paper")))
    return {s: list(v) for s, v in doc.items() if isinstance(v, dict)}


def make_input(rng: random.Random, keys: dict[str, list[str]], folder: Path, k: int) -> list[str]:
    """One fuzzed argv (writes its design file into ``folder`` when it has one)."""
    cmd = rng.choice(DESIGN_COMMANDS if rng.random() < 0.6 else tuple(COMMANDS))
    valued, switches, fixed = COMMANDS[cmd]
    argv = [cmd, *fixed]
    if cmd in DESIGN_COMMANDS and rng.random() < 0.85:
        lines: dict[str, list[str]] = {}
        for _ in range(rng.randint(1, 4)):
            section = rng.choice([s for s in SECTIONS if s in keys])
            key = rng.choice(keys[section] + ["unknown_key_mm"])
            if rng.random() < 0.5:
                value = rng.choice(EXTREMES)
            else:  # a plausible number, scaled by a random factor
                value = repr(rng.choice([1.0, -1.0]) * 10 ** rng.uniform(-6, 6))
            lines.setdefault(section, []).append(f"{key} = {value}")
        text = "".join(
            f"[{s}]\n" + ('base = "paper"\n' if s == "clutch" else "") + "\n".join(v) + "\n"
            for s, v in lines.items()
        )
        path = folder / f"d{k}.toml"
        path.write_text(text)
        argv.append(str(path))
    elif rng.random() < 0.2:
        argv += ["--preset", rng.choice(["paper", "paper-holes", "nope", ""])]
    for flag in rng.sample(valued, rng.randint(0, len(valued))):
        argv += [flag, rng.choice(ARG_EXTREMES)]
    argv += [s for s in switches if rng.random() < 0.5]
    if rng.random() < 0.03:
        argv.append(rng.choice(["--bogus", "-x", "--json=1", "extra"]))
    return argv


def run_one(argv: list[str], timeout: float) -> tuple[str, str]:
    """(class, detail) of one call of main: ok, traceback, nan, memory or slow."""
    from mrclutch.cli.main import main

    out, err = io.StringIO(), io.StringIO()

    def alarm(signum, frame):
        raise TimeoutError(f"more than {timeout:g} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 2
        if code not in (0, 2):
            return "traceback", f"SystemExit({exc.code!r})"
    except MemoryError:
        return "memory", "MemoryError"
    except TimeoutError as exc:
        return "slow", f"{argv[0]}: {exc}"
    except Exception as exc:
        return "traceback", f"{type(exc).__name__}: {str(exc)[:160]}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    if code not in OK_CODES:
        return "traceback", f"exit code {code!r}"
    text = out.getvalue()
    if NAN.search(text) and "note" not in text.lower():
        line = next(ln for ln in text.splitlines() if NAN.search(ln))
        return "nan", line.strip()[:160]
    return "ok", str(code)


def child(args: argparse.Namespace) -> None:
    """Run inputs start..stop; one JSON line per input on stdout (flushed)."""
    limit = int(args.mem_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    import warnings

    warnings.simplefilter("ignore")
    keys = preset_keys()
    report = sys.stdout
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.start, args.stop):
            rng = random.Random(f"{args.seed}-{k}")
            argv = make_input(rng, keys, Path(tmp), k)
            t = time.perf_counter()
            cls, detail = run_one(argv, args.timeout)
            rec = {"k": k, "class": cls, "detail": detail, "argv": argv,
                   "s": time.perf_counter() - t}  # fmt: skip
            files = [a for a in argv if a.endswith(".toml")]
            if cls != "ok" and files:
                rec["design"] = Path(files[0]).read_text()
            report.write(json.dumps(rec) + "\n")
            report.flush()


def worker(args: argparse.Namespace, start: int, stop: int) -> subprocess.Popen:
    cmd = [sys.executable, __file__, "--child", "--start", str(start), "--stop", str(stop),
           "--seed", str(args.seed), "--mem-gb", str(args.mem_gb), "--timeout",
           str(args.timeout)]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env=env)  # fmt: skip


def run_range(args: argparse.Namespace, start: int, stop: int) -> list[dict]:
    """Records of inputs start..stop from workers; a worker that dies (memory limit,
    segfault) is recorded as a memory failure at its input and restarted after it."""
    records: list[dict] = []
    while start < stop:
        proc = worker(args, start, stop)
        last = start - 1
        for line in proc.stdout:
            rec = json.loads(line)
            last = rec["k"]
            records.append(rec)
        proc.wait()
        if last + 1 < stop:
            records.append({"k": last + 1, "class": "memory", "argv": None,
                            "detail": f"worker died (exit {proc.returncode})"})  # fmt: skip
        start = last + 2
    return records


def parent(args: argparse.Namespace) -> int:
    from concurrent.futures import ThreadPoolExecutor

    t0 = time.perf_counter()
    counts = {"ok": 0, "traceback": 0, "nan": 0, "memory": 0, "slow": 0}
    examples: dict[str, dict[str, list]] = {c: {} for c in counts}
    step = math.ceil(args.n / args.workers)
    ranges = [(s, min(s + step, args.n)) for s in range(0, args.n, step)]
    with ThreadPoolExecutor(len(ranges)) as pool:
        parts = list(pool.map(lambda r: run_range(args, *r), ranges))
    for rec in (r for part in parts for r in part):
        counts[rec["class"]] += 1
        if rec["class"] != "ok":
            ex = examples[rec["class"]].setdefault(rec["detail"][:90], [0, rec])
            ex[0] += 1
    total = sum(counts.values())
    dt = time.perf_counter() - t0
    print(f"{total} fuzzed inputs in {dt:.0f} s ({total / dt:.0f}/s), seed {args.seed}, "
          f"RLIMIT_AS {args.mem_gb:g} GiB")  # fmt: skip
    for c, n in counts.items():
        print(f"  {c:<10} {n}")
    for c, exs in examples.items():
        for detail, (n, rec) in sorted(exs.items(), key=lambda t: -t[1][0])[: args.show]:
            print(f"{c}: {n}× {detail}\n    e.g. mrclutch {' '.join(rec.get('argv') or [])}")
            if rec.get("design"):
                print("    with " + rec["design"].strip().replace("\n", "\n         "))
    slowest = sorted((r for part in parts for r in part), key=lambda r: -r.get("s", 0))[:3]
    for r in slowest:
        print(f"slowest: {r.get('s', 0):.1f} s  mrclutch {' '.join(r.get('argv') or [])}")
    bad = counts["traceback"] + counts["nan"] + counts["memory"]
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000, help="inputs (default 10 000)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--mem-gb", type=float, default=4.0, help="RLIMIT_AS per worker, GiB")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds per input")
    ap.add_argument("--show", type=int, default=5, help="examples per class")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--start", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--stop", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args)
        return 0
    return parent(args)


if __name__ == "__main__":
    sys.exit(main())
