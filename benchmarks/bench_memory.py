"""Peak memory of every single-design command (issue 44: ≤ 1 GiB on any accepted input).

    python benchmarks/bench_memory.py [--designs paper,many,big,hot] [--only evaluate,...]
                                      [--timeout 600] [--json FILE]

Each command runs in a fresh process (``python -m mrclutch ...``, outputs in a temporary
folder); its peak resident set is ``ru_maxrss`` of that process alone (``os.wait4``), so
one command's peak never hides another's. Designs: the paper preset and extreme but
accepted ones (tests/mrclutch/test_json_walk.py's EXTREMES: 20 drums at a 0.1 mm gap and
1000 A; one 250 mm drum on a 2 m lever; a hot, slow, stiff bench) and ``huge`` (HUGE).
Prints a table (MiB, seconds, exit code) and the worst command; exits 1 if any accepted
command (exit 0) peaked above ``--limit-mib`` (default 1024).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "mrclutch"))

#: The commands (argv after the design arguments; ``{out}`` is a fresh output folder).
COMMANDS = {
    "evaluate": ["evaluate", "--json"],
    "evaluate-reference": ["evaluate", "--fidelity", "reference", "--json"],
    "evaluate-accuracy": ["evaluate", "--accuracy", "0.01", "--json"],
    "torque": ["torque", "--json"],
    "torque-fem": ["torque", "--method", "fem", "--json"],
    "field": ["field", "--plot", "{out}/field.png"],
    "inertia": ["inertia", "--json"],
    "export": ["export", "--out", "{out}/cad"],
    "compare": ["compare", "--json"],
    "haptic": ["haptic", "--json"],
    "scale": ["scale", "--json"],
    "device": ["device", "--out", "{out}/device.json"],
    "report": ["report", "--out", "{out}/report"],
}
#: Commands that build CAD solids or meshes: a chord height the large design accepts
#: (0.0001 × its size or more, geometry.cad.check_tolerance).
CAD = ("inertia", "export")


#: Beside test_json_walk's EXTREMES: 20 drums of 200 mm with 100 mm zones (inside the
#: Ø 0.3 m × 0.3 m envelope), whose FEM at the reference size (5.5e5 grid nodes, 3.1 GiB
#: estimated) the old 4 GiB budget accepted; refused now (grid.check_memory: exit 2).
HUGE = ('[clutch]\nbase = "paper"\nn_drums = 20\ndrum_inner_diameter_mm = 200\n'
        "zone_length_mm = 100\n")  # fmt: skip


def designs(folder: Path, names: list[str]) -> dict[str, list[str]]:
    from test_json_walk import EXTREMES

    out = {}
    for name in names:
        if name in ("paper", "paper-holes"):
            out[name] = ["--preset", name]
        else:
            path = folder / f"{name}.toml"
            path.write_text(HUGE if name == "huge" else EXTREMES[name])
            out[name] = [str(path)]
    return out


def peak(argv: list[str], timeout: float) -> tuple[float, float, int]:
    """(peak RSS [MiB], wall [s], exit code) of ``python -m mrclutch argv``; exit code -9
    when it ran past ``timeout`` and was killed."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    t = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "mrclutch", *argv], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)  # fmt: skip
    deadline = t + timeout
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        if time.perf_counter() > deadline:
            proc.kill()
            pid, status, usage = os.wait4(proc.pid, 0)
            break
        time.sleep(0.05)
    code = os.waitstatus_to_exitcode(status)
    return usage.ru_maxrss / 1024, time.perf_counter() - t, code  # Linux: kB


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", default="paper,many,big,hot")
    ap.add_argument("--only", default=",".join(COMMANDS), help="commands, comma-separated")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per command")
    ap.add_argument("--limit-mib", type=float, default=1024.0)
    ap.add_argument("--json", help="also write the rows as JSON to this file")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for dname, dargs in designs(folder, args.designs.split(",")).items():
            for cname in args.only.split(","):
                out = folder / f"{dname}-{cname}"
                out.mkdir()
                argv = [a.replace("{out}", str(out)) for a in COMMANDS[cname]]
                argv = [argv[0], *dargs, *argv[1:]]
                if cname in CAD and dname == "big":
                    argv += ["--tolerance-mm", "0.05"]
                mib, wall, code = peak(argv, args.timeout)
                rows.append({"design": dname, "command": cname, "peak_MiB": round(mib, 1),
                             "wall_s": round(wall, 1), "exit": code})  # fmt: skip
                print(f"{dname:<8} {cname:<20} {mib:8.1f} MiB {wall:7.1f} s  exit {code}",
                      flush=True)  # fmt: skip
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    ok = [r for r in rows if r["exit"] == 0]
    if ok:
        w = max(ok, key=lambda r: r["peak_MiB"])
        print(f"worst accepted: {w['command']} on {w['design']}: {w['peak_MiB']:.0f} MiB")
    over = [r for r in ok if r["peak_MiB"] > args.limit_mib]
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
