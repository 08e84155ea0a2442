"""What ``mrclutch haptic`` and ``mrclutch compare`` compute for the catalogue (no design):
one catalogue actuator reflected through the paper's bench transmission (Eq. 3-4) to the
2-DOF lever metrics at a virtual stiffness K, and the paper's equal-force comparison
(Table 2's identified MR set against the Maxon 136206, Fig. 7c). A design is judged by
``mrclutch.verdict`` instead, as ``evaluate`` judges it.

The CLI (mrclutch/cli/commands/haptic.py) parses, calls these and formats; the option ranges
it checks against are the actuator model's own (re-exported here, ``__all__``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from mrclutch.haptics.actuator import (
    GEARING_RANGE,
    LEVER_RANGE,
    STIFFNESS_MAX,
    TABLE2_EM_136206,
    TABLE2_MR,
    WORKSPACE_RANGE,
    Actuator,
    Transmission,
    actuator,
    reflect,
    transmission_for,
)
from mrclutch.haptics.model import bandwidth, is_stable, metrics

__all__ = [
    "ACTUATOR_NAMES",
    "GEARING_RANGE",
    "LEVER_RANGE",
    "STIFFNESS_MAX",
    "TABLE2_SOURCE",
    "WORKSPACE_RANGE",
    "catalogue_metrics",
    "catalogue_source",
    "compare_k_source",
    "compare_params",
    "compare_result",
]

#: The catalogue actuators ``haptic --actuator`` knows (mrclutch.haptics.actuator.actuator).
ACTUATOR_NAMES = ("mr-paper", "maxon-118890", "maxon-136206", "maxon-136209")
#: The MR pair of ``compare``: Table 2's identified m1 and b1, Table 1's torque.
TABLE2_SOURCE = "MR pair, Table 2"


def catalogue_metrics(name: str, lever: float, gearing: float, workspace: float,
                      delay: float | None = None, K: float | None = None,
                      ) -> tuple[Actuator, Transmission, dict[str, Any]]:  # fmt: skip
    """(actuator, transmission, metrics) of catalogue actuator ``name`` on a ``lever`` (m)
    with gear factor ``gearing`` and workspace ``workspace`` (m) for K_max, its delay
    replaced by ``delay`` (s) when given, at virtual stiffness ``K`` (N/m; None: K_max)."""
    act = actuator(name)
    if delay is not None:
        act = replace(act, delay=delay)
    tr = replace(transmission_for(act, lever), gearing=gearing, workspace=workspace)
    return act, tr, metrics(reflect(act, tr), K)


def catalogue_source(name: str) -> str:
    """Where a catalogue actuator's figures come from, as printed beside its K_max."""
    if name == "mr-paper":  # Table 1 torque and inertia, Table 2's identified b1
        return "MR pair, Table 1 catalogue"
    return f"{name}, Table 1 catalogue"


def compare_k_source(mr: Any, em: Any, K: float, typed: bool) -> str:
    """Which K_max ``compare`` renders: the smaller of the two (the force both produce)."""
    if typed:
        return "typed"
    return TABLE2_SOURCE if K == float(mr.k_max) else catalogue_source("maxon-136206")


def compare_params(
    K: float | None = None, delay: float | None = None, workspace: float = 0.05
) -> tuple[Any, Any, float]:
    """(MR params, EM params, K): Table 2 MR set vs the 136206 through the EM bench."""
    mr = replace(TABLE2_MR, workspace=workspace)
    em = replace(TABLE2_EM_136206, workspace=workspace)
    if delay is not None:
        mr = replace(mr, delay=delay)
    if K is None:
        K = float(min(mr.k_max, em.k_max))
    return mr, em, K


def compare_result(mr: Any, em: Any, K: float) -> dict[str, Any]:
    """The ``compare --json`` object."""
    m_mr, m_em = metrics(mr, K), metrics(em, K)
    bw_nodelay = float(bandwidth(replace(mr, delay=0.0), K))
    return {
        "mr": m_mr,
        "em": m_em,
        "bandwidth_gain_lumped": m_mr["bandwidth_lumped_hz"] / m_em["bandwidth_lumped_hz"] - 1,
        "bandwidth_gain": m_mr["bandwidth_hz"] / m_em["bandwidth_hz"] - 1,
        "bandwidth_gain_mr_without_delay": bw_nodelay / m_em["bandwidth_hz"] - 1,
        "damping_ratio_mr_over_em": m_mr["b1_N_s_per_m"] / m_em["b1_N_s_per_m"],
        "stable": {"mr": is_stable(mr, K), "em": is_stable(em, K)},
    }
