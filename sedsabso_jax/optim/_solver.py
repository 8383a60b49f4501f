"""The one contract every optimiser here implements: the paper's swarms and any evosax
strategy alike, so that nothing downstream (the driver, the budget code, ``compare``)
asks which kind a solver is.

A solver is an immutable ``equinox.Module`` whose fields are its hyperparameters, checked
when it is built (``__check_init__``). Everything it does is a pure function of a state
pytree, so it composes under ``jax.jit`` and ``jax.vmap``:

- :meth:`~AbstractSolver.init` (the initial population, evaluated) and
  :meth:`~AbstractSolver.step` (one iteration) for a loop that calls the fitness itself;
- :meth:`~AbstractSolver.start`, :meth:`~AbstractSolver.ask` and
  :meth:`~AbstractSolver.tell` for a user who owns the loop and evaluates the points
  (evosax's interface);
- :meth:`~AbstractSolver.best` (the best point evaluated so far and its fitness),
  :meth:`~AbstractSolver.n_evaluations`, :attr:`~AbstractSolver.label`;
- :meth:`~AbstractSolver.run`: a whole run as a :class:`~._result.Result`, what
  :func:`~sedsabso_jax.minimise` calls for each key: ``init``, then ``step`` in a
  ``lax.scan`` (the swarms cut their arrays to the population of each phase of the
  run, ``_swarm.py``).

``step`` is the rounds of ``ask``, evaluate, ``tell`` that make an iteration: a loop
written with ``init`` and ``step``, or with ``start``, ``ask`` and ``tell``, gives the
numbers :func:`~sedsabso_jax.minimise` gives, up to floating-point rounding
(``tests/test_composition.py``).
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int, PRNGKeyArray

from ._fitness import Fitness
from ._result import Result

#: A solver's state: a pytree of arrays, whatever the solver needs.
State = Any
Bounds = Float[Array, " d"]


class AbstractSolver(eqx.Module):
    """What :func:`~sedsabso_jax.minimise` runs. Subclasses implement :meth:`start`,
    :meth:`ask`, :meth:`tell`, :meth:`best`, :meth:`evaluation_counts`,
    :meth:`population` and :attr:`label`; :meth:`init`, :meth:`step` and :meth:`run`
    are built from them and may be overridden by faster equivalents.

    ``fitness`` arguments are fitness objects (:class:`~._fitness.BlackBox` or
    :class:`~._fitness.L1Residual`; :func:`~._fitness.as_fitness` makes one from a
    callable); ``lower, upper`` the box, 1-D arrays of one length and dtype, which also
    fix the dtype of the run."""

    @property
    @abc.abstractmethod
    def label(self) -> str:
        """The solver's name in results and reports (e.g. ``"SEDSABSO"``,
        ``"evosax CMA_ES"``)."""

    @abc.abstractmethod
    def population(self, dim: int) -> int:
        """The largest number of candidates the solver holds at once in dimension
        ``dim`` (what one iteration's memory scales with)."""

    @abc.abstractmethod
    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        """Cumulative fitness evaluations after each of ``iterations`` iterations in
        dimension ``dim``, the initial population included: what
        :meth:`n_evaluations` reads after each :meth:`step` (static, NumPy)."""

    def population_schedule(self, iterations: int, dim: int) -> np.ndarray:
        """The active population of each iteration (static, NumPy): what
        :attr:`~._result.Result.history_n` records. Default: :meth:`population` throughout."""
        return np.full(int(iterations), self.population(dim))

    @abc.abstractmethod
    def start(self, lower: Bounds, upper: Bounds, key: PRNGKeyArray, iterations: int) -> State:
        """A run of ``iterations`` iterations in the box, before anything is evaluated: the
        first :meth:`ask` asks for the initial population (if the solver has one)."""

    @abc.abstractmethod
    def ask(self, state: State, lower: Bounds, upper: Bounds
            ) -> tuple[Float[Array, "k d"], State]:
        """``(points, state)``: the points whose fitness the next :meth:`tell` needs, in the
        box. How many, and how many ask/tell rounds make an iteration, is the solver's
        (:attr:`asks_per_iteration`)."""

    @abc.abstractmethod
    def tell(self, state: State, fitness_values: Float[Array, " k"], lower: Bounds,
             upper: Bounds) -> State:
        """The state after learning the fitness of the points the last :meth:`ask` gave
        (raw values: NaN and Inf are counted and never become a best)."""

    @abc.abstractmethod
    def best(self, state: State) -> tuple[Float[Array, " d"], Float[Array, ""]]:
        """``(x, f)``: the best point evaluated so far and its fitness."""

    def n_evaluations(self, state: State) -> Int[Array, ""]:
        """Fitness evaluations so far (a population member counts once)."""
        return state.n_evaluations

    def n_nonfinite(self, state: State) -> Int[Array, ""]:
        """Evaluations so far that returned NaN or Inf."""
        return state.n_nonfinite

    @property
    def asks_per_iteration(self) -> int:
        """Ask/tell rounds per iteration (the first ask after :meth:`start` asks for the
        initial population and is not counted). Default 1."""
        return 1

    def hyperparameters(self) -> dict[str, Any]:
        """The solver's settings by name, those of settings objects it holds (a swarm's
        :class:`~._bso.BeetleStep`) first: what reports write."""
        return _settings_of(self)

    def init(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
             iterations: int) -> State:
        """The state after the initial population is evaluated with ``fitness``: ready
        for the first :meth:`step`."""
        state = self.start(lower, upper, key, iterations)
        if self.initial_asks:
            points, state = self.ask(state, lower, upper)
            state = self.tell(state, fitness.evaluate(points), lower, upper)
        return state

    @property
    def initial_asks(self) -> int:
        """Ask/tell rounds before the first iteration (1: the initial population; 0 for a
        strategy that starts from a distribution). Default 1."""
        return 1

    def step(self, fitness: Fitness, state: State, lower: Bounds, upper: Bounds) -> State:
        """One iteration: :attr:`asks_per_iteration` rounds of ask, evaluate, tell."""
        for _ in range(self.asks_per_iteration):
            points, state = self.ask(state, lower, upper)
            state = self.tell(state, fitness.evaluate(points), lower, upper)
        return state

    def run(self, fitness: Fitness, lower: Bounds, upper: Bounds, key: PRNGKeyArray,
            iterations: int, *, predraw: bool = False) -> Result:
        """One whole run (pure): :meth:`init`, then ``iterations`` :meth:`step` in a
        ``lax.scan``; the best fitness is recorded after each. ``predraw``: the caller
        (the driver, for a run compiled on its own on the CPU) lets the solver make its
        random draws before its loops, the same numbers (the swarms do). Timings are
        ``None``: :func:`~sedsabso_jax.minimise` measures them outside any trace."""
        iterations = int(iterations)

        def body(state: State, _: None) -> tuple[State, Float[Array, ""]]:
            state = self.step(fitness, state, lower, upper)
            return state, self.best(state)[1]

        state = self.init(fitness, lower, upper, key, iterations)
        state, history_f = jax.lax.scan(body, state, None, length=iterations)
        return self.result(state, history_f, lower.shape[0])

    def result(self, state: State, history_f: Float[Array, " iterations"], dim: int
               ) -> Result:
        """The run's :class:`~._result.Result` from its final state and history."""
        x, f = self.best(state)
        iterations = history_f.shape[-1]
        return Result(method=self.label, x=x, f=f, history_f=history_f,
                      history_n=jnp.asarray(self.population_schedule(iterations, dim),
                                            jnp.int32),
                      sa_accepted=jnp.int32(0),
                      n_evaluations=self.n_evaluations(state),
                      n_nonfinite=self.n_nonfinite(state))


def _settings_of(module: eqx.Module) -> dict[str, Any]:
    nested: dict[str, Any] = {}
    own: dict[str, Any] = {}
    for field in dataclasses.fields(module):
        value = getattr(module, field.name)
        if isinstance(value, eqx.Module):
            nested.update(_settings_of(value))
        else:
            own[field.name] = value
    return {**nested, **own}
