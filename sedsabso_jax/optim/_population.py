"""What every swarm's population is: the shared state of one run (:class:`SwarmState`),
evaluation with non-finite values counted, personal, global and best-ever updates, and a
shrinking population (SEDSABSO's Eq. 15-16) kept as a fixed number of slots with an
active mask, reordered best first and cut at a phase's start. A swarm's own fields live in
its own subclass of :class:`SwarmState` (:class:`~._bso.BeetleState`,
:class:`~._sedsabso.SEDSABSOState`)."""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar, TypeVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Bool, Float, Int, PRNGKeyArray

from ._fitness import Fitness, finite_or_inf
from ._solver import Bounds


class SwarmState(eqx.Module):
    """One run's population, what every swarm has. Inactive slots still move (masking
    them would cost more than moving them) but their personal bests are frozen and they
    never return: only active slots' personal bests can become the best.

    ``key`` is the chain the iterations draw from (iteration ``t`` uses ``split(key)[1]``
    and carries ``split(key)[0]``), ``t`` the iterations done of ``iterations``;
    ``round`` and ``asked`` where a loop of ``ask``/``tell`` stands
    (:meth:`~._swarm.AbstractSwarm.ask`): the round whose points are asked next (-1: the
    initial population), and whether they were asked and wait for ``tell``. Between
    iterations they are ``0, False``. A subclass adds a swarm's own fields, and names
    those of one value per slot in :attr:`per_slot` (reordered with the slots)."""

    x: Float[Array, "slots d"]  # x_i: positions
    v: Float[Array, "slots d"]  # V_i: velocities
    pbest_x: Float[Array, "slots d"]  # P_i: personal bests
    pbest_f: Float[Array, " slots"]
    active: Bool[Array, " slots"]
    slot_nonfinite: Int[Array, " slots"]  # non-finite evaluations of each active slot
    guide_x: Float[Array, " d"]  # g: the global best that steers the velocities
    guide_f: Float[Array, ""]
    best_x: Float[Array, " d"]  # best point ever evaluated: what is reported
    best_f: Float[Array, ""]
    n_evaluations: Int[Array, ""]
    n_nonfinite: Int[Array, ""]  # non-finite evaluations not in slot_nonfinite
    key: PRNGKeyArray
    t: Int[Array, ""]
    iterations: int = eqx.field(static=True)
    round: int = eqx.field(static=True)
    asked: bool = eqx.field(static=True)

    #: Fields of one value per slot: reordered and cut with the slots.
    per_slot: ClassVar[tuple[str, ...]] = ("x", "v", "pbest_x", "pbest_f", "active")

    @property
    def nonfinite_total(self) -> Int[Array, ""]:
        """Every non-finite evaluation so far (counted per slot inside the loop, where a
        sum per iteration would cost a reduction; summed here)."""
        return self.n_nonfinite + jnp.sum(self.slot_nonfinite, dtype=jnp.int32)


#: A swarm's state: :class:`SwarmState` or a swarm's subclass of it.
S = TypeVar("S", bound=SwarmState)
T = TypeVar("T", bound=SwarmState)


def replace(state: S, **changes: Any) -> S:
    """``state`` with fields replaced (static ones included)."""
    return dataclasses.replace(state, **changes)


def extend(cls: type[T], state: SwarmState, **fields: Any) -> T:
    """``state`` as a ``cls`` (a subclass of its class) with ``fields`` added."""
    return cls(**{f.name: getattr(state, f.name) for f in dataclasses.fields(state)},
               **fields)


#: :attr:`SwarmState.round` of a started population: its initial positions are asked next.
INITIAL = -1


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


def initial_positions(lower: Bounds, upper: Bounds, key: PRNGKeyArray, slots: int,
                      vmax: Float[Array, " d"]
                      ) -> tuple[Float[Array, "slots d"], Float[Array, "slots d"]]:
    """Positions uniform in the box, velocities uniform in ``+-vmax``."""
    kx, kv = jax.random.split(key)
    d = lower.shape[0]
    x = lower + (upper - lower) * jax.random.uniform(kx, (slots, d), lower.dtype)
    v = vmax * jax.random.uniform(kv, (slots, d), lower.dtype, -1.0, 1.0)
    return x, v


def started(x: Float[Array, "slots d"], v: Float[Array, "slots d"], key: PRNGKeyArray,
            iterations: int) -> SwarmState:
    """A population at ``x`` with velocities ``v``, not evaluated (round :data:`INITIAL`;
    its bests are placeholders until :func:`initial_bests`)."""
    slots = x.shape[0]
    zero = jnp.zeros((), x.dtype)
    return SwarmState(
        x=x, v=v, pbest_x=x, pbest_f=jnp.zeros(slots, x.dtype),
        active=jnp.ones(slots, bool), slot_nonfinite=jnp.zeros(slots, jnp.int32),
        guide_x=x[0], guide_f=zero, best_x=x[0], best_f=zero,
        n_evaluations=jnp.int32(slots), n_nonfinite=jnp.int32(0), key=key,
        t=jnp.int32(0), iterations=int(iterations), round=INITIAL, asked=False)


def initial_bests(state: S, raw: Float[Array, " slots"]) -> S:
    """The started population with its raw fitness ``raw``: every slot active, each
    position its personal best, the best of them the guide and the best ever; round 0."""
    x = state.x
    slots = x.shape[0]
    f, bad = evaluate(None, x, raw=raw)
    i = jnp.argmin(f)
    return replace(
        state, pbest_x=x, pbest_f=f, active=jnp.ones(slots, bool),
        slot_nonfinite=jnp.zeros(slots, jnp.int32), guide_x=x[i], guide_f=f[i],
        best_x=x[i], best_f=f[i], n_evaluations=jnp.int32(slots),
        n_nonfinite=jnp.sum(bad, dtype=jnp.int32), t=jnp.int32(0), round=0, asked=False)


def update_bests(state: S, x: Float[Array, "slots d"], f: Float[Array, " slots"]
                 ) -> tuple[S, tuple[Float[Array, " d"], Float[Array, ""]]]:
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


def absorb_positions(state: S, raw: Float[Array, " slots"], evaluations: int,
                     extra_bad: Int[ArrayLike, " slots"] = 0
                     ) -> tuple[S, tuple[Float[Array, " d"], Float[Array, ""]]]:
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


def set_active(state: S, n_active: Int[ArrayLike, ""]) -> S:
    """Keep the ``n_active`` slots with the best personal bests (worst dropped first)."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    rank = jnp.empty_like(order).at[order].set(jnp.arange(order.shape[0]))
    return eqx.tree_at(lambda s: s.active, state, rank < n_active)


def _best_first(state: S, slots) -> tuple[Array, S]:
    """The slot order best first (active before inactive; stable) and the state with the
    per-slot non-finite counts moved to the total."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    state = eqx.tree_at(lambda s: (s.n_nonfinite, s.slot_nonfinite), state,
                        (state.nonfinite_total, jnp.zeros(slots, jnp.int32)))
    return order, state


def _per_slot(state: S, order: Array) -> S:
    return replace(state, **{k: getattr(state, k)[order] for k in state.per_slot})


def shrink(state: S, slots: int) -> S:
    """Reorder slots best first (active before inactive) and keep the first ``slots``
    (the per-slot non-finite counts move to the total first)."""
    order, state = _best_first(state, slots)
    return _per_slot(state, order[:slots])


def reorder(state: S, slots: Int[ArrayLike, ""]) -> S:
    """:func:`shrink` without the cut: the slots reordered best first and those from
    ``slots`` on made inactive (the state keeps its shape)."""
    n = state.x.shape[0]
    order, state = _best_first(state, n)
    state = _per_slot(state, order)
    return eqx.tree_at(lambda s: s.active, state, state.active & (jnp.arange(n) < slots))
