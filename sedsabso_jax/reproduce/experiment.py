"""Deprecated module path: sedsabso_jax.reproduce.experiment (documented in 0.2). Its names
are public elsewhere now (each warning says where); kept with a warning through 0.3.x."""

from __future__ import annotations

from .. import _deprecation

__getattr__ = _deprecation.moved(__name__, {
    "Settings": "sedsabso_jax.reproduce.Settings",
    "run": "sedsabso_jax.reproduce.run",
    "build_problem": "sedsabso_jax.reproduce.build_problem",
    "scenario_box": "sedsabso_jax.reproduce.scenario_box",
    "Experiment": "sedsabso_jax.reproduce.Experiment",
    "SCENARIOS": "sedsabso_jax.reproduce.SCENARIOS",
}, module="sedsabso_jax.reproduce._experiment")
