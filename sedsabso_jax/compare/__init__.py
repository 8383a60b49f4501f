"""Comparing optimisers the way optimisation research does: equal budgets in fitness
evaluations, many seeded runs, a standard suite, statistics. What ``sedsabso-jax compare``
runs and writes. Builds on every layer below it (the identification problems come from
``reproduce``'s experiment and the real KUKA data).

- :mod:`._problems`: BBOB f1-f24 (evosax's JAX implementation) and the identification
  problems, with their known optima;
- :mod:`._coco`: COCO's bbob suite f1-f24 with COCO's numbered instances, the values of
  ``cocoex`` to rounding (:func:`coco_function`; one compiled fitness per dimension for
  all functions and instances: ``coco_args``, ``coco_value``);
- :mod:`._statistics`: median / IQR, Mann-Whitney U with Holm's correction, Vargha-Delaney
  A12, run lengths and their ECDF;
- :mod:`._run`: the runs, one resumable JSON file per problem;
- :mod:`._report`: report.md, summary.json and the ECDF figures.
"""

from __future__ import annotations

from ._coco import coco_function as coco_function
from ._problems import SUITES as SUITES
from ._problems import Problem as Problem
from ._problems import load_problem as load_problem
from ._problems import problem_names as problem_names
from ._report import write_report as write_report
from ._run import DEFAULT_ALGORITHMS as DEFAULT_ALGORITHMS
from ._run import DEFAULT_BUDGET as DEFAULT_BUDGET
from ._run import Settings as Settings
from ._run import compare as compare
from ._run import parse_budget as parse_budget
from ._run import run_problem as run_problem
from ._run import solver_for as solver_for
from ._statistics import a12 as a12
from ._statistics import ecdf as ecdf
from ._statistics import holm as holm
from ._statistics import pairwise as pairwise
from ._statistics import run_lengths as run_lengths
from ._statistics import summary as summary

__all__ = [
    "Settings", "compare", "run_problem", "solver_for", "parse_budget",
    "DEFAULT_ALGORITHMS", "DEFAULT_BUDGET", "Problem", "problem_names", "load_problem",
    "SUITES", "summary", "a12", "holm", "pairwise", "run_lengths", "ecdf", "write_report",
    "coco_function",
]
