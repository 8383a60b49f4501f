"""A torque model's searched parameters are leaves of its tree (issue 43):
``searched, rest = model.partition()`` splits it as ``equinox.partition`` does, and
``equinox.combine`` puts values back, so the model's own regressor is a function of them
that ``jax.grad``, ``jax.jit`` and ``jax.vmap`` take as they take any equinox model. The
references are the model's NumPy path (the values placed as floats) and central finite
differences of it, never the traced code itself."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification import parse_friction

ROBOT = sj.robots.rs010n()
N = ROBOT.n_joints


def _samples(T: int = 40, seed: int = 0):
    rng = np.random.default_rng(seed)
    q, qd, qdd = (rng.standard_normal((T, N)) for _ in range(3))
    return q, qd, qdd


@pytest.fixture(scope="module")
def model() -> sj.TorqueModel:
    return sj.TorqueModel.of(ROBOT, parse_friction("offset+smooth:fit+presliding:fit"))


def _values(model: sj.TorqueModel) -> np.ndarray:
    return np.concatenate([f.values for _, f in model.nonlinear()])


def test_partition_gives_the_searched_values_as_leaves(model):
    searched, rest = model.partition()
    leaves = jax.tree_util.tree_leaves(searched)
    assert [leaf.shape for leaf in leaves] == [(N,), (N,)]  # the smooth's, friction at rest's
    np.testing.assert_array_equal(np.concatenate(leaves), _values(model))
    assert rest.terms[1].velocity is None and rest.terms[2].displacement is None
    # the rest keeps every other leaf: the base's, the transmission's, the fixed fields'
    assert (len(jax.tree_util.tree_leaves(rest))
            == len(jax.tree_util.tree_leaves(eqx.combine(searched, rest))) - 2)


def test_combined_leaves_give_the_columns_of_the_values_placed(model):
    """Trial values put back by ``equinox.combine`` give, bit for bit, the columns of the
    model with those values placed as floats (:meth:`with_nonlinear`), on the NumPy path
    and, traced, under ``jax.jit`` (as leaves, or as the flat values a search traces)."""
    q, qd, qdd = _samples()
    searched, rest = model.partition()
    trial = jax.tree_util.tree_map(lambda v: v * jnp.array([0.5, 1.7, 3.0]), searched)
    placed = model.with_nonlinear(np.concatenate(jax.tree_util.tree_leaves(trial)))
    expected = placed.regressor(q, qd, qdd)
    np.testing.assert_array_equal(eqx.combine(trial, rest).regressor(q, qd, qdd), expected)
    traced = jax.jit(lambda p: eqx.combine(p, rest).regressor(q, qd, qdd))(trial)
    np.testing.assert_allclose(traced, expected, rtol=1e-12, atol=1e-12)
    # the compiled search's way: the flat values, traced, placed as leaves
    flat = jnp.concatenate(jax.tree_util.tree_leaves(trial))
    traced = jax.jit(lambda v: model.with_nonlinear(v).regressor(q, qd, qdd))(flat)
    np.testing.assert_allclose(traced, expected, rtol=1e-12, atol=1e-12)
    assert placed.names == model.names and traced.shape == expected.shape


def test_grad_of_a_loss_in_the_searched_leaves_matches_finite_differences(model):
    q, qd, qdd = _samples(seed=1)
    searched, rest = model.partition()
    rng = np.random.default_rng(2)
    x = rng.standard_normal(model.dim)
    tau = model.regressor(q, qd, qdd) @ x + 0.1 * rng.standard_normal((q.shape[0], N))
    start = jax.tree_util.tree_map(lambda v: v * 2.0, searched)  # off the start: no kink

    def loss(p):
        return jnp.sum((eqx.combine(p, rest).regressor(q, qd, qdd) @ x - tau) ** 2)

    grad = np.concatenate(jax.tree_util.tree_leaves(jax.jit(jax.grad(loss))(start)))
    flat = np.concatenate(jax.tree_util.tree_leaves(start))

    def numpy_loss(v):  # the NumPy path, the values placed as floats
        return float(np.sum((model.with_nonlinear(v).regressor(q, qd, qdd) @ x - tau) ** 2))

    h = 1e-6 * flat
    fd = np.array([(numpy_loss(flat + h[i] * e) - numpy_loss(flat - h[i] * e)) / (2 * h[i])
                   for i, e in enumerate(np.eye(len(flat)))])
    assert np.any(np.abs(fd) > 1e-3)  # the loss moves with them
    np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


def test_vmap_over_trials_of_the_leaves(model):
    q, qd, qdd = _samples(T=20, seed=3)
    searched, rest = model.partition()
    scales = jnp.array([0.5, 1.0, 4.0])
    trials = jax.tree_util.tree_map(lambda v: scales[:, None] * v, searched)
    batched = jax.vmap(lambda p: eqx.combine(p, rest).regressor(q, qd, qdd))(trials)
    for k in range(len(scales)):
        one = model.with_nonlinear(np.concatenate(
            [np.asarray(leaf[k]) for leaf in jax.tree_util.tree_leaves(trials)]))
        np.testing.assert_allclose(batched[k], one.regressor(q, qd, qdd), rtol=1e-12,
                                   atol=1e-12)


def test_nothing_searched_partitions_to_no_leaves():
    fixed = sj.TorqueModel.of(ROBOT, parse_friction("offset+smooth"))
    searched, rest = fixed.partition()
    assert jax.tree_util.tree_leaves(searched) == []
    q, qd, qdd = _samples()
    np.testing.assert_array_equal(eqx.combine(searched, rest).regressor(q, qd, qdd),
                                  fixed.regressor(q, qd, qdd))


def test_a_term_that_places_its_values_itself_is_named():
    """A term whose ``nonlinear`` names no field (it places its values in
    ``with_nonlinear``) still searches; ``partition`` refuses it by name."""

    class OneVelocity(sj.SmoothCoulomb):  # one scale for every joint, placed by hand
        def nonlinear(self, model):
            found = super().nonlinear(model)
            return dataclasses.replace(found, names=found.names[:1], values=found.values[:1],
                                       lower=found.lower[:1], upper=found.upper[:1],
                                       field=None)

        def with_nonlinear(self, values):
            if isinstance(values, jax.core.Tracer):
                return eqx.tree_at(lambda t: t.velocity, self, values[0])
            return dataclasses.replace(self, velocity=float(values[0]))

    own = sj.TorqueModel.of(ROBOT, OneVelocity(fitted=True))
    assert own.with_nonlinear(np.array([0.05])).terms[0].velocity == 0.05
    with pytest.raises(TypeError, match=r"\['smooth'\].*field"):
        own.partition()
