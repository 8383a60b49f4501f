"""Fitness functions for the optimisers, seen through two maps.

Every fitness here is ``value(embed(x))`` with ``embed`` LINEAR: for a black-box
``f(x, args)`` the embedding is ``x`` itself and ``value`` calls ``f``; for the paper's
identification fitness (Eq. 17) the embedding is ``W x`` and ``value`` is the L1 norm of
the residual. Linearity lets a swarm evaluate ``x + s V`` from ``embed(x) + s embed(V)``
without a new product with ``W`` (``W (x + s V) = W x + s W V``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float


def finite_or_inf(f):
    """NaN or Inf fitness counts as +Inf, so it never becomes a best."""
    return jnp.where(jnp.isfinite(f), f, jnp.inf)


class BlackBox(eqx.Module):
    """Any scalar fitness ``fn(x, args)``; the population is evaluated under ``vmap``."""

    fn: Callable[[Array, Any], Array] = eqx.field(static=True)
    args: Any = None

    def embed(self, X):
        return X

    def value(self, E):
        flat = E.reshape((-1, E.shape[-1]))
        return jax.vmap(lambda x: self.fn(x, self.args))(flat).reshape(E.shape[:-1])

    def __call__(self, x):
        return self.fn(x, self.args)

    def antenna_difference(self, E, G, a):
        """``(f(x + a v) - f(x - a v), non-finite count)`` per member from ``E = x``,
        ``G = v``: two evaluations; a NaN or Inf value counts as +Inf."""
        fl, fr = self.value(E + a * G), self.value(E - a * G)
        bad = (~jnp.isfinite(fl)).astype(jnp.int32) + (~jnp.isfinite(fr)).astype(jnp.int32)
        return finite_or_inf(fl) - finite_or_inf(fr), bad


class L1Residual(eqx.Module):
    """The paper's Eq. 17: ``f(p) = sum_i |W p - tau|_1`` over samples and joints.

    ``W`` is the stacked base regressor (Eq. 8), ``(m, d)`` with ``m = samples x joints``,
    and ``tau`` the measured torques stacked the same way.
    """

    W: Float[Array, "m d"]
    tau: Float[Array, " m"]

    def __init__(self, W, tau, dtype=jnp.float64):
        W = np.asarray(W, dtype=float)
        tau = np.asarray(tau, dtype=float)
        if W.ndim > 2:  # (samples, joints, d) -> stacked
            W = W.reshape(-1, W.shape[-1])
        tau = tau.reshape(-1)
        if W.ndim != 2 or W.shape[0] != tau.shape[0]:
            raise ValueError(f"W must be (m, d) and tau (m,); got W {W.shape}, tau {tau.shape}")
        if not (np.all(np.isfinite(W)) and np.all(np.isfinite(tau))):
            raise ValueError("W or tau contains NaN or Inf")
        self.W = jnp.asarray(W, dtype=dtype)
        self.tau = jnp.asarray(tau, dtype=dtype)

    @classmethod
    def from_base(cls, base, q, qd, qdd, tau, dtype=jnp.float64) -> L1Residual:
        """Eq. 17 for a :class:`~sedsabso_jax.BaseParameters` set and data
        ``q, qd, qdd, tau`` of shape ``(samples, n)``."""
        return cls(np.asarray(base.regressor(q, qd, qdd)), np.asarray(tau), dtype=dtype)

    @property
    def dim(self) -> int:
        return self.W.shape[1]

    def embed(self, X):
        return X @ self.W.T

    def value(self, E):
        return _row_sum(jnp.abs(E - self.tau))

    def __call__(self, x):
        return self.value(self.embed(x))

    def antenna_difference(self, E, G, a):
        """``(f(x + a v) - f(x - a v), non-finite count)`` per member from ``E = W x``,
        ``G = W v`` in ONE pass over the residuals: ``|r + a g| - |r - a g|`` summed."""
        R = E - self.tau
        diff = _row_sum(jnp.abs(R + a * G) - jnp.abs(R - a * G))
        return diff, (~jnp.isfinite(diff)).astype(jnp.int32)


def _row_sum(A):
    # sum over the long axis as a product with ones: XLA's CPU row reduction measured
    # slower inside the swarms' loops (BSO run: about -10 % float64, -15 % float32)
    return A @ jnp.ones(A.shape[-1], A.dtype)


def as_fitness(fitness, args=None):
    """A fitness object from a callable ``f(x, args)`` or one of the classes above."""
    if isinstance(fitness, (BlackBox, L1Residual)):
        if args is not None:
            raise ValueError("args only go with a plain callable fitness")
        return fitness
    if callable(fitness):
        return BlackBox(fitness, args)
    raise TypeError(f"fitness must be callable f(x, args) or an L1Residual, got {type(fitness)}")
