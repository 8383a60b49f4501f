"""Optimisers beyond the package root's names: the second foundation, which knows nothing
of robots (a problem is a fitness over a box). The common names (``minimise``,
``AbstractSolver``, ``SEDSABSO``, ``BSO``, ``LDWPSO``, ``Evosax``, ``BlackBox``,
``L1Residual``, ``Result``, ``box_around``, ``iterations_for_budget``,
``evaluation_counts``) are ``sedsabso_jax``'s; the least-squares and L1 baselines are
:mod:`sedsabso_jax.baselines`. Here: what a new solver or a study of the swarms needs."""

from __future__ import annotations

from .. import _deprecation
from ._bso import BeetleSwarm as BeetleSwarm
from ._driver import time_one_of_many as time_one_of_many
from ._external import EvosaxState as EvosaxState
from ._external import evosax_names as evosax_names
from ._linear import Factorization as Factorization
from ._linear import factorize as factorize
from ._linear import l1_solve as l1_solve
from ._linear import l1_solve_box as l1_solve_box
from ._registry import SWARMS as SWARMS
from ._sedsabso import metropolis_accept as metropolis_accept
from ._swarm import AbstractSwarm as AbstractSwarm
from ._swarm import SwarmState as SwarmState

__all__ = [
    "AbstractSwarm", "SwarmState", "BeetleSwarm", "EvosaxState", "evosax_names", "SWARMS",
    "metropolis_accept", "time_one_of_many", "Factorization", "factorize", "l1_solve",
    "l1_solve_box",
]

#: Names that moved to the package root (0.3), kept with a warning through 0.3.x.
__getattr__ = _deprecation.moved(__name__, {
    "minimise": "sedsabso_jax.minimise",
    "AbstractSolver": "sedsabso_jax.AbstractSolver",
    "SEDSABSO": "sedsabso_jax.SEDSABSO",
    "BSO": "sedsabso_jax.BSO",
    "LDWPSO": "sedsabso_jax.LDWPSO",
    "Evosax": "sedsabso_jax.Evosax",
    "BlackBox": "sedsabso_jax.BlackBox",
    "L1Residual": "sedsabso_jax.L1Residual",
    "Result": "sedsabso_jax.Result",
    "box_around": "sedsabso_jax.box_around",
    "iterations_for_budget": "sedsabso_jax.iterations_for_budget",
    "evaluation_counts": "sedsabso_jax.evaluation_counts",
    "baselines": "sedsabso_jax.baselines",
})
