"""``mrclutch haptic`` (one actuator on the lever → metrics) and ``mrclutch compare`` (the
paper's equal-force comparison, Fig. 7c). Given a design (``DESIGN.toml`` or ``--preset``)
both judge it as ``evaluate`` does (``mrclutch.verdict``: its ``[render]`` K, its verdict,
the equal-force Maxon geared from its K_max at the same fidelity). Imports nothing heavy at
module level: a design's branch is ``mrclutch.cli.commands.haptic_design`` (the design, the
pipeline and the verdict), loaded, as main loads a command's module, only when a design is
named, so the catalogue's answer loads the haptic model alone (issue 40: 84 project modules
before, 27 now)."""

from __future__ import annotations

import argparse
import importlib
from typing import Any

from geometry.validation import check_choice, check_range
from mrclutch.cli.metrics_format import print_metrics
from mrclutch.cli.options import add_design_args, print_json
from mrclutch.haptic_run import (
    ACTUATOR_NAMES,
    GEARING_RANGE,
    LEVER_RANGE,
    STIFFNESS_MAX,
    TABLE2_SOURCE,
    WORKSPACE_RANGE,
    catalogue_metrics,
    catalogue_source,
    compare_k_source,
    compare_params,
    compare_result,
)
from mrclutch.nulls import null_notes
from mrclutch.outputs import format_kmax

#: A design's branch of both commands and the comparison's figure: modules loaded by name
#: when used (as mrclutch.cli.main loads a command's), each heavy to import (the design's
#: duty, dynamics and network, the pipeline and the verdict; matplotlib).
_DESIGN = "mrclutch.cli.commands.haptic_design"
_PLOTS = "mrclutch.cli.plots.haptic"
#: --delay-ms's bound (s): mrclutch.operating.MAX_DELAY, the design file's (checked equal in
#: tests/mrclutch/test_one_design_speed.py; importing operating loads the drag and fluids).
MAX_DELAY_S = 1.0


def register(sub: Any) -> None:
    p = sub.add_parser(
        "haptic",
        help="one actuator + transmission + virtual spring K → haptic metrics",
        description="Reflect a catalogue actuator through the paper's bench transmission "
        "(Eq. 3-4) and report the 2-DOF lever metrics at the virtual stiffness K.",
    )
    p.add_argument(
        "--actuator",
        default="mr-paper",
        metavar="NAME",
        help=f"catalogue actuator: {', '.join(ACTUATOR_NAMES)} (default mr-paper)",
    )
    p.add_argument("--lever-mm", type=float, default=170.0, help="lever length [mm] (170)")
    p.add_argument("--gearing", type=float, default=1.0, help="gear factor G multiplying n (1)")
    _common(p)
    _design(p)
    p.set_defaults(func=run_haptic)

    c = sub.add_parser(
        "compare",
        help="the paper's equal-force comparison: MR pair vs Maxon 136206 (Fig. 7c)",
        description="Table 2's identified MR set against the Maxon 136206 (Table 1 inertia "
        "through the EM transmission), both at the same virtual stiffness K (default: the "
        "smaller K_max, i.e. the force both can produce).",
    )
    _common(c)
    _design(c)
    c.add_argument("--plot", metavar="FILE.png", help="write Bode / effective impedance figure")
    c.set_defaults(func=run_compare)


def _design(p: argparse.ArgumentParser) -> None:
    """A design instead of the catalogue: judged as ``evaluate`` judges it."""
    add_design_args(p)
    p.add_argument("--fidelity", default="fast",
                   help="with a design: the fidelity it is evaluated at (default fast), as "
                   "evaluate --fidelity")  # fmt: skip


def _named(args: argparse.Namespace) -> bool:
    """Whether the options name a design (a file or --preset) rather than the catalogue."""
    return args.design is not None or args.preset is not None


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--stiffness", type=float, default=None, help="virtual stiffness K [N/m] (default K_max)"
    )
    p.add_argument(
        "--delay-ms", type=float, default=None, help="actuator delay [ms] (default: catalogue)"
    )
    p.add_argument(
        "--workspace-mm", type=float, default=50.0, help="workspace d for K_max [mm] (50)"
    )
    p.add_argument("--json", action="store_true", help="print JSON (SI keys)")


def _edge(args: argparse.Namespace) -> tuple[float | None, float | None, float]:
    """mm/ms at the edge → SI, validated with the option's own name."""
    K = None
    if args.stiffness is not None:
        K = check_range("--stiffness", args.stiffness, 0.0, STIFFNESS_MAX, " N/m", lo_open=True)
    delay = None
    if args.delay_ms is not None:
        delay = check_range("--delay-ms", args.delay_ms, 0.0, MAX_DELAY_S * 1e3, " ms") * 1e-3
    lo, hi = WORKSPACE_RANGE
    workspace = check_range("--workspace-mm", args.workspace_mm, lo * 1e3, hi * 1e3, " mm") * 1e-3
    return K, delay, workspace


def run_haptic(args: argparse.Namespace) -> int:
    K, delay, workspace = _edge(args)
    if _named(args):  # a design: judged as evaluate judges it (its own module)
        return importlib.import_module(_DESIGN).run_haptic(args)
    lo, hi = LEVER_RANGE  # Transmission's own rule, stated in the option's unit
    lever = check_range("--lever-mm", args.lever_mm, lo * 1e3, hi * 1e3, " mm") * 1e-3
    gearing = check_range("--gearing", args.gearing, *GEARING_RANGE)
    name = check_choice("--actuator", args.actuator, ACTUATOR_NAMES)
    act, tr, m = catalogue_metrics(name, lever, gearing, workspace, delay, K)
    src = catalogue_source(act.name)
    if args.json:
        print_json({**m, "source": src, "nulls": null_notes(m)})
    else:
        print(f"{act.name} on a {lever * 1e3:g} mm lever, gearing {gearing:g}, n = {tr.ratio:.3f}")
        print_metrics(m, src if K is None else "typed")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    K, delay, workspace = _edge(args)
    if _named(args):
        return importlib.import_module(_DESIGN).run_compare(args)
    typed = K is not None
    mr, em, K = compare_params(K, delay, workspace)
    res = compare_result(mr, em, K)
    src = compare_k_source(mr, em, K, typed)
    res["K_source"] = src
    res["sources"] = {"mr": TABLE2_SOURCE, "em": catalogue_source("maxon-136206")}
    if args.plot:
        importlib.import_module(_PLOTS).compare_figure(
            {"MR pair (Table 2)": mr, "Maxon 136206": em}, K, args.plot
        )
    if args.json:
        print_json({**res, "nulls": null_notes(res)})  # every null with its reason
        return 0
    for side, title, p in (("mr", "MR pair (Table 2 identified)", mr),
                           ("em", "Maxon 136206", em)):  # fmt: skip
        print(title)
        print_metrics(res[side], src, res["sources"][side], own_kmax=float(p.k_max))
    g, g0 = res["bandwidth_gain"], res["bandwidth_gain_mr_without_delay"]
    print(
        f"At {format_kmax(K, src) if not typed else f'K = {K:.4g} N/m [typed]'} (the smaller "
        f"of the two K_max: {float(mr.k_max):.4g} N/m [{TABLE2_SOURCE}], "
        f"{float(em.k_max):.4g} N/m [{catalogue_source('maxon-136206')}]) the MR lever renders "
        f"{100 * res['bandwidth_gain_lumped']:.1f} % more "
        f"lumped bandwidth (paper: 52.8 %), {100 * g:.1f} % on the full model with its "
        f"{mr.delay * 1e3:g} ms delay ({100 * g0:.1f} % without); its damping b1 is "
        f"{res['damping_ratio_mr_over_em']:.2f}× the motor's. MR: "
        f"{_ps(res['mr']['passive'], res['stable']['mr'])}; EM: "
        f"{_ps(res['em']['passive'], res['stable']['em'])}."
    )
    if args.plot:
        print(f"figure: {args.plot}")
    return 0


def _ps(passive: bool, stable: bool) -> str:
    return f"{'passive' if passive else 'NOT passive'}, {'stable' if stable else 'UNSTABLE'}"
