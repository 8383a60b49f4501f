"""The paper's experiment reproduced: what ``sedsabso-jax reproduce`` runs and writes. Builds
on every other layer; nothing below imports it.

- :mod:`._experiment`: the experiment (Sec. 5) end to end, its settings and scenarios;
- :mod:`._report`: Tables 4-5 and Figures 5-6 with the paper's numbers beside ours, and the
  base-parameter table with the paper's Table 5.

The paper's published numbers themselves are in :mod:`sedsabso_jax.paper`.
"""

from __future__ import annotations

from ._experiment import SCENARIOS as SCENARIOS
from ._experiment import Experiment as Experiment
from ._experiment import Settings as Settings
from ._experiment import build_problem as build_problem
from ._experiment import run as run
from ._experiment import scenario_box as scenario_box
from ._report import base_parameter_table as base_parameter_table
from ._report import table4 as table4
from ._report import table5 as table5
from ._report import write_outputs as write_outputs

__all__ = [
    "Settings", "Experiment", "run", "build_problem", "scenario_box", "SCENARIOS",
    "write_outputs", "table4", "table5", "base_parameter_table",
]
