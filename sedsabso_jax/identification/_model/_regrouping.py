"""Which extra columns of a torque model the base regressor already spans
(:func:`kept_columns`): found as the base parameters are, at random states, once per
structure of model. A term that is a body keeps its columns whole: its parameters are
one body's, and those the data cannot tell apart are reported so (an infinite standard
deviation), not dropped."""

from __future__ import annotations

import contextlib
import dataclasses
from typing import Any

import jax
import numpy as np

from ...dynamics._base_parameters import RANK_TOLERANCE, random_states

#: Which extra columns a model keeps, by the model's structure and values
#: (:attr:`~._torque_model.TorqueModel.structure`); the latest :data:`KEEP` models'.
_KEPT: dict[tuple, np.ndarray] = {}
KEEP = 256


def kept_columns(model: Any) -> np.ndarray:
    """Indices of the extra columns of ``model`` (a :class:`~._torque_model.TorqueModel`)
    that the base regressor does not span: scaled columns at random states, ordered QR
    (as :func:`~sedsabso_jax.base_parameters`); kept per model structure and values
    (its base, recordings, transmission and terms, every field of each but the values
    they read of a fit, taken at random: :func:`read_at_random`). A model whose
    searched values are traced (:meth:`~._torque_model.TorqueModel.partition`) is taken
    with them at 1: which columns the base spans follows from the terms' kinds and fixed
    values, not from a scale's value."""
    traced = any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(model.terms))
    if traced:
        model = jax.tree_util.tree_map(
            lambda x: np.ones(x.shape) if isinstance(x, jax.core.Tracer) else x, model)
    model = read_at_random(model)
    key = model.structure
    if key not in _KEPT:
        if len(_KEPT) >= KEEP:
            del _KEPT[next(iter(_KEPT))]
        with jax.ensure_compile_time_eval() if traced else contextlib.nullcontext():
            _KEPT[key] = _independent(model)  # concrete, inside jax.jit too
    return _KEPT[key]


def read_at_random(model: Any) -> Any:
    """``model`` with the values its terms read of a fit
    (:attr:`~._term.AbstractTerm.read_fields`: values of the rigid-body columns) at a
    random point: which of their columns the base spans must not depend on them."""
    if not any(t.read_fields for t in model.terms):
        return model
    size = len(model.rigid_columns) + sum(len(t.names(model)) for t in model.terms if t.body)
    point = tuple(np.random.default_rng(2).standard_normal(size).tolist())
    terms = tuple(dataclasses.replace(t, **dict.fromkeys(t.read_fields, point))
                  if t.read_fields else t for t in model.terms)
    return dataclasses.replace(model, terms=terms)


def _independent(model: Any) -> np.ndarray:
    if not model._extra_names():
        return np.zeros(0, dtype=int)
    robot = model.robot
    # the sample count base_parameters uses: the regressor is compiled for it already
    q, qd, qdd = random_states(robot, max(50, -(-4 * robot.n_params // robot.n_joints)),
                               seed=1)
    recording = np.random.default_rng(1).integers(0, model.recordings, q.shape[0])
    Y = model._full_regressor(q, qd, qdd, recording if model.recordings > 1 else None)
    W = Y.reshape(-1, Y.shape[-1])
    W = W / np.where(np.linalg.norm(W, axis=0) > 0, np.linalg.norm(W, axis=0), 1.0)
    d = np.abs(np.diag(np.linalg.qr(W, mode="r")))
    independent = d > RANK_TOLERANCE * d.max()
    bodies = [term.body for term in model.terms for _ in term.names(model)]
    return np.flatnonzero(independent[model.base.rank:] | np.array(bodies, dtype=bool))
