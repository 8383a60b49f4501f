"""Where a run of a swarm changes its population: the static plan of a run (Plan).

A variable population (SEDSABSO's Eq. 15-16) uses a fixed number of slots with an active
mask. A run is split into phases of static, shrinking slot counts (:func:`phases`): at a
phase's start the slots are reordered best first and cut to the phase's count, so the
work follows the active count while everything compiles once per phase. Within a phase,
where N(t) falls, the worst leave (the active mask)."""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True, eq=False)
class Plan:
    """Where a run of a swarm changes its slots, per iteration (static, NumPy):
    ``phases`` the ``(first, end, slots)`` of :func:`phases`; ``n_active`` N(t);
    ``starts`` whether a phase starts at t; ``slots`` the phase's slot count; ``drops``
    whether N(t) falls below the active count before t (the worst then leave)."""

    phases: tuple
    n_active: np.ndarray
    starts: np.ndarray
    slots: np.ndarray
    drops: np.ndarray


@functools.lru_cache(maxsize=64)
def plan_of(schedule: tuple[int, ...], n_phases: int) -> Plan:
    """The :class:`Plan` of a run whose active population is ``schedule`` (one count per
    iteration), in at most ``n_phases`` phases."""
    sched = np.asarray(schedule)
    K = len(sched)
    parts = tuple(phases(sched, n_phases))
    starts, slots, drops = np.zeros(K, bool), np.zeros(K, int), np.zeros(K, bool)
    for a, b, s in parts:
        starts[a], slots[a:b] = True, s
        before = np.concatenate([[min(sched[max(a - 1, 0)], s)], sched[a:b - 1]])
        drops[a:b] = sched[a:b] < before
    return Plan(phases=parts, n_active=sched, starts=starts, slots=slots, drops=drops)


def phases(schedule: np.ndarray, n_phases: int) -> list[tuple[int, int, int]]:
    """Split iterations into at most ``n_phases`` runs of iterations with a static slot
    count each: the largest active count inside the phase (N(t) never grows)."""
    K = len(schedule)
    bounds = sorted({round(k * K / n_phases) for k in range(n_phases)} | {K})
    return [(a, b, int(schedule[a:b].max())) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def when(pred, fn, state):
    """``fn(state)`` where ``pred`` else ``state``: a ``lax.cond`` on the CPU, which
    skips ``fn`` when it is not needed; a select on accelerators, where a ``lax.cond``
    would read its predicate back to the host every iteration."""
    if jax.default_backend() == "cpu":
        return jax.lax.cond(pred, fn, lambda s: s, state)
    return jax.tree.map(lambda a, b: jnp.where(pred, a, b), fn(state), state)
