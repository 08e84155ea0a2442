"""One design's section and reluctance network, built once per process for every stage of
``evaluate`` that reads them (issue 40): the torque at the current limit and the
continuous rating's chords (``mrclutch.clutch``), the feel's loop (``mrclutch.feel``) and
the duty's cold curve (``mrclutch.duty``) each solved on the same network instead of each
building its own (a build is ≈ 20 ms in Python, a single design's solve a few).

``network_curve`` is ``magnetics.torque.torque_curve`` on that network (its ``network``
argument): the same numbers to the last digit (tests/mrclutch/test_design_network.py).
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike

from geometry.materials import DEFAULT_CHOICE, MaterialChoice
from geometry.params import DrumClutch
from geometry.section import Section, build_section
from magnetics.drag import ROOM_TEMPERATURE, Support
from magnetics.network import Network, network_from_regions, solve_network
from magnetics.torque import TorqueCurve, network_gap_torque, section_fluid, torque_curve

#: Designs whose network a process keeps (an evaluation reads one; a few for a script
#: that evaluates some designs in turn).
KEPT = 4


@functools.lru_cache(maxsize=KEPT)
def section_network(
    clutch: DrumClutch, materials: MaterialChoice = DEFAULT_CHOICE
) -> tuple[Section, Network]:
    """(``build_section(clutch, materials)``, its reluctance network with the default
    magnetic materials), built on the first call for these values and then shared: both
    are pure functions of the two frozen inputs, and their readers do not write to them."""
    section = build_section(clutch, materials)
    return section, network_from_regions(section.table)


def network_yield(section: Section, net: Network, currents: ArrayLike) -> np.ndarray:
    """Yield torque (N·m) at ``currents`` (A, 1-D) on the section's network: the sum over
    its films (``network_gap_torque``), as ``torque_curve(…).yield_torque``."""
    cur = np.atleast_1d(np.asarray(currents, dtype=float))
    return network_gap_torque(net, cur[None, :], None, section_fluid(section))[0].sum(axis=-1)


def network_curve(
    section: Section,
    net: Network,
    currents: ArrayLike,
    speed_rpm: float = 530.0,
    temperature: float = ROOM_TEMPERATURE,
    support: Support | None = None,
    flux: np.ndarray | None = None,
) -> TorqueCurve:
    """``torque_curve(section, currents, "network", speed_rpm, temperature=…, support=…)``
    on ``net``, the section's network already built (``section_network``); ``flux``: its
    loop fluxes (1, C, ·) at the currents if already solved (``solved_at``)."""
    return torque_curve(section, currents, "network", speed_rpm, temperature=temperature,
                        support=support, network=net, flux=flux)  # fmt: skip


def solved_at(net: Network, current: float) -> np.ndarray:
    """The loop fluxes (1, 1, ·) of the one-design network ``net`` at ``current`` (A), solved
    as ``torque_curve`` solves them (``solve_network`` at N·I, the default materials, from
    the linear start): the torque's and the trust check's one solve (issue 40)."""
    return solve_network(net, net.turns[:, None] * np.array([[float(current)]]))
