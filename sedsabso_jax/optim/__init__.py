"""Optimisers beyond the package root's names: the second foundation, which knows nothing
of robots (a problem is a fitness over a box). The common names (``minimise``,
``AbstractSolver``, ``SEDSABSO``, ``BSO``, ``LDWPSO``, ``Evosax``, ``BlackBox``,
``L1Residual``, ``Result``, ``box_around``, ``iterations_for_budget``,
``evaluation_counts``) are ``sedsabso_jax``'s; the least-squares and L1 baselines are
:mod:`sedsabso_jax.baselines`. Here: what a new solver or a study of the swarms needs."""

from __future__ import annotations

from ._bso import BeetleStep as BeetleStep
from ._driver import CACHE_SIZE as CACHE_SIZE
from ._driver import clear_compiled as clear_compiled
from ._driver import time_one_of_many as time_one_of_many
from ._external import EvosaxState as EvosaxState
from ._external import evosax_names as evosax_names
from ._fitness import AbstractFitness as AbstractFitness
from ._linear import Factorization as Factorization
from ._linear import factorize as factorize
from ._linear import l1_solve as l1_solve
from ._linear import l1_solve_box as l1_solve_box
from ._population import SwarmState as SwarmState
from ._registry import SWARMS as SWARMS
from ._sedsabso import metropolis_accept as metropolis_accept
from ._swarm import AbstractSwarm as AbstractSwarm

__all__ = [
    "AbstractSwarm", "SwarmState", "BeetleStep", "AbstractFitness", "EvosaxState",
    "evosax_names", "SWARMS", "metropolis_accept", "time_one_of_many", "clear_compiled",
    "CACHE_SIZE", "Factorization", "factorize", "l1_solve", "l1_solve_box",
]
