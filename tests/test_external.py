"""evosax strategies through minimise: same fitness objects, box, keys and Result as the
swarms; budgets in evaluations agree with what the runs count."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.optim._budget import evaluation_counts, iterations_for_budget
from sedsabso_jax.optim._external import Evosax

pytest.importorskip("evosax")

LO, HI = np.array([-1.0, 10.0, -200.0]), np.array([1.0, 30.0, 100.0])  # sides 2, 20, 300
X_STAR = np.array([0.3, 12.0, 50.0])


def sphere(x, args):
    return jnp.sum(((x - X_STAR) / (HI - LO)) ** 2)


@pytest.mark.parametrize("name", ["CMA_ES", "PSO", "DifferentialEvolution", "SNES"])
def test_strategy_finds_the_optimum_in_a_box_of_unequal_sides(name):
    r = sj.minimise(sphere, Evosax(name), LO, HI, key=jax.random.key(0), iterations=150,
                    runs=3)
    assert r.method == f"evosax {name}"
    x = np.asarray(r.x)
    assert np.all((x >= LO) & (x <= HI))
    assert np.all(np.abs(x - X_STAR) <= 0.02 * (HI - LO)), x
    # the reported value is the fitness at the reported point
    np.testing.assert_allclose(r.f, [sphere(xi, None) for xi in x], rtol=1e-12)
    # history: best so far, never increasing, ending at f
    h = np.asarray(r.history_f)
    assert np.all(np.diff(h, axis=-1) <= 0) and np.allclose(h[:, -1], r.f)


def test_optimum_on_the_boundary_is_reached_by_clipping():
    f = lambda x, a: jnp.sum(x / (HI - LO))  # noqa: E731 - minimum at the lower corner
    r = sj.minimise(f, Evosax("CMA_ES"), LO, HI, key=jax.random.key(1), iterations=100)
    assert np.all(np.abs(np.asarray(r.x) - LO) <= 1e-6 * (HI - LO)), r.x


def test_seeded_runs_are_identical_and_keys_differ():
    kw = dict(key=jax.random.key(3), iterations=40, runs=2)
    a = sj.minimise(sphere, Evosax("PSO"), LO, HI, **kw)
    b = sj.minimise(sphere, Evosax("PSO"), LO, HI, **kw)
    np.testing.assert_array_equal(a.x, b.x)
    assert a.f[0] != a.f[1]


def test_nonfinite_fitness_is_counted_and_never_best():
    f = lambda x, a: jnp.where(x[0] > 0, jnp.nan, jnp.sum(x ** 2))  # noqa: E731
    r = sj.minimise(f, Evosax("PSO"), LO, HI, key=jax.random.key(0), iterations=20)
    assert int(r.n_nonfinite) > 0 and np.isfinite(float(r.f)) and float(r.x[0]) <= 0


@pytest.mark.parametrize("solver", [sj.SEDSABSO(), sj.BSO(population_size=7), sj.LDWPSO(),
                                    Evosax("CMA_ES"), Evosax("PSO", population_size=9),
                                    Evosax("Open_ES")], ids=str)
def test_evaluation_counts_match_the_runs(solver):
    for k in (1, 13):
        r = sj.minimise(sphere, solver, LO, HI, key=jax.random.key(0), iterations=k)
        assert int(r.n_evaluations) == evaluation_counts(solver, k, 3)[-1]


def test_budget_gives_the_most_iterations_that_fit():
    for solver in (sj.SEDSABSO(), sj.BSO(), sj.LDWPSO(), Evosax("CMA_ES"), Evosax("PSO")):
        k = iterations_for_budget(solver, 5000, 10)
        assert evaluation_counts(solver, k, 10)[-1] <= 5000
        assert evaluation_counts(solver, k + 1, 10)[-1] > 5000
    assert iterations_for_budget(sj.LDWPSO(), 100, 3) == 1  # 50 initial + 50
    with pytest.raises(ValueError, match="below one generation of SEDSABSO"):
        iterations_for_budget(sj.SEDSABSO(), 200, 5)
    with pytest.raises(ValueError, match="budget must be an integer"):
        iterations_for_budget(sj.BSO(), 0, 5)


def test_bad_strategy_settings():
    with pytest.raises(ValueError, match="unknown evosax strategy 'CMAES'.*CMA_ES"):
        sj.minimise(sphere, Evosax("CMAES"), LO, HI, key=jax.random.key(0), iterations=2)
    with pytest.raises(ValueError, match="PSO has no parameter.*inertia"):
        sj.minimise(sphere, Evosax("PSO", params={"inertia": 0.5}), LO, HI,
                    key=jax.random.key(0), iterations=2)
    with pytest.raises(ValueError, match="population_size must be an integer >= 1"):
        Evosax("PSO", population_size=0)
    # a parameter that exists is used: PSO without inertia or pulls does not move
    still = Evosax("PSO", params={"inertia_coeff": 0.0, "cognitive_coeff": 0.0,
                                  "social_coeff": 0.0})
    a = sj.minimise(sphere, still, LO, HI, key=jax.random.key(0), iterations=1)
    b = sj.minimise(sphere, still, LO, HI, key=jax.random.key(0), iterations=30)
    assert float(a.f) == float(b.f)
