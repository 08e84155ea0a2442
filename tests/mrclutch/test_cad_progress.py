"""``export`` (STEP) and ``view`` say how far they are on stderr (issue 40: ~8 s and ~11 s
idle, silent before): a bar of their steps with its estimate, the CAD kernel's import its
first step; stdout unchanged; Ctrl-C one line, exit 130. The CAD work itself is replaced by
stand-ins here (test_cli_geometry.py runs the real export and view)."""

from __future__ import annotations

import re
from pathlib import Path
from types import SimpleNamespace

import pytest

import mrclutch.cli.commands.geometry as geo
from mrclutch.cli.main import main

BAR_DONE = r"{}: 100%\|[^|]*\| {n}/{n} \[\d\d:\d\d<\d\d:\d\d"


@pytest.fixture
def loads(monkeypatch):
    """The CAD kernel's import, recorded instead of run."""
    seen: list[str] = []
    monkeypatch.setattr(geo, "_load_cad", lambda: seen.append("build123d"))
    return seen


def _result(out: Path) -> SimpleNamespace:
    return SimpleNamespace(step=out / "clutch.step", materials=out / "clutch.materials.json",
                           stl={"rotor": out / "rotor.stl", "shaft": out / "shaft.stl"},
                           stl_triangles={"rotor": 120, "shaft": 48},
                           notes=("rotor.stl: a note",))  # fmt: skip


def test_export_bar_on_stderr_stdout_the_files_alone(tmp_path, capsys, monkeypatch, loads):
    """Two steps, each named above the bar (the kernel loaded, then the solids and files),
    2/2 with tqdm's estimate at the end; stdout the files written and the notes, as before."""
    out = tmp_path / "cad"
    monkeypatch.setattr(geo, "export_cad", lambda design, folder, tol: _result(Path(folder)))
    assert main(["export", "--preset", "paper", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    assert loads == ["build123d"]
    first = "export: loading the CAD kernel (build123d)\n"
    second = "export: the solids, clutch.step, the STL files, clutch.step read back\n"
    assert cap.err.index(first) < cap.err.index(second)
    assert re.search(BAR_DONE.format("export", n=2), cap.err)
    assert cap.out == (f"{out / 'clutch.step'}\n{out / 'clutch.materials.json'}  (material and "
                       "density of every solid: mrclutch inertia reads it)\n"
                       f"{out / 'rotor.stl'}  (120 triangles)\n{out / 'shaft.stl'}  (48 "
                       "triangles)\nnote: rotor.stl: a note\n")  # fmt: skip


def test_export_ctrl_c_is_one_line_and_exit_130(tmp_path, capsys, monkeypatch, loads):
    def interrupted(*_a):
        raise KeyboardInterrupt

    monkeypatch.setattr(geo, "export_cad", interrupted)
    assert main(["export", "--preset", "paper", "--out", str(tmp_path / "cad")]) == 130
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.endswith("\nmrclutch export: interrupted\n")
    assert "Traceback" not in cap.err


def test_other_formats_draw_no_bar(tmp_path, capsys, loads):
    """A DXF needs no CAD kernel: no bar, nothing loaded."""
    assert main(["export", "--preset", "paper", "--format", "dxf", "--out",
                 str(tmp_path)]) == 0  # fmt: skip
    cap = capsys.readouterr()
    assert loads == [] and "%|" not in cap.err and cap.out.strip().endswith(".dxf")


def test_view_screenshot_bar_on_stderr_stdout_the_file(tmp_path, capsys, monkeypatch, loads):
    shots = []

    def shot(clutch, path, tolerance=None):
        shots.append(path)
        return Path(path)

    monkeypatch.setattr(geo, "screenshot", shot)
    png = tmp_path / "v.png"
    assert main(["view", "--preset", "paper", "--screenshot", str(png)]) == 0
    cap = capsys.readouterr()
    assert loads == ["build123d"] and shots == [str(png)]
    assert cap.err.index("view: loading the CAD kernel (build123d)\n") < cap.err.index(
        f"view: the solids tessellated and rendered into {png}\n")  # fmt: skip
    assert re.search(BAR_DONE.format("view", n=2), cap.err)
    assert cap.out == f"{png}\n"


def test_view_window_loads_under_its_bar_then_opens(capsys, monkeypatch, loads):
    """The window's view: one step (the kernel) under the bar, the window after it ends."""
    order = []
    monkeypatch.setattr(geo, "show", lambda clutch, tolerance=None: order.append("window"))
    assert main(["view", "--preset", "paper"]) == 0
    cap = capsys.readouterr()
    assert loads == ["build123d"] and order == ["window"]
    assert re.search(BAR_DONE.format("view", n=1), cap.err) and cap.out == ""


def test_drawing_bar_on_stderr_stdout_the_file(tmp_path, capsys, loads):
    """``export --format drawing`` (~2 s, most of it matplotlib's import): a bar of its two
    steps, each named; stdout the SVG's path alone, the SVG whole; no CAD kernel loaded."""
    assert main(["export", "--preset", "paper", "--format", "drawing", "--out",
                 str(tmp_path)]) == 0  # fmt: skip
    cap = capsys.readouterr()
    svg = tmp_path / "paper.svg"
    assert cap.out == f"{svg}\n" and svg.read_text().rstrip().endswith("</svg>")
    assert cap.err.index("export: loading matplotlib\n") < cap.err.index(
        f"export: drawing {svg}\n")  # fmt: skip
    assert re.search(BAR_DONE.format("export", n=2), cap.err) and loads == []
