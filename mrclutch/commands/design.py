"""``mrclutch evaluate | sweep | optimize | report``: from the drums to the hand."""

from __future__ import annotations

import argparse

from mrclutch.commands._common import add_design_args, load_design_args, print_json


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "evaluate",
        help="a clutch design and its haptic consequences, beside the equal-force motor",
        description="Torque, inertia, mass and drag of a clutch design, and what the MR pair "
        "does at the hand (m1, b1, K_max, bandwidths, rendering area, passivity, stability) "
        "beside the Maxon 136206 geared to the same force, at the same virtual stiffness.",
    )
    add_design_args(p)
    p.add_argument(
        "--fidelity",
        default="fast",
        help="fast (analytic inertia, magnetic circuit) or reference (exact B-rep, FEM); "
        "default fast",
    )
    p.add_argument("--json", action="store_true", help="print JSON (SI units in the key names)")
    p.set_defaults(func=_evaluate)

    p = sub.add_parser(
        "sweep",
        help="evaluate a grid or random sample of designs on the fast path (CSV)",
        description="Sweep DrumClutch parameters given in SPEC.toml (ranges in mm); rows are "
        "written as they come, so an interrupted sweep loses nothing and --resume carries on.",
    )
    p.add_argument("spec", metavar="SPEC.toml", help="sweep spec (see examples/*.toml)")
    p.add_argument("--out", required=True, metavar="RESULTS.csv", help="CSV file to write")
    p.add_argument("--resume", action="store_true", help="continue an interrupted sweep")
    p.add_argument("--overwrite", action="store_true", help="replace an existing results file")
    p.add_argument("--workers", type=int, default=0, help="processes (0: in this process)")
    p.add_argument("--pareto", metavar="FILE.png", help="also draw the Pareto front")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_sweep)


def _evaluate(args: argparse.Namespace) -> int:
    from mrclutch.pipeline import evaluate

    design = load_design_args(args)
    ev = evaluate(design, args.fidelity)
    data = ev.as_json()
    if args.json:
        print_json(data)
        return 0
    print(format_evaluation(data))
    return 0


def format_evaluation(data: dict) -> str:
    """A person's view of ``Evaluation.as_json()``."""
    c = data["clutch"]
    lines = [
        f"design {data['design']}  (fidelity {data['fidelity']}: inertia by "
        f"{c['methods']['inertia']}, torque by {c['methods']['torque']})",
        "",
        "clutch",
        f"  max torque        {c['max_torque_N_m']:.4g} N·m at {c['max_current_A']:.3g} A",
        f"  rotor inertia     {c['rotor_inertia_kg_m2'] * 1e7:.4g} g·cm²"
        f"   (mass {c['rotor_mass_kg'] * 1e3:.3g} g)",
        f"  clutch mass       {c['clutch_mass_kg'] * 1e3:.4g} g   envelope "
        f"Ø{c['envelope_m'][0] * 1e3:.3g} × {c['envelope_m'][1] * 1e3:.3g} mm",
        f"  viscous damping   {c['viscous_damping_N_m_s']:.4g} N·m·s   off-state torque "
        f"{c['off_state_torque_N_m'] * 1e3:.4g} mN·m",
        f"  torque / inertia  {c['torque_per_inertia_N_m_per_kg_m2']:.4g} N·m/(kg·m²)",
        "",
        f"{'at the hand':<28}{'MR pair':>14}{'Maxon 136206':>14}",
    ]
    h, m = data["haptic"], data["motor"]
    rows = [
        ("m1 (g)", "m1_kg", 1e3),
        ("b1 (N·s/m)", "b1_N_s_per_m", 1),
        ("K (N/m)", "K_N_per_m", 1),
        ("bandwidth, lumped (Hz)", "bandwidth_lumped_hz", 1),
        ("bandwidth, full (Hz)", "bandwidth_hz", 1),
        ("resonance (Hz)", "resonance_hz", 1),
        ("rendering area (dB·dec)", "rendering_area_dB_decade", 1),
        ("max passive K (N/m)", "max_passive_K_N_per_m", 1),
        ("max stable K (N/m)", "max_stable_K_N_per_m", 1),
    ]
    for label, key, f in rows:
        lines.append(f"  {label:<26}{_num(h[key], f):>14}{_num(m[key], f):>14}")
    lines.append(f"  {'passive at K':<26}{h['passive']!s:>14}{m['passive']!s:>14}")
    lines.append(f"  (motor geared ×{m['gearing']:.3g} to the MR pair's force)")
    g, gl = data["bandwidth_gain"], data["bandwidth_gain_lumped"]
    lines.append(f"bandwidth gain MR over motor: {_pct(gl)} lumped, {_pct(g)} on the full response")
    return "\n".join(lines)


def _num(v: float | None, f: float) -> str:
    return "—" if v is None or v != v else f"{v * f:.4g}"  # None or NaN: none


def _pct(v: float | None) -> str:
    return "—" if v is None else f"{v * 100:+.1f} %"


def _sweep(args: argparse.Namespace) -> int:
    from concurrent.futures import ProcessPoolExecutor

    from mrclutch.cli import CLIError
    from mrclutch.design import design_from_mapping
    from mrclutch.pipeline import BATCH_OUTPUTS, BatchEvaluator
    from mrclutch.sweep import load_spec, run_sweep

    spec, rest = load_spec(args.spec)
    base = design_from_mapping({"clutch": spec.base.to_mm(), **rest}, where=args.spec)
    if args.workers < 0:
        raise CLIError(f"--workers = {args.workers}: must be >= 0")
    evaluator = BatchEvaluator(base)
    executor = ProcessPoolExecutor(args.workers) if args.workers else None
    try:
        res = run_sweep(
            spec,
            args.out,
            evaluator,
            BATCH_OUTPUTS,
            executor=executor,
            resume=args.resume,
            overwrite=args.overwrite,
            progress=not args.no_progress,
        )
    finally:
        if executor is not None:
            executor.shutdown(cancel_futures=True)
    if not res.complete:
        import sys

        print(
            f"mrclutch sweep: interrupted after {res.rows} of {spec.n_designs} designs; "
            f"rows kept in {res.path}; run again with --resume to carry on",
            file=sys.stderr,
        )
        return 130
    print(
        f"{res.rows} designs in {res.path}"
        + (f" (resumed at {res.resumed_from})" if res.resumed_from else "")
    )
    if args.pareto:
        from mrclutch.plots.design import pareto_plot

        pareto_plot(res.path, args.pareto)
        print(f"Pareto front: {args.pareto}")
    return 0
