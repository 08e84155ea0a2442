"""The reluctance network of the drum clutch (issue 12), in three modules a reader can find:

- ``magnetics.network.build``: the ladder read from the region table (``Network``,
  ``network_from_regions``): what each element is, and why;
- ``magnetics.network.solve``: its loop fluxes by damped Newton (``solve_network``,
  ``flux_linkage``);
- ``magnetics.network.torque``: the films' yield torque read from the loop fluxes
  (``network_film_torque`` and the batches on it, re-exported by ``magnetics.torque``).
"""

from magnetics.network.build import Network, network_from_regions
from magnetics.network.solve import (
    NetworkConvergenceError,
    flux_linkage,
    solve_network,
    use_compiled,
)

__all__ = [
    "Network",
    "NetworkConvergenceError",
    "flux_linkage",
    "network_from_regions",
    "solve_network",
    "use_compiled",
]
