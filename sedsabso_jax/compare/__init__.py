"""Comparing optimisers the way optimisation research does: equal budgets in fitness
evaluations, many seeded runs, a standard suite, statistics, and COCO's data format. What
``sedsabso-jax compare`` runs and writes. Builds on every layer below it (the
identification problems come from ``reproduce``'s experiment and the real KUKA data).

- :mod:`._coco`: COCO's bbob suite f1-f24 with COCO's numbered instances, the values of
  ``cocoex`` to rounding (:func:`coco_function`; one compiled fitness per dimension for
  all functions and instances: ``coco_args``, ``coco_value``);
- :mod:`._bbob`: the suite as ``compare`` runs it (dimensions, default instances, names);
- :mod:`._problems`: the BBOB and identification problems, with their known optima;
- :mod:`._statistics`: median / IQR, Mann-Whitney U with Holm's correction, Vargha-Delaney
  A12, run lengths, their ECDF and the average runtime (aRT);
- :mod:`._run`: one task (an algorithm on a problem: a batch of seeded runs);
- :mod:`._campaign`: every task, in this process or on Dask workers (:mod:`._dask`), one
  resumable JSON file per task, then COCO's folders (:mod:`._cocodata`);
- :mod:`._alignment`: run lengths read off COCO's files as cocopp reads them;
- :mod:`._report`: report.md, summary.json and the ECDF figures.
"""

from __future__ import annotations

from ._bbob import DEFAULT_INSTANCES as DEFAULT_INSTANCES
from ._bbob import DIMENSIONS as DIMENSIONS
from ._campaign import compare as compare
from ._coco import coco_function as coco_function
from ._problems import SUITES as SUITES
from ._problems import Problem as Problem
from ._problems import load_problem as load_problem
from ._problems import problem_names as problem_names
from ._report import write_report as write_report
from ._run import DEFAULT_ALGORITHMS as DEFAULT_ALGORITHMS
from ._run import DEFAULT_BUDGET as DEFAULT_BUDGET
from ._run import Settings as Settings
from ._run import Task as Task
from ._run import parse_budget as parse_budget
from ._run import run_problem as run_problem
from ._run import run_task as run_task
from ._run import solver_for as solver_for
from ._statistics import COCO_TARGETS as COCO_TARGETS
from ._statistics import a12 as a12
from ._statistics import average_runtime as average_runtime
from ._statistics import ecdf as ecdf
from ._statistics import holm as holm
from ._statistics import pairwise as pairwise
from ._statistics import run_lengths as run_lengths
from ._statistics import summary as summary

__all__ = [
    "Settings", "Task", "compare", "run_task", "run_problem", "solver_for", "parse_budget",
    "coco_function",
    "DEFAULT_ALGORITHMS", "DEFAULT_BUDGET", "DEFAULT_INSTANCES", "DIMENSIONS", "Problem",
    "problem_names", "load_problem", "SUITES", "summary", "a12", "holm", "pairwise",
    "run_lengths", "ecdf", "average_runtime", "COCO_TARGETS", "write_report",
]
