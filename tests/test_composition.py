"""The optimisers compose like optimistix's and evosax's: ``minimise`` inside ``jax.jit`` and
``jax.vmap`` (over keys, over the fitness's ``args``, over boxes, over data) is the same
computation as outside (a loop the user owns, ``init``/``step`` or ``ask``/``tell``, gives
the same numbers: ``tests/test_solver_paths.py``). Small budgets; every solver of the
contract."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj

K = 30  # iterations
LO, HI = -2 * np.ones(4), 2 * np.ones(4)


def rosenbrock(x, args=None):
    shift = 0.0 if args is None else args
    y = x - shift
    return jnp.sum(100.0 * (y[1:] - y[:-1] ** 2) ** 2 + (1.0 - y[:-1]) ** 2)


def solvers():
    out = [sj.SEDSABSO(n_phases=2), sj.BSO(population_size=20), sj.LDWPSO(population_size=20)]
    try:
        import evosax  # noqa: F401

        out.append(sj.Evosax("PSO", population_size=20))
    except ImportError:  # pragma: no cover - evosax is in the test extra
        pass
    return out


SOLVERS = solvers()
IDS = [s.label for s in SOLVERS]


def _one_by_one(solver, keys, **kw):
    return np.array([float(sj.minimise(rosenbrock, solver, LO, HI, key=k, iterations=K,
                                       **kw).f) for k in keys])


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_jit_vmap_over_keys_equals_runs_one_by_one(solver):
    keys = jax.random.split(jax.random.key(7), 3)
    traced = jax.jit(jax.vmap(lambda k: sj.minimise(rosenbrock, solver, LO, HI, key=k,
                                                   iterations=K)))(keys)
    assert traced.compile_s is None and traced.run_s is None  # timed by the caller
    assert traced.f.shape == (3,) and traced.history_f.shape == (3, K)
    np.testing.assert_allclose(traced.f, _one_by_one(solver, keys), rtol=1e-9, atol=0)
    assert traced.method == solver.label


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_vmap_over_args_equals_runs_one_by_one(solver):
    shifts = jnp.array([0.0, 0.3, -0.5])
    key = jax.random.key(3)
    traced = jax.vmap(lambda a: sj.minimise(rosenbrock, solver, LO, HI, key=key,
                                            iterations=K, args=a).f)(shifts)
    expected = [float(sj.minimise(rosenbrock, solver, LO, HI, key=key, iterations=K,
                                  args=float(a)).f) for a in shifts]
    np.testing.assert_allclose(traced, expected, rtol=1e-9, atol=0)
    assert len(set(np.round(np.asarray(traced), 12))) == 3  # three different problems


def test_vmap_over_boxes_and_runs_inside_jit():
    solver = sj.BSO(population_size=10)
    scales = jnp.array([1.0, 2.0])
    key = jax.random.key(4)
    traced = jax.jit(jax.vmap(lambda c: sj.minimise(rosenbrock, solver, -c * LO / LO,
                                                    c * HI / 2, key=key, iterations=K,
                                                    runs=2).f))(scales)
    assert traced.shape == (2, 2)
    for i, c in enumerate([1.0, 2.0]):
        outside = sj.minimise(rosenbrock, solver, -c * np.ones(4), c * HI / 2, key=key,
                              iterations=K, runs=2)
        np.testing.assert_allclose(traced[i], outside.f, rtol=1e-9)


def test_vmap_over_data_of_eq_17():
    """Several data sets of the paper's fitness in one call: an L1Residual built from
    traced torques."""
    rng = np.random.default_rng(0)
    W = rng.standard_normal((60, 3))
    taus = jnp.asarray(rng.standard_normal((3, 60)))
    solver = sj.LDWPSO(population_size=10)
    key = jax.random.key(5)
    traced = jax.vmap(lambda t: sj.minimise(sj.L1Residual(W, t), solver, -np.ones(3),
                                            np.ones(3), key=key, iterations=K).f)(taus)
    expected = [float(sj.minimise(sj.L1Residual(W, t), solver, -np.ones(3), np.ones(3),
                                  key=key, iterations=K).f) for t in np.asarray(taus)]
    np.testing.assert_allclose(traced, expected, rtol=1e-9)


def test_ask_and_tell_refuse_the_wrong_order():
    solver = sj.SEDSABSO(population_size=6)
    lo, hi = jnp.asarray(LO), jnp.asarray(HI)
    state = solver.init(sj.BlackBox(rosenbrock), lo, hi, jax.random.key(0), 5)
    with pytest.raises(ValueError, match="no points were asked for"):
        solver.tell(state, jnp.zeros(18), lo, hi)
    points, asked = solver.ask(state, lo, hi)
    assert points.shape == (3 * 6, 4)  # beetles and their antennae
    with pytest.raises(ValueError, match="expected 18 fitness values"):
        solver.tell(asked, jnp.zeros(5), lo, hi)
    with pytest.raises(ValueError, match="waits for tell"):
        sj.BSO().ask(sj.BSO().ask(sj.BSO().init(sj.BlackBox(rosenbrock), lo, hi,
                                                jax.random.key(0), 5), lo, hi)[1], lo, hi)
    annealing = solver.tell(asked, jax.vmap(rosenbrock)(points), lo, hi)
    candidates, _ = solver.ask(annealing, lo, hi)
    assert candidates.shape == (solver.n_trials, 4)  # Eq. 14's candidates around P_g


@pytest.mark.parametrize("make, match", [
    (lambda: sj.SEDSABSO(decay=1.5), r"decay must lie in \(0, 1\)"),
    (lambda: sj.BSO(beetle=sj.optim.BeetleStep(lam=2.0)), r"lam must lie in \[0, 1\]"),
    (lambda: sj.LDWPSO(population_size=0), "population_size must be an integer >= 1"),
    (lambda: sj.Evosax("CMAES"), "unknown evosax strategy 'CMAES'"),
])
def test_bad_hyperparameter_fails_when_the_solver_is_built(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_traced_box_of_the_wrong_shape_is_one_line():
    with pytest.raises(ValueError, match="bounds must be two 1-D arrays"):
        jax.jit(lambda k: sj.minimise(rosenbrock, sj.BSO(), LO, HI[:3], key=k,
                                      iterations=3).f)(jax.random.key(0))
