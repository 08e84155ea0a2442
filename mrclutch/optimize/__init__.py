"""Design optimisation on the fast path, with the winner checked at reference fidelity.

Where a change goes: ``single`` (the best design for one objective: scipy's differential
evolution per drum count, its stability strategy and ranked candidates), ``pareto`` (the
trade-offs: NSGA-II and the members spread over the front), ``limits`` (the builder's
limits and the columns they read), ``box`` (the search box, its process limits and the
edges a design touches), ``worst_case`` (the verdict over the uncertainty ranges). The CLI
re-checks the winners at reference fidelity (mrclutch.requirements, docs/optimize.md).
This package re-exports their public names.
"""

from __future__ import annotations

from mrclutch.optimize.box import DEFAULT_BOUNDS, EDGE, parse_bounds, range_edges, search_box
from mrclutch.optimize.limits import (
    ACTIVE,
    CONTINUOUS,
    PAPER_CONTINUOUS_ABOVE_DRAG,
    ROBUST_COLUMNS,
    Constraints,
    active_limits,
    evaluate_rows,
    limit_columns,
)
from mrclutch.optimize.pareto import (
    DEFAULT_GENERATIONS,
    DEFAULT_MEMBERS,
    DEFAULT_POP_SIZE,
    MAX_ROBUST,
    PARETO_OBJECTIVES,
    RENDERING,
    Member,
    ParetoSet,
    pareto,
)
from mrclutch.optimize.single import (
    MAX_CANDIDATES,
    MINIMISED,
    OBJECTIVES,
    Candidate,
    Optimum,
    optimize,
)
from mrclutch.optimize.worst_case import WorstCase, process_uncertainty, robust_verdict

__all__ = [
    "ACTIVE",
    "CONTINUOUS",
    "DEFAULT_BOUNDS",
    "DEFAULT_GENERATIONS",
    "DEFAULT_MEMBERS",
    "DEFAULT_POP_SIZE",
    "EDGE",
    "MAX_CANDIDATES",
    "MAX_ROBUST",
    "MINIMISED",
    "OBJECTIVES",
    "PAPER_CONTINUOUS_ABOVE_DRAG",
    "PARETO_OBJECTIVES",
    "RENDERING",
    "ROBUST_COLUMNS",
    "Candidate",
    "Constraints",
    "Member",
    "Optimum",
    "ParetoSet",
    "WorstCase",
    "active_limits",
    "evaluate_rows",
    "limit_columns",
    "optimize",
    "pareto",
    "parse_bounds",
    "process_uncertainty",
    "range_edges",
    "robust_verdict",
    "search_box",
]
