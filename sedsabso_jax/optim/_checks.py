"""Checks of a solver's hyperparameters, run when it is built (``__check_init__``): one
line naming the bad value and what was expected."""

from __future__ import annotations

from typing import Any

import jax
import numpy as np


def is_concrete(*values: Any) -> bool:
    """Whether every value is concrete (not a tracer): hyperparameters given as traced
    arrays (a ``vmap`` over a hyperparameter) are checked only where they are concrete."""
    return not any(isinstance(v, jax.core.Tracer) for v in jax.tree.leaves(values))


def check_integer(value: object, name: str, minimum: int) -> None:
    """``value`` must be an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")


def check_population(n: object, name: str = "population_size") -> None:
    """A population size must be an integer >= 1."""
    check_integer(n, name, 1)


def check_velocity_update(c1: float, c2: float, vmax_fraction: float) -> None:
    """The velocity update's coefficients: ``c1, c2 >= 0`` and ``vmax_fraction > 0``."""
    if vmax_fraction <= 0:
        raise ValueError(f"vmax_fraction must be > 0, got {vmax_fraction}")
    if c1 < 0 or c2 < 0:
        raise ValueError(f"c1 and c2 must be >= 0, got c1={c1}, c2={c2}")
