"""Any evosax strategy through :func:`~sedsabso_jax.minimise`: the same fitness objects,
box, keys, many runs per call and :class:`~.result.Result` as the swarms, so a comparison
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
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .fitness import finite_or_inf
from .swarm import check_population

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


class Evosax(eqx.Module):
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

    def check(self) -> None:
        algorithms = _evosax_algorithms()
        if self.name not in algorithms:
            raise ValueError(f"unknown evosax strategy {self.name!r}; expected one of "
                             f"{', '.join(sorted(algorithms))}")
        if self.population_size is not None:
            check_population(self.population_size, "population_size")
        if not self.std_init > 0:
            raise ValueError(f"std_init must be > 0, got {self.std_init}")

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

    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        """Cumulative fitness evaluations after each generation (the initial population
        of a population-based strategy counts before the first)."""
        lam = self.population(dim)
        start = 0 if self.distribution_based else lam
        return start + lam * np.arange(1, iterations + 1)

    def single_run(self, fitness, lower, upper, key, iterations: int):
        """One run: ``(best_x, best_f, history_f, history_n, sa_accepted, n_evaluations,
        n_nonfinite)`` like the swarms' runs (see :func:`~.driver.minimise`)."""
        dim, dtype = lower.shape[0], lower.dtype
        strategy, params = self._strategy(dim, dtype)
        lam = self.population(dim)
        width = upper - lower

        def cast(tree):  # evosax builds float64 state under x64: keep the carry in dtype
            return jax.tree.map(lambda a: a.astype(dtype) if jnp.issubdtype(
                jnp.result_type(a), jnp.floating) else a, tree)

        def evaluate(u):
            u = jnp.clip(u, 0.0, 1.0)
            raw = fitness.value(fitness.embed(lower + width * u))
            bad = jnp.sum(~jnp.isfinite(raw), dtype=jnp.int32)
            return u, finite_or_inf(raw), bad

        k_init, k_pop, k_loop = jax.random.split(key, 3)
        if self.distribution_based:
            mean = jax.random.uniform(k_pop, (dim,), dtype)
            state = strategy.init(k_init, mean, params)
            best_u, best_f, n_bad = mean, jnp.asarray(jnp.inf, dtype), jnp.int32(0)
        else:
            u0, f0, n_bad = evaluate(jax.random.uniform(k_pop, (lam, dim), dtype))
            state = strategy.init(k_init, u0, f0, params)
            i = jnp.argmin(f0)
            best_u, best_f = u0[i], f0[i]

        def generation(carry, k):
            state, best_u, best_f, n_bad = carry
            k_ask, k_tell = jax.random.split(k)
            u, state = strategy.ask(k_ask, state, params)
            u, f, bad = evaluate(u)
            state, _ = strategy.tell(k_tell, u, f, state, params)
            i = jnp.argmin(f)
            better = f[i] < best_f
            best_u = jnp.where(better, u[i], best_u)
            best_f = jnp.where(better, f[i], best_f)
            return (cast(state), best_u, best_f, n_bad + bad), best_f

        carry = (cast(state), best_u, best_f, n_bad)
        (_, best_u, best_f, n_bad), hist = jax.lax.scan(
            generation, carry, jax.random.split(k_loop, iterations))
        n_eval = int(self.evaluation_counts(iterations, dim)[-1])
        return (lower + width * best_u, best_f, hist, jnp.full(iterations, lam, jnp.int32),
                jnp.int32(0), jnp.int32(n_eval), n_bad)
