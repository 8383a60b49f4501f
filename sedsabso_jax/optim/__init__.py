"""Box optimisers, the second foundation: SEDSABSO, BSO and LDWPSO as vectorised JAX
kernels, one driver and result type, and the baselines they are judged against.

Nothing here knows about robots: a problem is a fitness over a box.

- :mod:`.fitness`: black-box ``f(x, args)`` and the paper's Eq. 17 as a linear embedding;
- :mod:`.swarm`: the solver interface, population state and bookkeeping;
- :mod:`.driver`: :func:`minimise` (compiled, many runs per call, several devices);
- :mod:`.bso`, :mod:`.sedsabso`, :mod:`.ldwpso`: one algorithm each; :mod:`.registry`;
- :mod:`.result`: the one :class:`Result` type;
- :mod:`.external`: any evosax strategy through :func:`minimise` (:class:`Evosax`);
- :mod:`.budget`: equal budgets in fitness evaluations;
- :mod:`.box`: bounds and the box around a point;
- :mod:`.linear`: the least-squares and least-absolute-deviation cores;
- :mod:`.baselines`: OLS, optimistix LM / GN, the exact L1 optimum of Eq. 17.
"""

from . import baselines as baselines
from .box import box_around as box_around
from .bso import BSO as BSO
from .budget import evaluation_counts as evaluation_counts
from .budget import iterations_for_budget as iterations_for_budget
from .driver import minimise as minimise
from .external import Evosax as Evosax
from .fitness import BlackBox as BlackBox
from .fitness import L1Residual as L1Residual
from .ldwpso import LDWPSO as LDWPSO
from .registry import SWARMS as SWARMS
from .result import Result as Result
from .sedsabso import SEDSABSO as SEDSABSO
from .solver import AbstractSolver as AbstractSolver
from .swarm import AbstractSwarm as AbstractSwarm
