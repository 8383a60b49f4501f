"""Any evosax strategy through :func:`~sedsabso_jax.minimise`: the same fitness objects,
box, keys, many runs per call and :class:`~._result.Result` as the swarms, so a comparison
differs only in the algorithm.

evosax (``pip install "sedsabso-jax[compare]"``) is imported only when an
:class:`Evosax` solver runs; nothing else in the package needs it.

Box handling. evosax searches an unbounded space; the adapter runs every strategy on the
unit cube ``u in [0, 1]^d`` mapped affinely onto the box, ``x = lower + (upper - lower) u``
(so one initial step size suits boxes whose sides differ by orders of magnitude, as the
identification boxes do). A candidate outside the cube is clipped to it before it is
evaluated, and the strategy is told the clipped point with its fitness (repair by
projection, as for the particle swarms, whose positions are clipped to the box).
Population-based strategies (PSO, DE, GA) start from a population drawn uniformly in the
box, which costs one population of evaluations; distribution-based ones (CMA-ES, NES, ES)
start from a mean drawn uniformly in the box with ``std_init`` (a fraction of each side).
A NaN or Inf fitness is told as +Inf and counted, as in the swarms.

:class:`Evosax` implements the solver contract (:class:`~._solver.AbstractSolver`): one
iteration is one generation, one ask/tell round; ``init`` of a population-based
strategy asks for its initial population first.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int, PRNGKeyArray

from ._checks import check_population
from ._fitness import finite_or_inf
from ._solver import AbstractSolver, Bounds

#: Strategies whose default population is CMA-ES's ``4 + floor(3 ln d)`` (Hansen's rule)
#: rather than the swarms' 50.
_LOG_POPULATION = ("CMA_ES", "Sep_CMA_ES", "MA_ES", "LM_MA_ES", "Rm_ES", "xNES", "SNES",
                   "CR_FM_NES")


def _evosax_algorithms() -> dict:
    try:
        from evosax.algorithms import algorithms
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError("evosax strategies need evosax: pip install 'sedsabso-jax[compare]'"
                          ) from err
    return algorithms


def evosax_names() -> tuple[str, ...]:
    """The strategies evosax offers (``evosax.algorithms.algorithms``)."""
    return tuple(sorted(_evosax_algorithms()))


class EvosaxState(eqx.Module):
    """A run of an evosax strategy: the strategy's own state, the best point evaluated
    (in the box and in the unit cube the strategy sees), counts, and every generation's
    key (split up front, as evosax's examples do). ``pending`` holds the points of the
    last ``ask`` (in the unit cube); ``round`` and ``asked`` where a loop of ``ask`` and
    ``tell`` stands: -1 before a population-based strategy's initial population is told,
    then 0; whether points were asked and wait for ``tell``."""

    strategy: Any
    best_u: Float[Array, " d"]
    best_x: Float[Array, " d"]
    best_f: Float[Array, ""]
    n_evaluations: Int[Array, ""]
    n_nonfinite: Int[Array, ""]
    keys: Any  # (iterations,) generation keys
    t: Int[Array, ""]
    k_init: Any
    pending: Float[Array, "population d"]
    round: int = eqx.field(static=True, default=0)
    asked: bool = eqx.field(static=True, default=False)


class Evosax(AbstractSolver):
    """An evosax strategy by name, e.g. ``Evosax("CMA_ES")`` or
    ``Evosax("PSO", population_size=50, params={"inertia_coeff": 0.8})``.

    Attributes:
        name: a key of ``evosax.algorithms.algorithms`` (:func:`evosax_names`).
        population_size: candidates per generation; None: ``4 + floor(3 ln d)`` for CMA-ES
            and the natural-evolution strategies, 50 (the swarms' size) otherwise.
        std_init: initial step size of distribution-based strategies as a fraction of each
            side of the box (0.25: about a quarter of the box, the usual CMA-ES advice).
        params: overrides of the strategy's ``default_params`` (name -> number).
    """

    name: str = eqx.field(static=True)
    population_size: int | None = eqx.field(static=True, default=None)
    std_init: float = eqx.field(static=True, default=0.25)
    params: tuple = eqx.field(static=True, default=())

    def __init__(self, name: str, population_size: int | None = None, std_init: float = 0.25,
                 params: dict | None = None):
        self.name = name
        self.population_size = population_size
        self.std_init = std_init
        self.params = tuple(sorted((params or {}).items()))

    def __check_init__(self) -> None:
        algorithms = _evosax_algorithms()
        if self.name not in algorithms:
            raise ValueError(f"unknown evosax strategy {self.name!r}; expected one of "
                             f"{', '.join(sorted(algorithms))}")
        if self.population_size is not None:
            check_population(self.population_size, "population_size")
        if not self.std_init > 0:
            raise ValueError(f"std_init must be > 0, got {self.std_init}")
        self._strategy(2, jnp.float32)  # unknown strategy parameters fail here

    @property
    def label(self) -> str:
        return f"evosax {self.name}"

    def population(self, dim: int) -> int:
        """Candidates per generation in dimension ``dim``."""
        if self.population_size is not None:
            return int(self.population_size)
        if self.name in _LOG_POPULATION:
            return 4 + int(math.floor(3 * math.log(dim)))
        return 50

    def _strategy(self, dim: int, dtype):
        cls = _evosax_algorithms()[self.name]
        strategy = cls(population_size=self.population(dim), solution=jnp.zeros(dim, dtype))
        params = strategy.default_params
        known = set(getattr(params, "__dataclass_fields__", ()))
        unknown = [k for k, _ in self.params if k not in known]
        if unknown:
            raise ValueError(f"{self.name} has no parameter(s) {unknown}; its parameters: "
                             f"{sorted(known)}")
        overrides = dict(self.params)
        if "std_init" in known and "std_init" not in overrides:
            overrides["std_init"] = self.std_init
        if overrides:
            params = params.replace(**overrides)
        return strategy, params

    @property
    def distribution_based(self) -> bool:
        from evosax.algorithms.distribution_based.base import DistributionBasedAlgorithm
        return issubclass(_evosax_algorithms()[self.name], DistributionBasedAlgorithm)

    @property
    def initial_asks(self) -> int:
        return 0 if self.distribution_based else 1

    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        """Cumulative fitness evaluations after each generation (the initial population
        of a population-based strategy counts before the first)."""
        lam = self.population(dim)
        start = 0 if self.distribution_based else lam
        return start + lam * np.arange(1, iterations + 1)

    @staticmethod
    def _cast(tree, dtype):
        """evosax builds float64 state under x64: the carry stays in the run's dtype."""
        return jax.tree.map(lambda a: a.astype(dtype) if jnp.issubdtype(
            jnp.result_type(a), jnp.floating) else a, tree)

    def start(self, lower: Bounds, upper: Bounds, key: PRNGKeyArray, iterations: int
              ) -> EvosaxState:
        """Distribution-based: the strategy's mean drawn uniformly in the box (nothing to
        evaluate). Population-based: the initial population drawn, to be asked for."""
        dim, dtype = lower.shape[0], lower.dtype
        strategy, params = self._strategy(dim, dtype)
        k_init, k_pop, k_loop = jax.random.split(key, 3)
        keys = jax.random.split(k_loop, int(iterations))
        common = dict(best_f=jnp.asarray(jnp.inf, dtype), n_nonfinite=jnp.int32(0),
                      keys=keys, t=jnp.int32(0), k_init=k_init, n_evaluations=jnp.int32(0))
        if self.distribution_based:
            mean = jax.random.uniform(k_pop, (dim,), dtype)
            return EvosaxState(strategy=self._cast(strategy.init(k_init, mean, params), dtype),
                               best_u=mean, best_x=lower + (upper - lower) * mean,
                               pending=jnp.zeros((self.population(dim), dim), dtype), **common)
        u0 = jax.random.uniform(k_pop, (self.population(dim), dim), dtype)
        return EvosaxState(strategy=None, best_u=u0[0], best_x=lower + (upper - lower) * u0[0],
                           pending=u0, round=-1, **common)

    def ask(self, state: EvosaxState, lower: Bounds, upper: Bounds
            ) -> tuple[Float[Array, "k d"], EvosaxState]:
        if state.asked:
            raise ValueError(f"{self.label}.ask: the state waits for tell (round "
                             f"{state.round}); call tell with the last points' fitness")
        if state.round < 0:  # the initial population, drawn by start
            return lower + (upper - lower) * state.pending, dataclasses.replace(
                state, asked=True)
        strategy, params = self._strategy(lower.shape[0], lower.dtype)
        k_ask, _ = jax.random.split(state.keys[state.t])
        u, s = strategy.ask(k_ask, state.strategy, params)
        u = jnp.clip(u, 0.0, 1.0)  # the clipped point is evaluated and told
        return lower + (upper - lower) * u, dataclasses.replace(
            state, strategy=s, asked=True, pending=u.astype(state.pending.dtype))

    def tell(self, state: EvosaxState, fitness_values: Float[ArrayLike, " k"], lower: Bounds,
             upper: Bounds) -> EvosaxState:
        dim, dtype = lower.shape[0], lower.dtype
        u = state.pending
        if not state.asked:
            raise ValueError(f"{self.label}.tell: no points were asked for (round "
                             f"{state.round}); call ask first")
        raw = jnp.asarray(fitness_values, dtype).reshape(-1)
        if raw.shape[0] != u.shape[0]:
            raise ValueError(f"{self.label}.tell: expected {u.shape[0]} fitness values (one "
                             f"per point asked), got {raw.shape[0]}")
        f = finite_or_inf(raw)
        bad = state.n_nonfinite + jnp.sum(~jnp.isfinite(raw), dtype=jnp.int32)
        strategy, params = self._strategy(dim, dtype)
        i = jnp.argmin(f)
        if state.round < 0:
            s = strategy.init(state.k_init, u, f, params)
            best_u, best_f, t = u[i], f[i], state.t
        else:
            _, k_tell = jax.random.split(state.keys[state.t])
            s, _ = strategy.tell(k_tell, u, f, state.strategy, params)
            better = f[i] < state.best_f
            best_u = jnp.where(better, u[i], state.best_u)
            best_f = jnp.where(better, f[i], state.best_f)
            t = state.t + 1
        return dataclasses.replace(
            state, strategy=self._cast(s, dtype), best_u=best_u,
            best_x=lower + (upper - lower) * best_u, best_f=best_f,
            n_evaluations=state.n_evaluations + u.shape[0], n_nonfinite=bad, t=t,
            round=0, asked=False)

    def best(self, state: EvosaxState) -> tuple[Float[Array, " d"], Float[Array, ""]]:
        return state.best_x, state.best_f


