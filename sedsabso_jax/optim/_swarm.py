"""What every swarm shares: the solver contract for a population that moves with clamped
velocities, written once for all of them.

An iteration is one or more ROUNDS ``k = 0, 1, ...`` (:attr:`~AbstractSwarm.asks_per_iteration`;
round ``-1``, :data:`~._population.INITIAL`, is the initial population). A round proposes
points (:meth:`~AbstractSwarm.propose`, :meth:`~AbstractSwarm.points`), gets their
fitness (:meth:`~AbstractSwarm.evaluate`) and absorbs it (:meth:`~AbstractSwarm.absorb`).
The three ways to drive a swarm are views of these rounds:

- :meth:`~AbstractSwarm.step`: every round of one iteration, the fitness called by the
  solver;
- :meth:`~AbstractSwarm.ask` / :meth:`~AbstractSwarm.tell`: the same rounds with the
  fitness evaluated by the caller (:meth:`~AbstractSwarm.told` reads its values);
- :meth:`~AbstractSwarm.run`: :meth:`~AbstractSwarm.init`, then the iteration of ``step``
  in a ``lax.scan``, in phases of static slot counts (:mod:`._phases`): at a phase's start
  the slots are cut to the phase's population, so the work follows N(t). The run may make
  each phase's random draws before its loop (``predraw``, :func:`~._random.fits_before_loop`).

``step`` on a state of constant shape reorders the slots at the iterations where ``run``
cuts them and leaves the cut ones inactive; the random draws are indexed by slot
(:func:`~._random.uniforms`), so every way gives the same numbers up to rounding
(``tests/test_composition.py``).

A swarm is one module: a subclass with its hyperparameters as fields,
:meth:`~AbstractSwarm.vmax`, :meth:`~AbstractSwarm.evaluations`,
:meth:`~AbstractSwarm.propose` and :meth:`~AbstractSwarm.absorb`, its own state (a
subclass of :class:`~._population.SwarmState`, made by :meth:`~AbstractSwarm.own_state`)
where it keeps more than every swarm does, and :meth:`~AbstractSwarm.paper`, the paper's
settings, which puts it in :data:`~._registry.SWARMS` by its class name.
"""

from __future__ import annotations

import abc
from typing import Any, ClassVar, Generic

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float, Int, PRNGKeyArray

from ._fitness import Fitness
from ._phases import Plan, plan_of, when
from ._population import (
    INITIAL,
    S,
    SwarmState,
    initial_positions,
    reorder,
    replace,
    set_active,
    shrink,
    started,
)
from ._random import fits_before_loop, iteration_randomness, next_key, uniforms
from ._result import Result
from ._solver import AbstractSolver, Bounds

#: Swarms by name, in the order they register (:meth:`AbstractSwarm.__init_subclass__`):
#: the concrete ones that give ``paper()``.
REGISTERED: dict[str, type[AbstractSwarm]] = {}


class AbstractSwarm(AbstractSolver, Generic[S]):
    """A population moving with clamped velocities. A swarm gives its population size,
    :meth:`vmax`, :meth:`evaluations`, :meth:`propose` and :meth:`absorb`; and where it
    differs from a constant population of one round drawing ``r1, r2``:
    :meth:`schedule` and :attr:`n_phases`, :meth:`randomness` and :meth:`draw`,
    :meth:`own_state`, :meth:`points`, :meth:`evaluate` and :meth:`told`,
    :attr:`asks_per_iteration`."""

    population_size: eqx.AbstractVar[int]
    #: Where the swarm sits in :data:`~._registry.SWARMS` (lower first, then by name).
    registry_order: ClassVar[int] = 100

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "paper" in cls.__dict__:
            REGISTERED[cls.__name__] = cls

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
    def propose(self, k: int, state: S, draws: Any, lower: Bounds, upper: Bounds) -> S:
        """Round ``k``'s proposal, nothing evaluated: in round 0 every slot's new ``x``
        and ``v`` from the iteration's ``draws`` (what :meth:`draw` returns; None in a
        later round)."""

    @abc.abstractmethod
    def absorb(self, k: int, state: S, evaluation: Any) -> S:
        """Round ``k``'s absorption of its points' :meth:`evaluate` (or :meth:`told`):
        personal, global and best-ever updated. Round :data:`~._population.INITIAL`:
        the started population's (:func:`~._population.initial_bests`)."""

    # ------------------------------------------------- what a swarm may give otherwise
    @classmethod
    def paper(cls) -> AbstractSwarm:
        """The swarm with the paper's settings (Sec. 5.2); a swarm that gives it is named
        in :data:`~._registry.SWARMS`."""
        raise NotImplementedError(f"{cls.__name__} has no paper's settings")

    def schedule(self, iterations: int) -> np.ndarray:
        """Active population per iteration (static, never growing). Default: the whole
        population throughout."""
        return np.full(iterations, int(self.population_size))

    @property
    def n_phases(self) -> int:
        """Compiled phases of static slot count the iterations are split into."""
        return 1

    def randomness(self, key: PRNGKeyArray, dim: int, dtype: DTypeLike) -> Any:
        """What one iteration draws from, derived from the iteration's key: keys for the
        population's draws (their shape follows the phase) or small draws made up front.
        Default: two keys, for ``r1`` and ``r2`` of the velocity update."""
        return jax.random.split(key)

    def draw(self, randomness: Any, shape: tuple[int, ...], dtype: DTypeLike) -> Any:
        """One iteration's draws for a population of ``shape`` (slots, d), from what
        :meth:`randomness` returned: what :meth:`propose` takes. Default: ``(r1, r2)``,
        uniform, one per slot and dimension."""
        return uniforms(randomness, shape, dtype)

    def own_state(self, state: SwarmState) -> S:
        """The swarm's state of a started population: ``state`` with the swarm's own
        fields added (:func:`~._population.extend`). Default: ``state``."""
        return state  # type: ignore[return-value]

    def points(self, k: int, state: S) -> Float[Array, "m d"]:
        """The points round ``k`` asks for, once proposed. Default: the positions."""
        return state.x

    def evaluate(self, k: int, fitness: Fitness, state: S) -> Any:
        """Round ``k``'s points evaluated with ``fitness``: what :meth:`absorb` takes.
        Default: their raw fitness."""
        return fitness.evaluate(self.points(k, state))

    def told(self, k: int, state: S, values: Float[Array, " m"]) -> Any:
        """What :meth:`evaluate` would give, from the raw fitness of :meth:`points`.
        Default: ``values``."""
        return values

    # ------------------------------------------------------------------- contract
    @property
    def label(self) -> str:
        return type(self).__name__

    def population(self, dim: int) -> int:
        return int(self.population_size)

    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        return int(self.population_size) + np.cumsum(
            self.evaluations(self.schedule(int(iterations))))

    def population_schedule(self, iterations: int, dim: int) -> np.ndarray:
        return self.schedule(int(iterations))

    def n_nonfinite(self, state: S) -> Int[Array, ""]:
        return state.nonfinite_total

    def best(self, state: S) -> tuple[Float[Array, " d"], Float[Array, ""]]:
        return state.best_x, state.best_f

    def plan(self, iterations: int) -> Plan:
        """The static phase plan of a run of ``iterations`` (:class:`~._phases.Plan`)."""
        return plan_of(tuple(int(n) for n in self.schedule(int(iterations))),
                       int(self.n_phases))

    def start(self, lower: Bounds, upper: Bounds, key: PRNGKeyArray, iterations: int) -> S:
        """Positions uniform in the box, velocities uniform in ``+-Vmax``, not evaluated:
        the first :meth:`ask` asks for their :meth:`points`."""
        key, k0 = jax.random.split(key)
        x, v = initial_positions(lower, upper, k0, int(self.population_size),
                                 self.vmax(lower, upper))
        return self.own_state(started(x, v, key, iterations))

    def init(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
             iterations: int) -> S:
        """:meth:`start`, evaluated, the worst beyond N(0) inactive."""
        state = self.start(lower, upper, key, iterations)
        return self._initial(state, self.evaluate(INITIAL, fitness, state))

    def step(self, fitness: Fitness, state: S, lower: Bounds, upper: Bounds) -> S:
        """One iteration, its draws from the state's key: the slots' reordering or
        re-ranking where N(t) changes (:meth:`prepare`), then :meth:`update`."""
        state, draws = self._next_draws(state)
        return self.update(fitness, self.prepare(state), draws, lower, upper)

    def update(self, fitness: Fitness, state: S, draws: Any, lower: Bounds, upper: Bounds
               ) -> S:
        """Iteration ``state.t``'s rounds with the given draws (what :meth:`draw`
        returns; the state's key is not touched): each round proposed, evaluated with
        ``fitness`` and absorbed; ``t`` advanced."""
        for k in range(self.asks_per_iteration):
            state = self.propose(k, state, draws if k == 0 else None, lower, upper)
            state = self.absorb(k, state, self.evaluate(k, fitness, state))
        return replace(state, t=state.t + 1)

    def prepare(self, state: S) -> S:
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

    def ask(self, state: S, lower: Bounds, upper: Bounds) -> tuple[Float[Array, "k d"], S]:
        """The :meth:`points` of the next round (:attr:`~._population.SwarmState.round`):
        the initial population after :meth:`start`, then each round's, proposed."""
        if state.asked:
            raise ValueError(f"{self.label}.ask: the state waits for tell (round "
                             f"{state.round}); call tell with the last points' fitness")
        k = state.round
        if k == 0:
            state, draws = self._next_draws(self.prepare(state))
            state = self.propose(0, state, draws, lower, upper)
        elif k > 0:
            state = self.propose(k, state, None, lower, upper)
        return self.points(k, state), replace(state, asked=True)

    def tell(self, state: S, fitness_values: Float[ArrayLike, " k"], lower: Bounds,
             upper: Bounds) -> S:
        """The state after the fitness of the points the last :meth:`ask` gave."""
        if not state.asked:
            raise ValueError(f"{self.label}.tell: no points were asked for (round "
                             f"{state.round}); call ask first")
        k = state.round
        values = jnp.asarray(fitness_values, state.x.dtype).reshape(-1)
        want = self.points(k, state).shape[0]
        if values.shape[0] != want:
            raise ValueError(f"{self.label}.tell: expected {want} fitness values (one per "
                             f"point asked), got {values.shape[0]}")
        evaluation = self.told(k, state, values)
        if k == INITIAL:
            return self._initial(state, evaluation)
        state = self.absorb(k, state, evaluation)
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

            def body(state: S, r: Any, drawn: bool = drawn,
                     shape: tuple[int, int] = shape) -> tuple[S, Float[Array, ""]]:
                draws = r if drawn else self.draw(r, shape, dtype)
                state = self.update(fitness, self.prepare(state), draws, lower, upper)
                return state, state.best_f

            state, fh = jax.lax.scan(body, state, phase)
            history.append(fh)
        return self.result(state, jnp.concatenate(history), dim)

    # ------------------------------------------------------------------- internals
    def _next_draws(self, state: S) -> tuple[S, Any]:
        key, sub = next_key(state.key)
        dim, dtype = state.x.shape[-1], state.x.dtype
        draws = self.draw(self.randomness(sub, dim, dtype), state.x.shape, dtype)
        return replace(state, key=key), draws

    def _initial(self, state: S, evaluation: Any) -> S:
        """The started population with its evaluation: bests, and the worst beyond N(0)
        inactive."""
        state = self.absorb(INITIAL, state, evaluation)
        return set_active(state, int(self.schedule(state.iterations)[0]))
