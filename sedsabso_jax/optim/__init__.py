"""Optimisers beyond the package root's names: the second foundation, which knows nothing
of robots (a problem is a fitness over a box). The common names (``minimise``,
``AbstractSolver``, ``SEDSABSO``, ``BSO``, ``LDWPSO``, ``Evosax``, ``BlackBox``,
``L1Residual``, ``Result``, ``box_around``, ``iterations_for_budget``,
``evaluation_counts``) are ``sedsabso_jax``'s; the least-squares and L1 baselines are
:mod:`sedsabso_jax.baselines`. Here: what a new solver or a study of the swarms needs,
a swarm of your own included (:class:`AbstractSwarm`, its :class:`SwarmState` and the
rounds' helpers: :data:`INITIAL`, :func:`initial_bests`, :func:`absorb_positions`,
:func:`swarm_best`, :func:`extend`)."""

from __future__ import annotations

import importlib as _importlib

from ._bso import BeetleStep as BeetleStep
from ._driver import CACHE_SIZE as CACHE_SIZE
from ._driver import clear_compiled as clear_compiled
from ._external import evosax_names as evosax_names
from ._fitness import AbstractFitness as AbstractFitness
from ._linear import Factorization as Factorization
from ._linear import factorize as factorize
from ._linear import l1_solve as l1_solve
from ._linear import l1_solve_box as l1_solve_box
from ._population import INITIAL as INITIAL
from ._population import SwarmState as SwarmState
from ._population import absorb_positions as absorb_positions
from ._population import extend as extend
from ._population import initial_bests as initial_bests
from ._population import swarm_best as swarm_best
from ._registry import SWARMS as SWARMS
from ._swarm import AbstractSwarm as AbstractSwarm

__all__ = [
    "AbstractSwarm", "SwarmState", "INITIAL", "initial_bests", "absorb_positions",
    "swarm_best", "extend", "BeetleStep", "AbstractFitness", "evosax_names",
    "SWARMS", "clear_compiled", "CACHE_SIZE", "Factorization", "factorize", "l1_solve",
    "l1_solve_box",
]

#: Internals once in ``__all__``, still importable from here.
_INTERNAL = {"metropolis_accept": "._sedsabso", "EvosaxState": "._external",
             "time_one_of_many": "._driver"}


def __getattr__(name: str) -> object:
    if name in _INTERNAL:
        return getattr(_importlib.import_module(_INTERNAL[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
