"""Figures quoted in README.md and docs/*.md, produced by the commands that measure them.

A quoted figure is a marked span in the Markdown::

    b1 = <!-- fig: paper_b1 -->0.268<!-- /fig --> N·s/m

and its KEY has an entry in ``docs/figures.toml``::

    [paper_b1]
    command = "mrclutch evaluate --preset paper --json"   # run once per run, output cached
    json = "haptic.b1_N_s_per_m"     # a path into the JSON output (dots; list indices)
    # regex = 'b1 ([0-9.]+)'        # or: the first group of a regex over the text output
    # file = "{tmp}/metrics.json"   # read this file (JSON) the command wrote instead of stdout
    # expr = "100 * (v[0] / v[1] - 1)"  # with json = [path, path]: a derived figure
    scale = 1.0                       # multiply the extracted value (units of the text)
    format = "{:.3f}"                 # how the span is written (default "{:.3g}")
    tolerance = 0.01                  # relative; or abs_tolerance = ...; or both (the larger)
    # slow = true                     # the command takes more than a few seconds
    # historical = true               # what a past version measured: kept as written, exempt
    # factor = 30                     # a timing: within ×/÷ factor of what the command prints
    # measured_on = "..."             # a timing's machine (required with factor)

``python -m mrclutch.docs_figures`` runs every command once and rewrites the spans;
``--check`` only compares (exit 1 on a difference); ``tests/test_doc_figures.py`` runs the
check in the test suite, timings (``factor``) excepted: the suite checks a timing's form
(a positive number) and that its machine is recorded, never its value (a wall-clock figure
asserted in the suite is a flaky test, issue 40); ``--check`` and the benchmark that
prints it check its value. A quoted value passes when it is within its tolerance of what the
command prints, plus half a unit of its last written digit (a rounded figure is not a
difference).

Commands starting with ``mrclutch`` or ``python`` run with this interpreter and this
checkout first on ``PYTHONPATH``; ``{tmp}`` in a command or a ``file`` is a scratch folder
of the run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shlex
import subprocess
import sys
import tempfile
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from geometry.atomic import write_text

ROOT = Path(__file__).resolve().parents[1]
REGISTRY = ROOT / "docs" / "figures.toml"
#: A marked figure; one written in inline code (`<!-- fig: ...`, as in this docstring's
#: Markdown twin in the README) is an example, not a figure.
SPAN = re.compile(r"(?<!`)<!-- fig: ([A-Za-z0-9_.\-]+) -->(.*?)<!-- /fig -->", re.S)
NUMBER = re.compile(r"[-−+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+−]?\d+)?")
_KEYS = {
    "command",
    "json",
    "regex",
    "file",
    "expr",
    "scale",
    "format",
    "tolerance",
    "abs_tolerance",
    "factor",
    "slow",
    "historical",
    "note",
    "measured_on",
}


@dataclass(frozen=True)
class Figure:
    key: str
    command: str = ""
    json: str | tuple[str, ...] | None = None
    regex: str | None = None
    file: str | None = None
    expr: str | None = None
    scale: float = 1.0
    format: str = "{:.3g}"
    tolerance: float = 0.0
    abs_tolerance: float = 0.0
    factor: float = 1.0
    slow: bool = False
    historical: bool = False
    measured_on: str = ""

    def __post_init__(self):
        if self.historical:
            return
        if not self.command:
            raise ValueError(f"figure {self.key!r}: command is empty (give the command to run)")
        if (self.json is None) == (self.regex is None):
            raise ValueError(f"figure {self.key!r}: give exactly one of json or regex")
        if self.tolerance < 0 or self.abs_tolerance < 0:
            raise ValueError(f"figure {self.key!r}: tolerances must be ≥ 0")
        if self.factor < 1:
            raise ValueError(f"figure {self.key!r}: factor = {self.factor} must be ≥ 1")
        if self.factor > 1 and not self.measured_on.strip():
            raise ValueError(f"figure {self.key!r}: a timing (factor > 1) needs measured_on "
                             "(the machine it was measured on)")  # fmt: skip
        if isinstance(self.json, tuple) and self.expr is None:
            raise ValueError(f"figure {self.key!r}: several json paths need an expr")

    def render(self, value: float) -> str:
        """The value as the span writes it (exponents without padding: 1.55e-2; − for minus)."""
        text = re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", self.format.format(value))
        return re.sub(r"^-", "−", text)  # the docs' minus sign (U+2212)


@dataclass(frozen=True)
class Span:
    path: Path
    line: int
    key: str
    text: str


@dataclass
class Runner:
    """Runs each command once and keeps its output for the run."""

    tmp: Path
    outputs: dict[str, str] = field(default_factory=dict)

    def run(self, command: str) -> str:
        if command not in self.outputs:
            argv = shlex.split(command.replace("{tmp}", str(self.tmp)))
            if argv[0] == "mrclutch":
                argv = [sys.executable, "-m", "mrclutch", *argv[1:]]
            elif argv[0] == "python":
                argv = [sys.executable, *argv[1:]]
            env = dict(os.environ)
            env["PYTHONPATH"] = os.pathsep.join(
                p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p
            )
            env.setdefault("OPENBLAS_NUM_THREADS", "1")
            proc = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True)
            if proc.returncode != 0:
                raise RuntimeError(
                    f"`{command}` exited {proc.returncode}: {proc.stderr.strip()[-500:]}"
                )
            self.outputs[command] = proc.stdout
        return self.outputs[command]


def load_registry(path: Path = REGISTRY) -> dict[str, Figure]:
    data = tomllib.loads(path.read_text())
    out = {}
    for key, entry in data.items():
        unknown = set(entry) - _KEYS
        if unknown:
            raise ValueError(f"figure {key!r}: unknown keys {sorted(unknown)} in {path.name}")
        entry = dict(entry)
        entry.pop("note", None)
        if isinstance(entry.get("json"), list):
            entry["json"] = tuple(entry["json"])
        out[key] = Figure(key=key, **entry)
    return out


def doc_files(root: Path = ROOT) -> list[Path]:
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]


def find_spans(files: list[Path] | None = None) -> list[Span]:
    spans = []
    for f in files or doc_files():
        text = f.read_text()
        for m in SPAN.finditer(text):
            spans.append(Span(f, text.count("\n", 0, m.start()) + 1, m.group(1), m.group(2)))
    return spans


_SEGMENT = re.compile(r"\[([^\]]*)\]|([^.\[\]]+)")


def _json_path(data, path: str):
    """``a.b.0.c``; ``rows[quantity=torque,method=fem].error_rel`` picks the first list item
    whose fields equal those values; ``rows[-1]`` indexes."""
    for m in _SEGMENT.finditer(path):
        sel, name = m.groups()
        if name is not None:
            data = data[int(name)] if isinstance(data, list) else data[name]
        elif "=" in sel:
            conds = [c.split("=", 1) for c in sel.split(",")]
            hits = [d for d in data if all(str(d.get(k)) == v for k, v in conds)]
            if not hits:
                raise KeyError(f"no item [{sel}] in {path!r}")
            data = hits[0]
        else:
            data = data[int(sel)]
    return data


def measure(fig: Figure, runner: Runner) -> float:
    """The figure's value, as the span would quote it (scaled), from its command."""
    out = runner.run(fig.command)
    if fig.file is not None:
        out = Path(fig.file.replace("{tmp}", str(runner.tmp))).read_text()
    if fig.json is not None:
        data = json.loads(out)
        paths = fig.json if isinstance(fig.json, tuple) else (fig.json,)
        values = [float(_json_path(data, p)) for p in paths]
    else:
        m = re.search(fig.regex, out, re.M)
        if m is None:
            raise RuntimeError(f"figure {fig.key!r}: {fig.regex!r} not in `{fig.command}`")
        values = [float(g.replace("−", "-")) for g in m.groups()]
    if fig.expr is not None:
        names = {"v": values, "abs": abs, "min": min, "max": max, "math": math}
        value = float(eval(fig.expr, {"__builtins__": {}}, names))
    else:
        value = values[0]
    return value * fig.scale


def parse_quoted(text: str) -> tuple[float, float]:
    """The number a span quotes and half a unit of its last written digit."""
    m = NUMBER.search(text)
    if m is None:
        raise ValueError(f"no number in {text!r}")
    s = m.group(0).replace("−", "-")
    mant, _, exp = s.lower().partition("e")
    decimals = len(mant.partition(".")[2])
    half = 0.5 * 10.0 ** (-decimals + (int(exp) if exp else 0))
    return float(s), half


def difference(fig: Figure, quoted: str, value: float) -> str | None:
    """None when the quoted text agrees with the value within the figure's tolerance."""
    q, half = parse_quoted(quoted)
    if fig.factor > 1:  # timings: within a factor either way
        if value > 0 and q > 0 and 1 / fig.factor <= q / value <= fig.factor:
            return None
        return (
            f"quotes {quoted!r}, the command gives {fig.render(value)} (allowed ×/÷{fig.factor:g})"
        )
    allowed = max(fig.tolerance * abs(value), fig.abs_tolerance) + half
    if abs(q - value) <= allowed * (1 + 1e-12):
        return None
    return f"quotes {quoted!r}, the command gives {fig.render(value)} (allowed ±{allowed:.3g})"


def timing_form(fig: Figure, quoted: str) -> str | None:
    """None when a timing's quoted text is a positive finite number (its form, what the
    test suite checks of a timing; ``check(timings=True)`` compares its value)."""
    try:
        q, _ = parse_quoted(quoted)
    except ValueError:
        return f"quotes {quoted!r}: not a number"
    return None if math.isfinite(q) and q > 0 else f"quotes {quoted!r}: not a positive time"


def check(
    registry: dict[str, Figure],
    spans: list[Span],
    runner: Runner,
    keys=None,
    timings: bool = True,
) -> list[str]:
    """Every problem: unregistered keys, registered keys never quoted, and differences;
    with ``timings`` False a timing (factor > 1) is checked for its form only, its command
    not run (``timing_form``)."""
    problems = []
    quoted = {s.key for s in spans}
    for s in spans:
        if s.key not in registry:
            problems.append(f"{s.path.name}:{s.line}: {s.key} is not in docs/figures.toml")
    for key in sorted(set(registry) - quoted):
        problems.append(f"docs/figures.toml: {key} is quoted nowhere")
    values: dict[str, float] = {}
    for s in spans:
        fig = registry.get(s.key)
        if fig is None or fig.historical or (keys is not None and s.key not in keys):
            continue
        if fig.factor > 1 and not timings:
            diff = timing_form(fig, s.text)
            if diff:
                problems.append(f"{s.path.name}:{s.line}: {s.key} {diff}")
            continue
        if s.key not in values:
            values[s.key] = measure(fig, runner)
        diff = difference(fig, s.text, values[s.key])
        if diff:
            problems.append(f"{s.path.name}:{s.line}: {s.key} {diff}")
    return problems


def update(
    registry: dict[str, Figure],
    runner: Runner,
    files: list[Path] | None = None,
    retime: bool = False,
) -> int:
    """Rewrite every non-historical span with its command's value (a timing only when it is
    off by more than its factor, or always with ``retime``); the number of spans changed."""
    changed = 0
    values: dict[str, float] = {}
    for f in files or doc_files():
        text = f.read_text()

        def repl(m, f=f):
            nonlocal changed
            key, old = m.group(1), m.group(2)
            fig = registry.get(key)
            if fig is None:
                raise KeyError(f"{f.name}: {key} is not in docs/figures.toml")
            if fig.historical:
                return m.group(0)
            if key not in values:
                values[key] = measure(fig, runner)
            new = fig.render(values[key])
            if not retime and fig.factor > 1 and difference(fig, old, values[key]) is None:
                new = old  # a timing within its factor keeps its quote (no churn per run)
            if new != old:
                changed += 1
            return f"<!-- fig: {key} -->{new}<!-- /fig -->"

        new_text = SPAN.sub(repl, text)
        if new_text != text:
            write_text(f, new_text)  # the output layer: whole or untouched
    return changed


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m mrclutch.docs_figures",
        description="Run the commands of docs/figures.toml once each and rewrite the marked "
        "figures in README.md and docs/*.md (or, with --check, only compare them).",
    )
    p.add_argument("--check", action="store_true", help="compare only; exit 1 on a difference")
    p.add_argument("--retime", action="store_true",
                   help="rewrite the timings too (by default a timing within its factor "
                        "keeps its quote); run it on an idle machine")  # fmt: skip
    args = p.parse_args(argv)
    registry = load_registry()
    with tempfile.TemporaryDirectory(prefix="mrclutch-figs-") as tmp:
        runner = Runner(Path(tmp))
        if args.check:
            problems = check(registry, find_spans(), runner)
            for line in problems:
                print(line)
            print(f"{len(find_spans())} quoted figures, {len(problems)} problems")
            return 1 if problems else 0
        n = update(registry, runner, retime=args.retime)
        problems = check(registry, find_spans(), runner)
    for line in problems:
        print(line)
    print(f"{n} figures rewritten by {len(runner.outputs)} commands")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
