"""A swarm's population and the operations on it: the state of one run
(:class:`SwarmState`), evaluation with non-finite values counted, personal, global and
best-ever updates, and a shrinking population (SEDSABSO's Eq. 15-16) kept as a fixed
number of slots with an active mask, reordered best first and cut at a phase's start."""

from __future__ import annotations

import dataclasses
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Bool, Float, Int, PRNGKeyArray

from ._fitness import Fitness, finite_or_inf
from ._solver import Bounds


class SwarmState(eqx.Module):
    """One run's population. Inactive slots still move (masking them would cost more
    than moving them) but their personal bests are frozen and they never return: only
    active slots' personal bests can become the best. Nothing of the fitness's size is
    carried from one iteration to the next: a beetle's antenna difference (Eq. 12) at
    its current position is computed with that position's fitness, in the same pass,
    and carried as one number per slot.

    ``key`` is the chain the iterations draw from (iteration ``t`` uses ``split(key)[1]``
    and carries ``split(key)[0]``), ``t`` the iterations done of ``iterations``;
    ``pending`` what a later round of the iteration needs (SEDSABSO's annealing draws and
    candidates; its structure never changes); ``round`` and ``asked`` where a loop of
    ``ask``/``tell`` stands (:meth:`~._swarm.AbstractSwarm.ask`): the round whose points
    are asked next (-1: the initial population), and whether they were asked and wait
    for ``tell``. Between iterations they are ``0, False``."""

    x: Float[Array, "slots d"]
    v: Float[Array, "slots d"]
    antennae: Float[Array, " slots"]  # f(x + a v) - f(x - a v) (beetles; 0 otherwise)
    antennae_bad: Int[Array, " slots"]  # how many of those two were NaN or Inf
    pbest_x: Float[Array, "slots d"]
    pbest_f: Float[Array, " slots"]
    active: Bool[Array, " slots"]
    slot_nonfinite: Int[Array, " slots"]  # non-finite evaluations of each active slot
    guide_x: Float[Array, " d"]  # global best that steers the velocities (SA guide)
    guide_f: Float[Array, ""]
    best_x: Float[Array, " d"]  # best point ever evaluated: what is reported
    best_f: Float[Array, ""]
    temperature: Float[Array, ""]
    sa_accepted: Int[Array, ""]
    n_evaluations: Int[Array, ""]
    n_nonfinite: Int[Array, ""]  # non-finite evaluations not in slot_nonfinite
    key: Any = None
    t: Int[Array, ""] = eqx.field(default_factory=lambda: jnp.int32(0))
    iterations: int = eqx.field(static=True, default=1)
    pending: Any = None
    round: int = eqx.field(static=True, default=0)
    asked: bool = eqx.field(static=True, default=False)

    @property
    def nonfinite_total(self) -> Int[Array, ""]:
        """Every non-finite evaluation so far (counted per slot inside the loop, where a
        sum per iteration would cost a reduction; summed here)."""
        return self.n_nonfinite + jnp.sum(self.slot_nonfinite, dtype=jnp.int32)


def replace(state: SwarmState, **changes: Any) -> SwarmState:
    """``state`` with fields replaced (static ones included)."""
    return dataclasses.replace(state, **changes)


def evaluate(fitness: Fitness | None, X: Float[Array, "k d"],
             mask: Bool[Array, " k"] | None = None, raw: Float[Array, " k"] | None = None
             ) -> tuple[Float[Array, " k"], Int[Array, " k"]]:
    """Fitness of the members ``X`` (or their ``raw`` values when already computed),
    non-finite values mapped to +Inf, and per member 1 where a value was non-finite
    (0 outside ``mask`` when given)."""
    raw = fitness.evaluate(X) if raw is None else raw  # type: ignore[union-attr]
    bad = ~jnp.isfinite(raw)
    if mask is not None:
        bad = bad & mask
    return finite_or_inf(raw), bad.astype(jnp.int32)


def antenna_difference(fl: Float[Array, " k"], fr: Float[Array, " k"]
                       ) -> tuple[Float[Array, " k"], Int[Array, " k"]]:
    """``(f(xl) - f(xr), how many of the two were NaN or Inf)`` per member from the two
    antennae's raw values; a NaN or Inf value counts as +Inf."""
    bad = (~jnp.isfinite(fl)).astype(jnp.int32) + (~jnp.isfinite(fr)).astype(jnp.int32)
    return finite_or_inf(fl) - finite_or_inf(fr), bad


def initial_positions(lower: Bounds, upper: Bounds, key: PRNGKeyArray, slots: int,
                      vmax: Float[Array, " d"]
                      ) -> tuple[Float[Array, "slots d"], Float[Array, "slots d"]]:
    """Positions uniform in the box, velocities uniform in ``+-vmax``."""
    kx, kv = jax.random.split(key)
    d = lower.shape[0]
    x = lower + (upper - lower) * jax.random.uniform(kx, (slots, d), lower.dtype)
    v = vmax * jax.random.uniform(kv, (slots, d), lower.dtype, -1.0, 1.0)
    return x, v


def initial_from(x: Float[Array, "slots d"], v: Float[Array, "slots d"],
                 raw: Float[Array, " slots"], diff: Float[Array, " slots"] | None,
                 diff_bad: Int[Array, " slots"] | None, temperature: Float[ArrayLike, ""] = 0.0
                 ) -> SwarmState:
    """The state of a population at ``x`` with velocities ``v`` and raw fitness ``raw``
    (and antenna differences, for beetles)."""
    slots = x.shape[0]
    if diff is None:
        diff, diff_bad = jnp.zeros(slots, x.dtype), jnp.zeros(slots, jnp.int32)
    f, bad = evaluate(None, x, raw=raw)
    i = jnp.argmin(f)
    return SwarmState(
        x=x, v=v, antennae=diff, antennae_bad=diff_bad,  # type: ignore[arg-type]
        pbest_x=x, pbest_f=f,
        active=jnp.ones(slots, bool), slot_nonfinite=jnp.zeros(slots, jnp.int32),
        guide_x=x[i], guide_f=f[i], best_x=x[i], best_f=f[i],
        temperature=jnp.asarray(temperature, x.dtype), sa_accepted=jnp.int32(0),
        n_evaluations=jnp.int32(slots), n_nonfinite=jnp.sum(bad, dtype=jnp.int32),
    )


def initial_state(fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
                  slots: int, vmax: Float[Array, " d"], temperature: Float[ArrayLike, ""] = 0.0,
                  antenna: Float[ArrayLike, ""] | None = None) -> SwarmState:
    """Positions uniform in the box, velocities uniform in ``+-vmax``, evaluated; with
    ``antenna`` (the beetles' ``a``), also each slot's ``f(x + a v) - f(x - a v)``."""
    x, v = initial_positions(lower, upper, key, slots, vmax)
    if antenna is None:
        raw, diff, diff_bad = fitness.evaluate(x), None, None
    else:
        raw, diff, diff_bad = fitness.evaluate_with_antennae(x, v, antenna)
    return initial_from(x, v, raw, diff, diff_bad, temperature)


def update_bests(state: SwarmState, x: Float[Array, "slots d"], f: Float[Array, " slots"]
                 ) -> tuple[SwarmState, tuple[Float[Array, " d"], Float[Array, ""]]]:
    """Take the new positions; update the active slots' personal bests and the best ever.
    Returns the state and the swarm's global best ``(x, f)`` among the active slots."""
    better = state.active & (f < state.pbest_f)
    pbest_f = jnp.where(better, f, state.pbest_f)
    pbest_x = jnp.where(better[:, None], x, state.pbest_x)
    masked = jnp.where(state.active, pbest_f, jnp.inf)
    i = jnp.argmin(masked)
    improve_best = masked[i] < state.best_f
    return eqx.tree_at(
        lambda s: (s.x, s.pbest_x, s.pbest_f, s.best_x, s.best_f),
        state,
        (x, pbest_x, pbest_f,
         jnp.where(improve_best, pbest_x[i], state.best_x),
         jnp.where(improve_best, masked[i], state.best_f)),
    ), (pbest_x[i], masked[i])


def absorb_positions(state: SwarmState, raw: Float[Array, " slots"], evaluations: int,
                     extra_bad: Int[ArrayLike, " slots"] = 0
                     ) -> tuple[SwarmState, tuple[Float[Array, " d"], Float[Array, ""]]]:
    """The moved population's raw fitness taken in (``evaluations`` per active member;
    its non-finite values, and ``extra_bad`` more, counted per slot), then
    :func:`update_bests`."""
    f, bad = evaluate(None, state.x, state.active, raw)
    n_active = jnp.sum(state.active, dtype=jnp.int32)
    state = replace(state, n_evaluations=state.n_evaluations + evaluations * n_active,
                    slot_nonfinite=state.slot_nonfinite + bad + extra_bad)
    return update_bests(state, state.x, f)


def swarm_best(state: SwarmState) -> tuple[Float[Array, " d"], Float[Array, ""]]:
    """The swarm's global best ``(x, f)`` among the active slots' personal bests."""
    masked = jnp.where(state.active, state.pbest_f, jnp.inf)
    i = jnp.argmin(masked)
    return state.pbest_x[i], masked[i]


def set_active(state: SwarmState, n_active: Int[ArrayLike, ""]) -> SwarmState:
    """Keep the ``n_active`` slots with the best personal bests (worst dropped first)."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    rank = jnp.empty_like(order).at[order].set(jnp.arange(order.shape[0]))
    return eqx.tree_at(lambda s: s.active, state, rank < n_active)


PER_SLOT = ("x", "v", "antennae", "antennae_bad", "pbest_x", "pbest_f", "active")


def _best_first(state: SwarmState, slots) -> tuple[Array, SwarmState]:
    """The slot order best first (active before inactive; stable) and the state with the
    per-slot non-finite counts moved to the total."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    state = eqx.tree_at(lambda s: (s.n_nonfinite, s.slot_nonfinite), state,
                        (state.nonfinite_total, jnp.zeros(slots, jnp.int32)))
    return order, state


def _per_slot(state: SwarmState, order: Array) -> SwarmState:
    return eqx.tree_at(lambda s: [getattr(s, k) for k in PER_SLOT], state,
                       [getattr(state, k)[order] for k in PER_SLOT])


def shrink(state: SwarmState, slots: int) -> SwarmState:
    """Reorder slots best first (active before inactive) and keep the first ``slots``
    (the per-slot non-finite counts move to the total first)."""
    order, state = _best_first(state, slots)
    return _per_slot(state, order[:slots])


def reorder(state: SwarmState, slots: Int[ArrayLike, ""]) -> SwarmState:
    """:func:`shrink` without the cut: the slots reordered best first and those from
    ``slots`` on made inactive (the state keeps its shape)."""
    n = state.x.shape[0]
    order, state = _best_first(state, n)
    state = _per_slot(state, order)
    return eqx.tree_at(lambda s: s.active, state, state.active & (jnp.arange(n) < slots))
