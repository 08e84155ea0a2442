"""The reluctance network of the drum clutch (issue 12), in three modules a reader can find:

- ``magnetics.network.build``: the ladder read from the region table (``Network``,
  ``network_from_regions``): what each element is, and why;
- ``magnetics.network.solve``: its loop fluxes by damped Newton (``solve_network``,
  ``flux_linkage``), on the kernels of ``magnetics.network.kernels`` (plain Python),
  compiled by ``magnetics.network.compiled`` (numba, its cache, ``use_compiled``);
- ``magnetics.network.torque``: the films' yield torque read from the loop fluxes
  (``network_film_torque`` and the batches on it, re-exported by ``magnetics.torque``).
"""

from magnetics.network.build import Network, network_from_regions
from magnetics.network.compiled import use_compiled
from magnetics.network.solve import NetworkConvergenceError, flux_linkage, solve_network

__all__ = [
    "Network",
    "NetworkConvergenceError",
    "flux_linkage",
    "network_from_regions",
    "solve_network",
    "use_compiled",
]
