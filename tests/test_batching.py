"""Batching, broadcasting, dtypes and compilation caching of the regressor."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import sedsabso_jax as sj
from sedsabso_jax.dynamics._regressor import _regressor_jit, padded_samples


def test_batched_equals_unbatched(rng):
    robot = sj.robots.rs010n()
    q, qd, qdd = rng.normal(size=(3, 2, 5, 3))
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    assert Y.shape == (2, 5, 3, 36) and Y.dtype == np.float64
    for i in range(2):
        for k in range(5):
            np.testing.assert_allclose(Y[i, k], sj.regressor(robot, q[i, k], qd[i, k], qdd[i, k]),
                                       rtol=1e-13, atol=1e-13)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    assert tau.shape == (2, 5, 3)
    np.testing.assert_allclose(tau, Y @ np.asarray(robot.params), rtol=1e-13, atol=1e-12)


def test_batch_not_multiple_of_chunk(rng):
    """lax.map's remainder chunk gives the same rows as the full chunks."""
    robot = sj.robots.rs010n()
    q, qd, qdd = rng.normal(size=(3, 37, 3))
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    np.testing.assert_allclose(Y[-3:], sj.regressor(robot, q[-3:], qd[-3:], qdd[-3:]), atol=1e-13)


def test_leading_axes_broadcast(rng):
    robot = sj.robots.rs010n()
    q = rng.normal(size=(4, 3))
    Y = sj.regressor(robot, q, np.zeros(3), np.zeros(3))  # statics at 4 configurations
    assert Y.shape == (4, 3, 36)
    np.testing.assert_allclose(Y[2], sj.regressor(robot, q[2], np.zeros(3), np.zeros(3)))


def test_float32_on_request(rng):
    robot = sj.robots.rs010n()
    q, qd, qdd = rng.normal(size=(3, 3))
    Y32 = sj.regressor(robot, q, qd, qdd, dtype=jnp.float32)
    assert Y32.dtype == jnp.float32
    np.testing.assert_allclose(Y32, sj.regressor(robot, q, qd, qdd), rtol=1e-4, atol=1e-4)


def test_second_call_does_not_recompile(rng):
    robot = sj.robots.rs010n()
    q, qd, qdd = rng.normal(size=(3, 11, 3))
    sj.regressor(robot, q, qd, qdd).block_until_ready()
    before = _regressor_jit._cache_size()
    sj.regressor(robot, q + 1.0, qd, qdd).block_until_ready()
    # other parameter values, same structure: the same compiled code
    other = robot.with_params(np.asarray(robot.params) * 2.0)
    sj.regressor(other, q, qd, qdd).block_until_ready()
    sj.inverse_dynamics(other, other.params, q, qd, qdd).block_until_ready()
    assert _regressor_jit._cache_size() == before


def test_nearby_lengths_share_one_compilation(rng):
    """The base regressor of recordings of nearby lengths (a validation's outer splits)
    is computed at one padded length: one compilation (seconds, hundreds of memory maps
    each), the same rows as their own length's program, and no padding row returned."""
    robot = sj.robots.rs010n()
    base = sj.base_parameters(robot)
    q, qd, qdd = (jnp.asarray(a) for a in rng.normal(size=(3, 1040, 3)))
    base.regressor(q[:1030], qd[:1030], qdd[:1030]).block_until_ready()
    before = _regressor_jit._cache_size()
    lengths = (1025, 1039, 1040)  # 1025..1088 share one padded length
    found = [base.regressor(q[:T], qd[:T], qdd[:T]) for T in lengths]
    found.append(base.regressor(q[:1040].reshape(8, 130, 3), qd[:1040].reshape(8, 130, 3),
                                qdd[:1040].reshape(8, 130, 3)).reshape(1040, 3, -1))
    assert _regressor_jit._cache_size() == before
    assert [Y.shape for Y in found] == [(T, 3, base.rank) for T in (*lengths, 1040)]
    assert np.array_equal(np.asarray(found[-1]), np.asarray(found[-2]))
    own = _regressor_jit(robot, q[:1039], qd[:1039], qdd[:1039], jnp.dtype(jnp.float64), 16)
    assert np.array_equal(np.asarray(found[1]), np.asarray(own)[..., list(base.indices)])
    np.testing.assert_array_equal(found[0], found[1][:1025])
    # the full regressor, as a user times it, at its own length: no copy of the rows
    sj.regressor(robot, q[:1027], qd[:1027], qdd[:1027]).block_until_ready()
    assert _regressor_jit._cache_size() == before + 2


def test_padded_lengths():
    """At most an eighth more samples, exact up to 15, eight lengths per doubling; a
    multiple of the chunk where one is asked, at most a chunk more."""
    for samples in range(5000):
        padded = padded_samples(samples)
        assert samples <= padded <= samples + samples // 8 + (samples > 15)
        assert samples > 15 or padded == samples
        for chunk in (8, 16, 1000):
            assert padded_samples(samples, chunk) % chunk == 0
            assert padded <= padded_samples(samples, chunk) < padded + chunk
    assert len({padded_samples(s) for s in range(1025, 2049)}) == 8


def test_base_parameters_and_a_models_columns_share_one_program():
    """The base parameters' random states and those that find which of a model's extra
    columns the base spans are one padded length, a multiple of the CPU's chunk: one
    compilation of the regressor, with no second body for a remainder (each took 3 s of
    the default identification's compilation for the KUKA LWR4+)."""
    from sedsabso_jax.identification._model._torque_model import TorqueModel

    # a structure no other test compiles: its programs are this test's alone
    robot = sj.robots.from_dh([0.3, 0.0, 0.1, 0.0], [0.0, 0.4, 0.3, 0.0],
                              [np.pi / 2, 0.0, 0.3, -np.pi / 2])
    before = _regressor_jit._cache_size()
    base = sj.base_parameters(robot)
    assert _regressor_jit._cache_size() == before + 1
    model = TorqueModel(base, (sj.Offset(),))
    assert model.dim == base.rank + 4
    assert _regressor_jit._cache_size() == before + 1
    assert padded_samples(50, 16) == 64 and padded_samples(50, 8) == 56


def test_differentiable_in_q(rng):
    """jax.grad through the regressor agrees with central differences."""
    import jax

    robot = sj.robots.rs010n()
    q, qd, qdd = rng.normal(size=(3, 3))
    from sedsabso_jax.dynamics._regressor import unchecked_regressor

    def f(q):
        return jnp.sum(unchecked_regressor(robot, q, qd, qdd) ** 2)

    g = jax.grad(f)(jnp.asarray(q))
    eps = 1e-6
    fd = [(f(q + eps * e) - f(q - eps * e)) / (2 * eps) for e in np.eye(3)]
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-5)
