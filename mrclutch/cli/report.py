"""The design report: every artefact a person needs to judge one clutch design, in one folder.

``write_report(design, out_dir)`` writes

* ``clutch.step`` and ``<part>.stl`` (CAD, mm), ``clutch.materials.json`` (each STEP
  solid's material and density: ``mrclutch inertia clutch.step`` weighs it),
* ``view.png`` (3D, half-section cut) and ``section.png`` (r–z drawing),
* ``torque.png`` (torque–current: circuit curve with FEM points),
* ``haptic.png`` (Bode magnitude, effective stiffness and damping, rendering areas of
  the MR pair against the equal-force motor),
* ``zwidth.png`` (the Z-width: passive virtual springs and dampers of both),
* ``response.png`` (torque after a current step: the lags, their equivalent delay and the
  typed delay),
* ``metrics.json`` (exactly ``mrclutch evaluate --json`` at the same fidelity, plus the
  torque curve and the artefact list),
* ``report.html`` (one page, read first).

Everything is built in a temporary folder beside ``out_dir`` (``.<name>-partial-<pid>-…``)
and moved in only when all of it succeeded, so an error, Ctrl-C or ``kill`` (SIGTERM) never
leaves a half-written report: either signal stops the build at its next step (a second one at
once) and the staging folder is removed. The staging folders of processes that died harder
(SIGKILL, power loss) are removed by the next report into the same place.

The CAD side — build123d's import (seconds), the B-rep mass the evaluation uses, the STEP
and STL files and the 3D view's pixels (VTK) — runs in a second process
(``mrclutch.cli.report_cad``) started with the build, while this one solves the FEM and
draws the plots (issue 40); the evaluation waits for the mass, the last steps for the files
and the pixels (view.png's legend is drawn here, with the matplotlib loaded for the plots),
and a stopped build kills it before the staging folder goes.
"""

from __future__ import annotations

import html
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from geometry.atomic import OutputError, fsync_dir, output_error, write_text
from geometry.validation import ParameterError
from mrclutch.cli.duty_format import duty_html
from mrclutch.cli.feel_format import feel_html
from mrclutch.cli.jsonio import to_jsonable
from mrclutch.cli.plots.design import section_figure
from mrclutch.cli.plots.dynamics import plot_torque_step
from mrclutch.cli.plots.haptic import compare_figure, zwidth_figure
from mrclutch.cli.plots.magnetics import plot_torque
from mrclutch.cli.report_cad import CadProcess
from mrclutch.cli.view import compose
from mrclutch.design import ClutchDesign
from mrclutch.outputs import CLUTCH_ROWS, HAND_ROWS, output, row_label
from mrclutch.pipeline import evaluate
from mrclutch.report_data import design_mass_from, torque_curves
from mrclutch.sweep import sigterm_as_interrupt
from mrclutch.verdict import judge_evaluation


@dataclass(frozen=True)
class Report:
    out_dir: Path
    files: tuple[str, ...]
    metrics: dict[str, Any]


def write_report(
    design: ClutchDesign,
    out_dir: str | Path,
    *,
    fidelity: str = "reference",
    progress: Callable[[str], None] | None = None,
) -> Report:
    """Write the report of ``design`` into ``out_dir`` (see module docstring)."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"--out {out}: exists and is not a directory")
    out.parent.mkdir(parents=True, exist_ok=True)
    report = progress if progress is not None else (lambda _msg: None)
    remove_stale_partials(out)
    # deferred: CAD and the 3D view run C++ (OpenCascade, manifold3d, VTK) that a
    # KeyboardInterrupt raised inside cannot unwind through; the build stops between steps
    with sigterm_as_interrupt(deferred=True) as terminated:

        def check() -> None:
            if terminated.is_set():
                raise KeyboardInterrupt

        def tick(msg: str) -> None:
            check()
            report(msg)

        return _build(design, out, fidelity, tick, check)


def _partial_prefix(out: Path) -> str:
    return f".{out.name}-partial-"


def remove_stale_partials(out: Path) -> list[Path]:
    """Remove the staging folders beside ``out`` left by report processes that no longer
    run (the pid in the name); returns what was removed. Folders of live processes stay."""
    removed = []
    prefix = _partial_prefix(out)
    for p in out.parent.glob(f"{prefix}*"):
        pid, _, _ = p.name[len(prefix) :].partition("-")
        if p.is_dir() and pid.isdigit() and not _alive(int(pid)):
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    except OverflowError:  # not a pid at all
        return False
    return True


def _build(design: ClutchDesign, out: Path, fidelity: str, tick: Callable[[str], None],
           check: Callable[[], None]) -> Report:  # fmt: skip
    """The report built in a staging folder and moved into ``out``; a write that fails
    (disk full, read-only) is one OutputError naming the file under ``out``, and the
    staging folder goes."""
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f"{_partial_prefix(out)}{os.getpid()}-",
                                    dir=out.parent))  # fmt: skip
    except OSError as exc:
        raise output_error(out, exc) from None
    try:
        return _build_in(design, out, fidelity, tick, check, tmp)
    except OutputError as exc:  # name the file where the user will look for it
        raise OutputError(str(exc).replace(str(tmp), str(out))) from None
    except OSError as exc:
        raise output_error(Path(str(exc.filename or out).replace(str(tmp), str(out))),
                           exc) from None  # fmt: skip
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _build_in(design: ClutchDesign, out: Path, fidelity: str, tick: Callable[[str], None],
              check: Callable[[], None], tmp: Path) -> Report:  # fmt: skip
    # build123d's import (seconds), the B-rep mass, the CAD files and the 3D view run in a
    # second process while this one solves the FEM and draws (issue 40); it is killed and
    # waited for before the staging folder goes (_build's finally)
    cad_side = CadProcess(design, tmp, check)
    try:
        return _steps(design, out, fidelity, tick, tmp, cad_side)
    finally:
        cad_side.close()


def _steps(design: ClutchDesign, out: Path, fidelity: str, tick: Callable[[str], None],
           tmp: Path, cad_side: CadProcess) -> Report:  # fmt: skip
    tick("torque–current curve (network, circuit and FEM); a second process loads build123d "
         "for the B-rep mass, STEP/STL and 3D view")  # fmt: skip
    curve = _torque(design, tmp / "torque.png")
    tick("section drawing")
    section_figure(design.section(), tmp / "section.png")
    tick("evaluating the design" + (" (its B-rep mass from the CAD process)"
                                    if fidelity == "reference" else ""))  # fmt: skip

    with design_mass_from(design, lambda: cad_side.result("mass")):
        ev = evaluate(design, fidelity)
        data = judge_evaluation(ev)  # the design's `[render]` rule, its one verdict
    tick("haptic plots")
    k = float(data["haptic"]["K_N_per_m"])  # the K rendered (the design's `[render]` rule)
    sides = {"MR pair": ev.mr, "Maxon 136206 (equal force)": ev.motor}
    compare_figure({n: p for n, p in sides.items() if p is not None}, k, tmp / "haptic.png")
    zw = {"MR pair": ev.zwidth["mr"]}
    if ev.motor is not None:
        zw["Maxon 136206 (equal force)"] = ev.zwidth["motor"]
    zwidth_figure(zw, k, tmp / "zwidth.png")
    tick("torque step response")
    plot_torque_step([(design.name, ev.torque_response)], tmp / "response.png",
                     typed_delay=design.operating.delay)  # fmt: skip
    tick("the CAD files: STEP and STL (the second process)")
    cad = _cad(cad_side)
    tick("the 3D view (the second process)")
    _view(cad_side, design, tmp / "view.png")
    metrics = {**data, "torque_curve": curve, "cad": cad}
    write_text(tmp / "metrics.json", json.dumps(to_jsonable(metrics), indent=2) + "\n")
    tick("report.html")
    write_text(tmp / "report.html", render_html(metrics))
    files = tuple(sorted(p.name for p in tmp.iterdir()))
    tick("moving the files into place")
    out.mkdir(exist_ok=True)
    for name in files:
        (tmp / name).replace(out / name)
    fsync_dir(out)
    return Report(out, files, metrics)


def _cad(cad_side: CadProcess) -> dict[str, Any]:
    """The CAD files' names and volumes (report_data.export_cad, run by the CAD process)."""
    return cad_side.result("cad")


def _view(cad_side: CadProcess, design: ClutchDesign, path: Path) -> None:
    """view.png at ``path``: the model the CAD process rendered (its pixels) beside its
    legend, drawn here (mrclutch.cli.view.compose)."""
    compose(cad_side.result("view"), design.clutch, path)


def _torque(design: ClutchDesign, path: Path) -> dict[str, Any]:
    curves, data = torque_curves(design)
    plot_torque(curves, path, title=f"{design.name} at {data['speed_rpm']:.0f} rpm")
    return data


# ---- the one-page HTML -----------------------------------------------------------------


def _fmt(v: Any, scale: float = 1.0, digits: int = 4) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return f"{v * scale:.{digits}g}"


def findings(m: dict[str, Any]) -> list[str]:
    """Plain-language statements a designer should read first."""
    h, e, c = m["haptic"], m["motor"], m["clutch"]
    out = []  # the verdict itself is the badge above (verdict.verdict_of): said once
    rule = (m.get("render") or {}).get("describe", "K_max = F_max/d")
    kmax = f"K = {h['K_N_per_m']:.4g} N/m ({rule}, {m.get('source', 'model')})"
    gain = m["bandwidth_gain"]
    if gain is not None:
        out.append(
            f"At {kmax} the MR pair renders the "
            f"spring up to {h['bandwidth_hz']:.1f} Hz (the first k_eff crossing), the "
            f"equal-force Maxon 136206 up to {e['bandwidth_hz']:.1f} Hz ({gain * 100:+.0f} %); "
            f"hands off it is stable up to {h['max_stable_K_N_per_m']:.0f} N/m and passive up "
            f"to {h['max_passive_K_N_per_m']:.0f} N/m at nominal values."
        )
    hand = m.get("hand")
    if hand is not None and not hand["mr"].get("note") and not hand["motor"].get("note"):
        hm, he = hand["mr"], hand["motor"]
        mo = hm["motion"]
        out.append(
            f"In free motion (K = 0, ±{mo['amplitude_m'] * 1e3:g} mm at {mo['frequency_hz']:g} Hz)"
            f" the hand feels {hm['backdrive_force_N'] * 1e3:.3g} mN from the MR pair against "
            f"{he['backdrive_force_N'] * 1e3:.3g} mN from the motor."
        )
    if not h["passive"]:
        out.append(
            f"At nominal values, with its {h['delay_s'] * 1e3:.3g} ms delay and b1 = "
            f"{h['b1_N_s_per_m']:.3g} N·s/m, the MR pair stays passive only up to "
            f"{h['max_passive_K_N_per_m']:.0f} N/m: more drag (smaller gaps, more drums) or "
            "less delay raises that limit."
        )
    if e.get("note"):  # the equal-force motor is unavailable
        out.append(f"Reflected mass m1 = {h['m1_kg'] * 1e3:.3g} g, damping b1 = "
                   f"{h['b1_N_s_per_m']:.3g} N·s/m; no motor beside it: {e['note']}.")  # fmt: skip
    else:
        out.append(
            f"Reflected mass m1 = {h['m1_kg'] * 1e3:.3g} g against the motor's "
            f"{e['m1_kg'] * 1e3:.3g} g; damping b1 = {h['b1_N_s_per_m']:.3g} against "
            f"{e['b1_N_s_per_m']:.3g} N·s/m."
        )
    tc = m["torque_curve"]
    out.append(
        f"Torque at {c['max_current_A']:.3g} A: {c['max_torque_N_m']:.3g} N·m "
        f"({c['methods']['torque']}); circuit vs FEM differ by at most "
        f"{tc['circuit_vs_fem_max_error_rel'] * 100:.1f} %, the reluctance network vs FEM by "
        f"{tc['network_vs_fem_max_error_rel'] * 100:.1f} %, over the FEM check points."
    )
    out += [f"Note: {n}" for n in c["notes"]]
    return out


def budget_html(budget: dict[str, Any]) -> str:
    """b1 and m1 of the MR pair as tables of terms beside the paper's Table 2."""
    e_ = html.escape
    parts = ["<h2>Where b1 and m1 come from</h2><div class=grid>"]
    for key, unit, scale in (("b1_N_s_per_m", "N·s/m", 1.0), ("m1_kg", "g", 1e3)):
        b = budget[key]
        rows = "".join(
            f"<tr><td>{e_(t['name'])}</td><td class=n>{t['value'] * scale:.4g}</td>"
            f"<td class=n>{t['share'] * 100:.1f} %</td><td>{e_(t['source'])}</td></tr>"
            for t in b["terms"]
        )
        rows += f"<tr><th>total</th><th class=n>{b['total'] * scale:.4g}</th><th></th><th></th>"
        if budget["paper_clutch"]:
            rows += (f"</tr><tr><td>paper, Table 2</td><td class=n>"
                     f"{b['paper_table2'] * scale:.4g}</td><td></td><td></td></tr><tr><td>"
                     f"unexplained</td><td class=n>{b['unexplained'] * scale:.4g}</td><td></td>"
                     f"<td></td></tr>")  # fmt: skip
        else:  # Table 2 identified the paper's clutch, not this one
            rows += (f"</tr><tr><td>paper clutch, Table 2 (for scale)</td><td class=n>"
                     f"{b['paper_table2'] * scale:.4g}</td><td></td><td></td></tr>")  # fmt: skip
        why = "".join(f"<li>{e_(w)}</li>" for w in b.get("least_certain", ()))
        name = key.split("_")[0]
        parts.append(f"<div><h3>{name} ({unit})</h3><table>{rows}</table>"
                     + (f"<p class=small>Least certain:</p><ul class=small>{why}</ul>" if why
                        else "") + "</div>")  # fmt: skip
    t2 = budget["with_table2_b1"]
    if not budget["paper_clutch"]:
        parts.append("</div>")
        return "".join(parts)
    parts.append(
        f"</div><p class=small>With Table 2's b1 = {t2['b1_N_s_per_m']:g} N·s/m the pair is "
        f"{'passive' if t2['passive'] else 'not passive'} at K (largest passive K "
        f"{t2['max_passive_K_N_per_m']:.4g} N/m, largest stable K "
        f"{t2['max_stable_K_N_per_m']:.4g} N/m).</p>"
    )
    return "".join(parts)


def measured_html(rows: list[dict[str, Any]]) -> str:
    """The model against the bench's measurements (``[measured]``), error in %."""
    if not rows:
        return ""
    scale = {"N·m": (1.0, "N·m"), "s": (1e3, "ms"), "kg": (1e3, "g"), "N·s/m": (1.0, "N·s/m")}
    e_ = html.escape
    body = ""
    for r in rows:
        f, unit = scale[r["unit"]]
        body += (f"<tr><td>{e_(r['quantity'])} ({e_(unit)})</td><td class=n>"
                 f"{r['model'] * f:.4g}</td><td class=n>{r['measured'] * f:.4g}</td>"
                 f"<td class=n>{r['error'] * 100:+.1f} %</td>"
                 f"<td>{e_(r['model_source'])}</td></tr>")  # fmt: skip
    return ("<h2>Model against the bench</h2><table><tr><th></th><th>model</th>"
            f"<th>measured</th><th>error</th><th>model from</th></tr>{body}</table>")  # fmt: skip


def motor_caption(e: dict[str, Any]) -> str:
    """How the motor column was set up, or why it is empty."""
    if e.get("gearing") is None:
        return f"No motor column: {e.get('note', 'unavailable')}."
    return (f"Motor geared ×{e['gearing']:.3g} so both render the same maximum force; both "
            "render the same virtual spring K.")  # fmt: skip


def zwidth_caption(zw: dict[str, Any]) -> str:
    """One sentence on the Z-width of both sides (continuous time, with the delay)."""
    mr, em = zw["mr"], zw["motor"]
    if em.get("note"):
        em = {k: math.nan for k in mr}
    return (f"Passive (K, B) set with the actuator delay (continuous time, "
            f"mrclutch.haptics.zwidth): MR pair up to K = {mr['K_max_at_B0_N_per_m']:.4g} N/m "
            f"at B = 0 and B = {mr['B_max_at_K0_N_s_per_m']:.4g} N·s/m at K = 0, area "
            f"{mr['zwidth_area_N2_s_per_m2']:.4g} N²·s/m²; motor {em['K_max_at_B0_N_per_m']:.4g} "
            f"N/m, {em['B_max_at_K0_N_s_per_m']:.4g} N·s/m, area "
            f"{em['zwidth_area_N2_s_per_m2']:.4g} N²·s/m².")  # fmt: skip


def response_caption(r: dict[str, Any]) -> str:
    """One sentence on the torque response (magnetics.dynamics) and which delay is used."""
    used = "the equivalent delay" if r["delay_source"] == "geometry" else "the typed delay"
    return (f"Equivalent delay {r['torque_delay_s'] * 1e3:.3g} ms from the geometry "
            f"(typed: {r['typed_delay_s'] * 1e3:.3g} ms); largest stable K "
            f"{r['max_stable_K_torque_delay_N_per_m']:.4g} N/m with it, "
            f"{r['max_stable_K_typed_delay_N_per_m']:.4g} N/m with the typed delay. The haptic "
            f"figures above use {used} (delay_source = \"{r['delay_source']}\"; "
            f"docs/dynamics.md).")  # fmt: skip


def verdict_badge(m: dict[str, Any]) -> str:
    """The design's one verdict (``mrclutch.verdict.verdict_of``) as the page's first block:
    the status word, its sentence and, labelled as the second verdict, the hand-held case."""
    v = m["verdict"]
    e_ = html.escape
    return (f'<div class="verdict {e_(v["status"])}" id="verdict"><b>Verdict: '
            f'{e_(v["status"].upper())}</b> — {e_(v["line"].split(" — ", 1)[1])}<br>'
            f'<span class=small>{e_(v["hand"]["line"])}</span></div>')  # fmt: skip


def render_html(m: dict[str, Any]) -> str:
    """One page: findings, the clutch, the hand, the figures, the files."""
    c, h, e = m["clutch"], m["haptic"], m["motor"]
    e_ = html.escape
    capped = any("caps the current" in n or "supply holds at most" in n for n in c["notes"])
    clutch_rows = [
        (output(k).label + (" (capped: see the note above)" if capped and k == "max_current_A"
                            else ""), output(k).display(c[k]), output(k).shown_unit)
        for k in CLUTCH_ROWS
    ]  # fmt: skip
    d, length = c["envelope_m"]
    clutch_rows.append(("envelope", f"Ø{d * 1e3:.3g} × {length * 1e3:.3g}", "mm"))
    rows1 = "".join(
        f"<tr><td>{e_(a)}</td><td class=n>{e_(b)}</td><td>{e_(u)}</td></tr>"
        for a, b, u in clutch_rows
    )
    rows2 = "".join(
        f"<tr><td>{e_(row_label(k))}</td><td class=n>{output(k).display(h[k])}</td>"
        f"<td class=n>{output(k).display(e[k])}</td></tr>"
        for k in HAND_ROWS
    )
    items = "".join(f"<li>{e_(s)}</li>" for s in findings(m))
    budget = budget_html(m["budget"]) if "budget" in m else ""
    budget = measured_html(m.get("measured") or []) + budget
    duty = duty_html(m["duty"]) if m.get("duty") else ""  # issue 41 (docs/hot.md)
    duty += feel_html(m.get("feel") or {})  # issue 41 (docs/hysteresis.md)
    stl = ", ".join(f'<a href="{e_(p)}">{e_(p)}</a>' for p in m["cad"]["stl"].values())
    methods = ", ".join(f"{k}: {v}" for k, v in c["methods"].items())
    side = m["cad"].get("materials") or ""
    cad_notes = "".join(f"<p class=small>Note: {e_(n)}</p>" for n in m["cad"].get("notes", ()))
    page = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>mrclutch report: {e_(m["design"])}</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body{{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}}
p,li,h1,h2,h3{{overflow-wrap:anywhere}}
.scroll{{overflow-x:auto;max-width:100%}}
table{{border-collapse:collapse;margin:.5em 0 1.5em}}
td,th{{padding:.2em .8em;border-bottom:1px solid #ddd}}
td.n{{text-align:right;font-variant-numeric:tabular-nums}}
img{{max-width:100%;height:auto;border:1px solid #eee;box-sizing:border-box}}
.grid{{display:grid;grid-template-columns:1fr 1fr;gap:1em}} .grid>div{{min-width:0}}
.small{{color:#666;font-size:.9em}}
.verdict{{padding:.6em 1em;border-radius:6px;margin:1em 0;border:2px solid}}
.verdict.pass{{background:#e6f4ea;border-color:#2e7d32}}
.verdict.fail{{background:#fdecea;border-color:#c62828}}
.verdict.depends{{background:#fff8e1;border-color:#f9a825}}
@media (max-width:700px){{.grid{{grid-template-columns:1fr}} body{{margin:1em auto}}
td,th{{padding:.2em .4em}}}}
</style></head><body>
<h1>MR drum clutch design “{e_(m["design"])}”</h1>
<p class=small>Fidelity <b>{e_(m["fidelity"])}</b> ({e_(methods)}). All figures SI unless marked.
Generated by mrclutch; the numbers are in <a href="metrics.json">metrics.json</a>.</p>
{verdict_badge(m)}
<h2>What the hand feels, in short</h2><ul>{items}</ul>
<div class=grid>
<div><h2>The clutch</h2><table>{rows1}</table></div>
<div><h2>At the hand</h2><table>
<tr><th></th><th>MR pair</th><th>Maxon 136206</th></tr>{rows2}</table>
<p class=small>{e_(motor_caption(e))}</p></div></div>
{budget}
{duty}
<div class=grid>
<div><h2>Impedance and rendering area</h2>
<img src="haptic.png" alt="Bode and effective impedance"></div>
<div><h2>Z-width: the springs and dampers it renders passively</h2>
<img src="zwidth.png" alt="Z-width in the K-B plane">
<p class=small>{e_(zwidth_caption(m["zwidth"]))}</p></div></div>
<div class=grid>
<div><h2>Torque against current</h2><img src="torque.png" alt="torque-current"></div>
<div><h2>Torque response to a current step</h2><img src="response.png" alt="torque step response">
<p class=small>{e_(response_caption(m["response"]))}</p></div></div>
<div class=grid>
<div><h2>3D view</h2><img src="view.png" alt="3D view"></div>
<div><h2>Section</h2><img src="section.png" alt="r-z section"></div></div>
<h2>Files</h2><p>CAD assembly: <a href="{e_(m["cad"]["step"])}">{e_(m["cad"]["step"])}</a>
(materials and densities: <a href="{e_(side)}">{e_(side)}</a>); parts (STL): {stl}.</p>
{cad_notes}
</body></html>
"""
    # every table scrolls inside its own box on a narrow screen instead of widening the page
    return page.replace("<table>", "<div class=scroll><table>").replace(
        "</table>", "</table></div>"
    )
