"""Excitation design beyond the package root's names (``FourierTrajectory``,
``design_excitation``): the checks against joint limits, the design fitness of Eq. 9 and
its parts (the paper's Eq. 5-9). Builds on :mod:`sedsabso_jax.dynamics` and
:mod:`sedsabso_jax.optim`."""

from __future__ import annotations

from ._checks import check_trajectory as check_trajectory
from ._checks import violations as violations
from ._design import DesignSearch as DesignSearch
from ._design import ExcitationDesign as ExcitationDesign
from ._design import coefficient_box as coefficient_box
from ._design import default_solver as default_solver
from ._fitness import PENALTY as PENALTY
from ._fitness import DesignProblem as DesignProblem
from ._fitness import condition_number as condition_number
from ._fitness import design_fitness as design_fitness
from ._fitness import sampling_margin as sampling_margin

__all__ = [
    "DesignSearch",
    "ExcitationDesign", "coefficient_box", "default_solver", "check_trajectory",
    "violations", "DesignProblem", "design_fitness", "condition_number", "sampling_margin",
    "PENALTY",
]
