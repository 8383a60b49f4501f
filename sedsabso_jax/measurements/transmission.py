"""Deprecated module path: sedsabso_jax.measurements.transmission (documented in 0.2). Its names
are public elsewhere now (each warning says where); kept with a warning through 0.3.x."""

from __future__ import annotations

from .. import _deprecation

__getattr__ = _deprecation.moved(__name__, {
    "Transmission": "sedsabso_jax.Transmission",
    "coupled_motors": "sedsabso_jax.measurements.coupled_motors",
}, module="sedsabso_jax.measurements._transmission")
