"""Deprecated module path: sedsabso_jax.identification.validation (documented in 0.2). Its names
are public elsewhere now (each warning says where); kept with a warning through 0.3.x."""

from __future__ import annotations

from .. import _deprecation

__getattr__ = _deprecation.moved(__name__, {
    "select_model": "sedsabso_jax.select_model",
    "cross_validate": "sedsabso_jax.cross_validate",
    "choose_prior_strength": "sedsabso_jax.choose_prior_strength",
    "phase_folds": "sedsabso_jax.identification.phase_folds",
    "PRIOR_STRENGTHS": "sedsabso_jax.identification.PRIOR_STRENGTHS",
    "FRICTION_CANDIDATES": "sedsabso_jax.identification.FRICTION_CANDIDATES",
}, module="sedsabso_jax.identification._validation")
