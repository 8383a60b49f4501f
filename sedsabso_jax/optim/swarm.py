"""What every swarm shares: the solver interface, the population state, and the operations
on it (evaluation, personal and global bests, a shrinking population).

A swarm is an immutable solver (an ``equinox.Module`` whose fields are its
hyperparameters) implementing :class:`AbstractSwarm`; :func:`~sedsabso_jax.minimise`
(``driver.py``) runs any of them. A variable population (SEDSABSO's Eq. 15-16) uses a fixed
number of slots with an active mask; the driver splits the iterations into phases of
static, shrinking slot counts (:func:`phases`), so the work follows the active count while
everything compiles once.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .fitness import finite_or_inf


class AbstractSwarm(eqx.Module):
    """The interface :func:`~sedsabso_jax.minimise` runs: a static population
    :meth:`schedule`, :meth:`init` and :meth:`step` (one iteration), and :meth:`check`
    for the hyperparameters. Every swarm here moves its population with velocities
    clamped to ``vmax_fraction (upper - lower)``."""

    vmax_fraction: eqx.AbstractVar[float]

    @property
    @abc.abstractmethod
    def n_slots(self) -> int:
        """Population slots to allocate (the largest population of the run)."""

    def schedule(self, iterations: int) -> np.ndarray:
        """Active population per iteration (static, never growing). Default: all
        :attr:`n_slots` throughout."""
        return np.full(iterations, self.n_slots)

    @property
    def n_phases(self) -> int:
        """Compiled phases of static slot count the iterations are split into."""
        return 1

    def init(self, fitness, lower, upper, key) -> SwarmState:
        """The initial population: uniform in the box ``[lower, upper]``, velocities
        uniform in ``+-Vmax``."""
        return initial_state(fitness, lower, upper, key, self.n_slots,
                             self.vmax_fraction * (upper - lower))

    def randomness(self, key, dim: int, dtype):
        """What one iteration draws from, derived from the iteration's key: keys for the
        population's draws (their shape follows the phase) or small draws made up front.
        Default: two keys, for ``r1`` and ``r2`` of the velocity update."""
        return jax.random.split(key)

    @abc.abstractmethod
    def step(self, fitness, state: SwarmState, t, iterations: int, lower, upper,
             keys) -> SwarmState:
        """Iteration ``t`` of ``iterations``; ``keys`` as returned by :meth:`randomness`."""

    @abc.abstractmethod
    def check(self) -> None:
        """Raise ValueError on bad hyperparameters (called before anything compiles)."""


class SwarmState(eqx.Module):
    """One run's population. Inactive slots still move (masking them would copy the
    large embedding arrays every iteration) but their personal bests are frozen and they
    never return: only active slots' personal bests can become the best."""

    x: Float[Array, "slots d"]
    v: Float[Array, "slots d"]
    ex: Float[Array, "slots m"]  # embed(x): W x for Eq. 17, x for a black box
    ev: Float[Array, "slots m"]  # embed(v), used by the beetles' antennae
    pbest_x: Float[Array, "slots d"]
    pbest_f: Float[Array, " slots"]
    active: Bool[Array, " slots"]
    guide_x: Float[Array, " d"]  # global best that steers the velocities (SA guide)
    guide_f: Float[Array, ""]
    best_x: Float[Array, " d"]  # best point ever evaluated: what is reported
    best_f: Float[Array, ""]
    temperature: Float[Array, ""]
    sa_accepted: Int[Array, ""]
    n_evaluations: Int[Array, ""]
    n_nonfinite: Int[Array, ""]


def evaluate(fitness, e, mask=None):
    """Fitness from embeddings, non-finite values mapped to +Inf and counted."""
    raw = fitness.value(e)
    bad = ~jnp.isfinite(raw)
    if mask is not None:
        bad = bad & mask
    return finite_or_inf(raw), jnp.sum(bad, dtype=jnp.int32)


def initial_state(fitness, lower, upper, key, slots: int, vmax, temperature=0.0) -> SwarmState:
    kx, kv = jax.random.split(key)
    d = lower.shape[0]
    x = lower + (upper - lower) * jax.random.uniform(kx, (slots, d), lower.dtype)
    v = vmax * jax.random.uniform(kv, (slots, d), lower.dtype, -1.0, 1.0)
    ex, ev = fitness.embed(x), fitness.embed(v)
    f, bad = evaluate(fitness, ex)
    i = jnp.argmin(f)
    return SwarmState(
        x=x, v=v, ex=ex, ev=ev, pbest_x=x, pbest_f=f,
        active=jnp.ones(slots, bool), guide_x=x[i], guide_f=f[i], best_x=x[i], best_f=f[i],
        temperature=jnp.asarray(temperature, lower.dtype), sa_accepted=jnp.int32(0),
        n_evaluations=jnp.int32(slots), n_nonfinite=bad,
    )


def update_bests(state: SwarmState, x, ex, f):
    """Take the new positions; update the active slots' personal bests and the best ever.
    Returns the state and the swarm's global best ``(x, f)`` among the active slots."""
    better = state.active & (f < state.pbest_f)
    pbest_f = jnp.where(better, f, state.pbest_f)
    pbest_x = jnp.where(better[:, None], x, state.pbest_x)
    masked = jnp.where(state.active, pbest_f, jnp.inf)
    i = jnp.argmin(masked)
    improve_best = masked[i] < state.best_f
    return eqx.tree_at(
        lambda s: (s.x, s.ex, s.pbest_x, s.pbest_f, s.best_x, s.best_f),
        state,
        (x, ex, pbest_x, pbest_f,
         jnp.where(improve_best, pbest_x[i], state.best_x),
         jnp.where(improve_best, masked[i], state.best_f)),
    ), (pbest_x[i], masked[i])


def set_active(state: SwarmState, n_active) -> SwarmState:
    """Keep the ``n_active`` slots with the best personal bests (worst dropped first)."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    rank = jnp.empty_like(order).at[order].set(jnp.arange(order.shape[0]))
    return eqx.tree_at(lambda s: s.active, state, rank < n_active)


def shrink(state: SwarmState, slots: int) -> SwarmState:
    """Reorder slots best first (active before inactive) and keep the first ``slots``."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))[:slots]
    per_slot = ("x", "v", "ex", "ev", "pbest_x", "pbest_f", "active")
    return eqx.tree_at(lambda s: [getattr(s, k) for k in per_slot], state,
                       [getattr(state, k)[order] for k in per_slot])


def phases(schedule: np.ndarray, n_phases: int):
    """Split iterations into at most ``n_phases`` runs of iterations with a static slot
    count each: the largest active count inside the phase (N(t) never grows)."""
    K = len(schedule)
    bounds = sorted({round(k * K / n_phases) for k in range(n_phases)} | {K})
    return [(a, b, int(schedule[a:b].max())) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def uniforms(keys, shape, dtype):
    """``jax.random.uniform(k, shape)`` for each key of ``keys`` in one batched call (the
    same numbers as one call per key)."""
    return jax.vmap(lambda k: jax.random.uniform(k, shape, dtype))(keys)


def check_population(n, name: str) -> None:
    """A population size must be an integer >= 1."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"{name} must be an integer >= 1, got {n!r}")


def check_velocity_update(c1: float, c2: float, vmax_fraction: float) -> None:
    """The velocity update's coefficients: ``c1, c2 >= 0`` and ``vmax_fraction > 0``."""
    if vmax_fraction <= 0:
        raise ValueError(f"vmax_fraction must be > 0, got {vmax_fraction}")
    if c1 < 0 or c2 < 0:
        raise ValueError(f"c1 and c2 must be >= 0, got c1={c1}, c2={c2}")
