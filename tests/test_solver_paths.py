"""One way to run a solver, seen three ways: ``minimise`` (``run``: ``init``, then the
step's iteration in a scan, per phase for a shrinking population, draws made before the
loop on the CPU), a loop of ``init`` and ``step``, and a loop of ``start``, ``ask`` and
``tell`` with the fitness evaluated outside. Every solver kind (a shrinking population with
annealing rounds, without them, constant populations, evosax strategies population-based
and distribution-based), in float64 and float32, on a fitness with NaN holes: the same
best point and fitness up to rounding (XLA fuses the draws made before a loop and inside
it differently), the same counts. And the traps a new user fell into: a fitness of one
argument, a traced box turned inside out, a compile cache that only grew, two names for a
population."""

from __future__ import annotations

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.optim import _driver

K = 25
LO, HI = -2 * np.ones(3), 2 * np.ones(3)


def holed(x, args=None):
    """Rosenbrock with a NaN hole (counted, never a best)."""
    value = jnp.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2)
    return jnp.where(x[0] > 1.0, jnp.nan, value)


def solvers():
    out = [sj.SEDSABSO(population_size=12, n_phases=2),  # shrinks within and across phases
           sj.SEDSABSO(population_size=8, n_trials=0),  # one round per iteration
           sj.BSO(population_size=7), sj.LDWPSO(population_size=9)]
    try:
        import evosax  # noqa: F401

        out += [sj.Evosax("PSO", population_size=8), sj.Evosax("CMA_ES")]
    except ImportError:  # pragma: no cover - evosax is in the test extra
        pass
    return out


SOLVERS = solvers()
#: every solver in float64; a shrinking swarm and a strategy in float32 too
CASES = [(s, jnp.float64) for s in SOLVERS] + [(SOLVERS[0], jnp.float32),
                                                (SOLVERS[-1], jnp.float32)]
IDS = [f"{s.label}-{i}-{jnp.dtype(d).name}" for i, (s, d) in enumerate(CASES)]


def _with_steps(solver, fitness, lo, hi, key):
    state = solver.init(fitness, lo, hi, key, K)
    structure = jax.tree.structure(state)
    state = solver.step(fitness, state, lo, hi)
    assert jax.tree.structure(state) == structure  # the static part never changes
    state = jax.lax.fori_loop(1, K, lambda i, s: solver.step(fitness, s, lo, hi), state)
    return state


def _with_ask_tell(solver, fitness, lo, hi, key):
    def round_(state):
        points, state = solver.ask(state, lo, hi)
        return solver.tell(state, fitness.evaluate(points), lo, hi)

    state = solver.start(lo, hi, key, K)
    for _ in range(solver.initial_asks):
        state = round_(state)

    def iteration(i, state):
        for _ in range(solver.asks_per_iteration):
            state = round_(state)
        return state

    structure = jax.tree.structure(state)
    state = iteration(0, state)
    assert jax.tree.structure(state) == structure  # between iterations, as with step
    return jax.lax.fori_loop(1, K, iteration, state)


@pytest.mark.parametrize("solver, dtype", CASES, ids=IDS)
def test_run_step_and_ask_tell_agree(solver, dtype):
    key = jax.random.key(3)
    fitness = sj.BlackBox(holed)
    lo, hi = jnp.asarray(LO, dtype), jnp.asarray(HI, dtype)
    reference = sj.minimise(fitness, solver, LO, HI, key=key, iterations=K, dtype=dtype)
    rtol = 1e-9 if dtype == jnp.float64 else 1e-4
    for way in (_with_steps, _with_ask_tell):
        state = jax.jit(lambda k, way=way: way(solver, fitness, lo, hi, k))(key)
        x, f = solver.best(state)
        assert x.dtype == dtype
        np.testing.assert_allclose(f, reference.f, rtol=rtol, err_msg=way.__name__)
        np.testing.assert_allclose(x, reference.x, rtol=rtol, atol=rtol, err_msg=way.__name__)
        assert int(solver.n_evaluations(state)) == int(reference.n_evaluations)
        assert int(solver.n_nonfinite(state)) == int(reference.n_nonfinite)
        result = solver.result(state, jnp.zeros(K, dtype), 3)
        assert int(result.sa_accepted) == int(reference.sa_accepted)
    assert int(reference.n_nonfinite) > 0  # the hole was hit


def test_shrinking_population_is_cut_where_run_cuts_it():
    """The history of N is Eq. 15-16's schedule, and each compiled phase holds its
    largest N: step on a full-size state keeps the cut slots inactive."""
    solver = sj.SEDSABSO(population_size=12, n_phases=2)
    plan = solver.plan(K)
    assert [s for _, _, s in plan.phases] == [int(solver.schedule(K)[a]) for a, _, _ in
                                              plan.phases]
    assert plan.drops.any() and not plan.starts[plan.drops].any()  # drops inside phases
    fitness, lo, hi = sj.BlackBox(holed), jnp.asarray(LO), jnp.asarray(HI)
    state = solver.init(fitness, lo, hi, jax.random.key(0), K)
    step = jax.jit(lambda s: solver.step(fitness, s, lo, hi))
    for t in range(K):
        state = step(state)
        assert int(state.active.sum()) == int(solver.schedule(K)[t]), t


# ------------------------------------------------------------------------- the traps
def test_a_fitness_of_one_argument_is_refused_before_tracing():
    calls = []

    def sphere(x):
        calls.append(1)
        return jnp.sum(x ** 2)

    with pytest.raises(TypeError, match=r"called f\(x, args\).*sphere\(x\) takes other "
                                        r"arguments.*lambda x, args: sphere\(x\)"):
        sj.minimise(sphere, sj.BSO(), LO, HI, key=jax.random.key(0), iterations=3)
    with pytest.raises(TypeError, match=r"f\(x, args\)"):
        jax.jit(lambda k: sj.minimise(sphere, sj.BSO(), LO, HI, key=k, iterations=3).f)(
            jax.random.key(0))
    with pytest.raises(TypeError, match=r"f\(x, args\)"):
        sj.BlackBox(sphere)
    assert calls == []  # refused before anything traced it
    # two parameters, or one with a default for the second, are fine
    sj.minimise(lambda x, a=None: jnp.sum(x ** 2), sj.BSO(population_size=4), LO, HI,
                key=jax.random.key(0), iterations=2)


def test_a_traced_box_turned_inside_out_fails_when_it_runs():
    def best(lo):
        return sj.minimise(holed, sj.BSO(population_size=4), lo, HI, key=jax.random.key(0),
                           iterations=3).f

    assert np.isfinite(float(jax.jit(best)(jnp.asarray(LO))))
    bad = LO.copy()
    bad[1] = 2.5  # above the upper bound 2
    with pytest.raises(Exception, match="the bounds need lower < upper"):
        jax.block_until_ready(jax.jit(best)(jnp.asarray(bad)))
    with pytest.raises(Exception, match="the bounds need lower < upper"):
        jax.block_until_ready(jax.vmap(best)(jnp.stack([jnp.asarray(LO), jnp.asarray(bad)])))


def test_compiled_runs_are_bounded_and_clearable(monkeypatch):
    monkeypatch.setattr(_driver, "_COMPILED", _driver.CompiledRuns(size=2))
    solver = sj.LDWPSO(population_size=4)

    def call(iterations):
        return sj.minimise(holed, solver, LO, HI, key=jax.random.key(0), iterations=iterations)

    first = call(3)
    assert first.compile_s > 0 and call(3).compile_s == 0.0
    call(4), call(5)
    assert len(_driver._COMPILED) == 2  # the least recently used (3 iterations) dropped
    assert call(3).compile_s > 0 and call(5).compile_s == 0.0
    sj.optim.clear_compiled()
    assert len(_driver._COMPILED) == 0 and call(5).compile_s > 0


@pytest.mark.parametrize("cls, old", [(sj.SEDSABSO, "n_start"), (sj.BSO, "n_beetles"),
                                      (sj.LDWPSO, "n_particles")])
def test_one_population_argument(cls, old):
    """``population_size`` for every swarm (evosax's name); the old names keep working
    through 0.5.x with a warning that names the new one."""
    with pytest.warns(DeprecationWarning, match=f"{old}.*removed after sedsabso-jax.*"
                                                f"population_size"):
        solver = cls(**{old: 11})
    assert solver.population_size == 11 and solver.population(3) == 11
    with pytest.warns(DeprecationWarning, match="population_size"):
        assert getattr(solver, old) == 11
    with pytest.raises(TypeError, match=f"both {old}="):
        cls(**{old: 11, "population_size": 12})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cls(population_size=11)


def test_hyperparameters_are_flat_with_the_beetle_step_first():
    h = sj.SEDSABSO.paper().hyperparameters()
    assert list(h)[:8] == ["c1", "c2", "w", "lam", "delta", "c", "vmax_fraction",
                           "literal_sign"]
    assert h["population_size"] == 90 and h["n_trials"] == 3 and "beetle" not in h
    assert sj.LDWPSO().hyperparameters()["w_start"] == 0.9
