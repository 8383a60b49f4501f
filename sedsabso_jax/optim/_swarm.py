"""What every swarm shares: the solver contract for a population that moves with clamped
velocities, written once for all of them.

An iteration is one or more ROUNDS. A round proposes points, gets their fitness and
absorbs it: round 0 moves the population (:meth:`~AbstractSwarm.move`) and takes in its
fitness (:meth:`~AbstractSwarm.absorb`; for beetles with their antennae); SEDSABSO adds a
round of annealing candidates (:meth:`~AbstractSwarm.propose_later`,
:meth:`~AbstractSwarm.absorb_later`). The three ways to drive a swarm are views of these
rounds:

- :meth:`~AbstractSwarm.step`: every round of one iteration, the fitness called by the
  solver (a beetle's position and its two antennae in one pass over Eq. 17's residuals,
  :meth:`~sedsabso_jax.L1Residual.evaluate_with_antennae`);
- :meth:`~AbstractSwarm.ask` / :meth:`~AbstractSwarm.tell`: the same rounds with the
  fitness evaluated by the caller: ``ask`` is a round's proposal, ``tell`` its absorption;
- :meth:`~AbstractSwarm.run`: :meth:`~AbstractSwarm.init`, then the iteration of ``step``
  in a ``lax.scan``, in phases of static slot counts (:mod:`._phases`): at a phase's start
  the slots are cut to the phase's population, so the work follows N(t). The run may make
  each phase's random draws before its loop (``predraw``), which the driver asks for on
  the CPU: the same numbers, faster there (:func:`~._random.fits_before_loop`).

``step`` on a state of constant shape reorders the slots at the iterations where ``run``
cuts them and leaves the cut ones inactive; the random draws are indexed by slot
(:func:`~._random.uniforms`), so every way gives the same numbers up to rounding
(``tests/test_composition.py``).
"""

from __future__ import annotations

import abc
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float, Int, PRNGKeyArray

from ._fitness import Fitness
from ._phases import Plan, plan_of, when
from ._population import (
    SwarmState,
    antenna_difference,
    initial_from,
    initial_positions,
    reorder,
    replace,
    set_active,
    shrink,
)
from ._random import fits_before_loop, iteration_randomness, next_key, uniforms
from ._result import Result
from ._solver import AbstractSolver, Bounds

#: Round numbers of :class:`~._population.SwarmState`: the initial population.
INITIAL = -1


class AbstractSwarm(AbstractSolver):
    """A population moving with clamped velocities. A swarm gives its population size,
    :meth:`vmax`, :meth:`evaluations`, round 0's :meth:`move` and :meth:`absorb`, and
    where it differs from a constant population of one round: :meth:`schedule`,
    :attr:`n_phases`, :attr:`antenna`, its randomness, later rounds."""

    population_size: eqx.AbstractVar[int]

    # ----------------------------------------------------------- what a swarm gives
    @abc.abstractmethod
    def vmax(self, lower: Bounds, upper: Bounds) -> Float[Array, " d"]:
        """The velocity clamp per dimension."""

    @abc.abstractmethod
    def evaluations(self, n_active: int | Int[np.ndarray, " t"]
                    ) -> int | Int[np.ndarray, " t"]:
        """Fitness evaluations one iteration makes with ``n_active`` members (a member's
        position counts once)."""

    @abc.abstractmethod
    def move(self, state: SwarmState, draws: Any, lower: Bounds, upper: Bounds
             ) -> SwarmState:
        """Round 0's proposal: the state with every slot's new positions and velocities
        (``x``, ``v``; nothing evaluated), from the iteration's ``draws``."""

    @abc.abstractmethod
    def absorb(self, state: SwarmState, raw: Float[Array, " slots"],
               diff: Float[Array, " slots"] | None, diff_bad: Int[Array, " slots"] | None
               ) -> SwarmState:
        """Round 0's absorption: the state after its new positions were evaluated (raw
        fitness ``raw``; for beetles the antenna difference and its non-finite count);
        personal, global and best-ever updated."""

    # ------------------------------------------------- what a swarm may give otherwise
    @property
    def label(self) -> str:
        return type(self).__name__

    def population(self, dim: int) -> int:
        return int(self.population_size)

    def schedule(self, iterations: int) -> np.ndarray:
        """Active population per iteration (static, never growing). Default: the whole
        population throughout."""
        return np.full(iterations, int(self.population_size))

    @property
    def n_phases(self) -> int:
        """Compiled phases of static slot count the iterations are split into."""
        return 1

    @property
    def antenna(self) -> float | None:
        """``a`` of the beetles' antennae at ``x +- a v`` (Eq. 13); None: no antennae."""
        return None

    @property
    def initial_temperature(self) -> float:
        return 0.0

    def initial_pending(self, dim: int, dtype: DTypeLike) -> Any:
        """What later rounds keep between their proposal and absorption (zeros of a
        fixed structure); None without later rounds."""
        return None

    def randomness(self, key: PRNGKeyArray, dim: int, dtype: DTypeLike) -> Any:
        """What one iteration draws from, derived from the iteration's key: keys for the
        population's draws (their shape follows the phase) or small draws made up front.
        Default: two keys, for ``r1`` and ``r2`` of the velocity update."""
        return jax.random.split(key)

    def draw(self, randomness: Any, shape: tuple[int, ...], dtype: DTypeLike) -> Any:
        """One iteration's draws for a population of ``shape`` (slots, d), from what
        :meth:`randomness` returned: what :meth:`move` takes. Default: ``(r1, r2)``,
        uniform, one per slot and dimension."""
        return uniforms(randomness, shape, dtype)

    def propose_later(self, k: int, state: SwarmState, lower: Bounds, upper: Bounds
                      ) -> SwarmState:
        """Round ``k >= 1``'s proposal (the points go to :meth:`later_points`)."""
        raise ValueError(f"{self.label} has one round per iteration, not {k + 1}")

    def later_points(self, k: int, state: SwarmState) -> Float[Array, "m d"]:
        """The points round ``k >= 1`` asks for, once proposed."""
        raise ValueError(f"{self.label} has one round per iteration, not {k + 1}")

    def absorb_later(self, k: int, state: SwarmState, raw: Float[Array, " m"]
                     ) -> SwarmState:
        """Round ``k >= 1``'s absorption of its points' raw fitness."""
        raise ValueError(f"{self.label} has one round per iteration, not {k + 1}")

    # ------------------------------------------------------------------- contract
    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        return int(self.population_size) + np.cumsum(
            self.evaluations(self.schedule(int(iterations))))

    def population_schedule(self, iterations: int, dim: int) -> np.ndarray:
        return self.schedule(int(iterations))

    def sa_accepted(self, state: SwarmState) -> Int[Array, ""]:
        return state.sa_accepted

    def n_nonfinite(self, state: SwarmState) -> Int[Array, ""]:
        return state.nonfinite_total

    def best(self, state: SwarmState) -> tuple[Float[Array, " d"], Float[Array, ""]]:
        return state.best_x, state.best_f

    def plan(self, iterations: int) -> Plan:
        """The static phase plan of a run of ``iterations`` (:class:`~._phases.Plan`)."""
        return plan_of(tuple(int(n) for n in self.schedule(int(iterations))),
                       int(self.n_phases))

    def start(self, lower: Bounds, upper: Bounds, key: PRNGKeyArray, iterations: int
              ) -> SwarmState:
        """Positions uniform in the box, velocities uniform in ``+-Vmax``, not evaluated:
        the first :meth:`ask` asks for them (and the beetles' antennae)."""
        key, k0 = jax.random.split(key)
        x, v = initial_positions(lower, upper, k0, int(self.population_size),
                                 self.vmax(lower, upper))
        state = initial_from(x, v, jnp.zeros(x.shape[0], x.dtype), None, None,
                             self.initial_temperature)
        return replace(state, key=key, iterations=int(iterations), round=INITIAL,
                       pending=self.initial_pending(x.shape[1], x.dtype))

    def init(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
             iterations: int) -> SwarmState:
        """:meth:`start`, evaluated (with the beetles' antennae), the worst beyond N(0)
        inactive."""
        state = self.start(lower, upper, key, iterations)
        return self._initial(state, *self._evaluate_moved(fitness, state))

    def step(self, fitness: Fitness, state: SwarmState, lower: Bounds, upper: Bounds
             ) -> SwarmState:
        """One iteration, its draws from the state's key: the slots' reordering or
        re-ranking where N(t) changes (:meth:`prepare`), then :meth:`update`."""
        state, draws = self._next_draws(state)
        return self.update(fitness, self.prepare(state), draws, lower, upper)

    def update(self, fitness: Fitness, state: SwarmState, draws: Any, lower: Bounds,
               upper: Bounds) -> SwarmState:
        """Iteration ``state.t``'s rounds with the given draws (what :meth:`draw`
        returns; the state's key is not touched): each round proposed, evaluated with
        ``fitness`` and absorbed; ``t`` advanced."""
        for k in range(self.asks_per_iteration):
            state = self._propose(k, state, draws, lower, upper)
            if k == 0:
                state = self.absorb(state, *self._evaluate_moved(fitness, state))
            else:
                state = self.absorb_later(k, state, fitness.evaluate(self.later_points(k,
                                                                                      state)))
        return replace(state, t=state.t + 1)

    def prepare(self, state: SwarmState) -> SwarmState:
        """Before iteration ``state.t``: at a phase's start the slots reordered best first
        and those beyond the phase's count made inactive (a no-op on a state :meth:`run`
        has cut to the phase), and where N(t) falls the worst leave."""
        plan = self.plan(state.iterations)
        t = state.t
        state = when(jnp.asarray(plan.starts)[t],
                     lambda s: reorder(s, jnp.asarray(plan.slots)[t]), state)
        if plan.drops.any():
            state = when(jnp.asarray(plan.drops)[t],
                         lambda s: set_active(s, jnp.asarray(plan.n_active, jnp.int32)[t]),
                         state)
        return state

    def ask(self, state: SwarmState, lower: Bounds, upper: Bounds
            ) -> tuple[Float[Array, "k d"], SwarmState]:
        """The points of the next round (:attr:`~._population.SwarmState.round`): the
        initial population after :meth:`start`, the moved population (and the beetles'
        antennae ``x + a v``, ``x - a v``) in round 0, a later round's points."""
        if state.asked:
            raise ValueError(f"{self.label}.ask: the state waits for tell (round "
                             f"{state.round}); call tell with the last points' fitness")
        k = state.round
        if k == 0:
            state, draws = self._next_draws(self.prepare(state))
            state = self._propose(0, state, draws, lower, upper)
        elif k > 0:
            state = self._propose(k, state, None, lower, upper)
        return self._points(k, state), replace(state, asked=True)

    def tell(self, state: SwarmState, fitness_values: Float[ArrayLike, " k"], lower: Bounds,
             upper: Bounds) -> SwarmState:
        """The state after the fitness of the points the last :meth:`ask` gave."""
        if not state.asked:
            raise ValueError(f"{self.label}.tell: no points were asked for (round "
                             f"{state.round}); call ask first")
        k = state.round
        values = jnp.asarray(fitness_values, state.x.dtype).reshape(-1)
        want = self._points(k, state).shape[0]
        if values.shape[0] != want:
            raise ValueError(f"{self.label}.tell: expected {want} fitness values (one per "
                             f"point asked), got {values.shape[0]}")
        if k > 0:
            state = self.absorb_later(k, state, values)
        else:
            n = state.x.shape[0]
            evaluation: tuple[Array, Array | None, Array | None] = (values, None, None)
            if self.antenna is not None:
                evaluation = (values[:n], *antenna_difference(values[n:2 * n],
                                                              values[2 * n:]))
            if k == INITIAL:
                return self._initial(state, *evaluation)
            state = self.absorb(state, *evaluation)
        if k + 1 < self.asks_per_iteration:
            return replace(state, round=k + 1, asked=False)
        return replace(state, t=state.t + 1, round=0, asked=False)

    def run(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
            iterations: int, *, predraw: bool = False) -> Result:
        """:meth:`init`, then :meth:`step`'s iteration in a ``lax.scan`` per phase of static slot
        count (module docstring), each iteration's randomness from the key chain of
        :meth:`step`. With ``predraw`` a phase's population draws are made before its
        loop where they fit :data:`~._random.BEFORE_LOOP_BYTES`. The history of N is
        the schedule itself: where N(t) falls is static."""
        K = int(iterations)
        plan = self.plan(K)
        state = self.init(fitness, lower, upper, key, K)
        dim, dtype = lower.shape[0], lower.dtype
        rand = iteration_randomness(self, state.key, K, dim, dtype)
        history = []
        for a, b, slots in plan.phases:
            state = shrink(state, slots)
            shape = (slots, dim)
            phase = jax.tree.map(lambda r, a=a, b=b: r[a:b], rand)
            drawn = predraw and fits_before_loop(self, phase, shape, dtype, b - a)
            if drawn:
                phase = jax.vmap(lambda r, shape=shape: self.draw(r, shape, dtype))(phase)

            def body(state: SwarmState, r: Any, drawn: bool = drawn,
                     shape: tuple[int, int] = shape) -> tuple[SwarmState, Float[Array, ""]]:
                draws = r if drawn else self.draw(r, shape, dtype)
                state = self.update(fitness, self.prepare(state), draws, lower, upper)
                return state, state.best_f

            state, fh = jax.lax.scan(body, state, phase)
            history.append(fh)
        return self.result(state, jnp.concatenate(history), dim)

    # ------------------------------------------------------------------- the rounds
    def _next_draws(self, state: SwarmState) -> tuple[SwarmState, Any]:
        key, sub = next_key(state.key)
        dim, dtype = state.x.shape[-1], state.x.dtype
        draws = self.draw(self.randomness(sub, dim, dtype), state.x.shape, dtype)
        return replace(state, key=key), draws

    def _propose(self, k: int, state: SwarmState, draws: Any, lower: Bounds, upper: Bounds
                 ) -> SwarmState:
        if k == 0:
            return self.move(state, draws, lower, upper)
        return self.propose_later(k, state, lower, upper)

    def _points(self, k: int, state: SwarmState) -> Float[Array, "m d"]:
        """Round ``k``'s points: the population (with the beetles' antennae) for the
        initial round and round 0, a later round's own."""
        if k > 0:
            return self.later_points(k, state)
        a = self.antenna
        x, v = state.x, state.v
        return x if a is None else jnp.concatenate([x, x + a * v, x - a * v])

    def _evaluate_moved(self, fitness: Fitness, state: SwarmState
                        ) -> tuple[Float[Array, " slots"], Float[Array, " slots"] | None,
                                   Int[Array, " slots"] | None]:
        """``(raw, diff, diff_bad)`` of the population's positions, from the fitness
        object (for beetles with the antennae, in one pass for Eq. 17)."""
        a = self.antenna
        if a is None:
            return fitness.evaluate(state.x), None, None
        return fitness.evaluate_with_antennae(state.x, state.v, a)

    def _initial(self, state: SwarmState, raw: Float[Array, " slots"],
                 diff: Float[Array, " slots"] | None, diff_bad: Int[Array, " slots"] | None
                 ) -> SwarmState:
        """The started population with its fitness: bests, and the worst beyond N(0)
        inactive."""
        s = initial_from(state.x, state.v, raw, diff, diff_bad, self.initial_temperature)
        s = set_active(s, int(self.schedule(state.iterations)[0]))
        return replace(s, key=state.key, iterations=state.iterations, pending=state.pending)
