"""The swarms: N(t), Metropolis, determinism, batching, NaN handling, test functions, the
RS010N identification problem, bad input. Budgets are small; speed is benchmarked apart."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.optim._phases import phases
from sedsabso_jax.optim._random import uniforms
from sedsabso_jax.optim._sedsabso import metropolis_accept

# SEDSABSO with 2 compiled phases keeps the suite's compile time down; the phase logic is
# tested on its own below.
SOLVERS = {"SEDSABSO": sj.SEDSABSO(n_phases=2), "BSO": sj.BSO(), "LDWPSO": sj.LDWPSO()}


def sphere(x, args=None):
    return jnp.sum(x**2)


def rosenbrock(x, args=None):
    return jnp.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2)


def rastrigin(x, args=None):
    return 10.0 * x.shape[0] + jnp.sum(x**2 - 10.0 * jnp.cos(2 * jnp.pi * x))


def test_population_schedule_follows_the_notes():
    n = sj.SEDSABSO().schedule(600)
    assert n[0] == 67 and n[-1] == 37  # round(90 e^-0.3), round(90 e^-0.9)
    assert np.all(np.diff(n) <= 0)
    assert abs(n.mean() - 50) < 1.5  # the same work as BSO with N = 50 (Figure 5)
    np.testing.assert_array_equal(sj.BSO().schedule(600), 50)


def test_phases_cover_the_schedule():
    n = sj.SEDSABSO().schedule(600)
    parts = phases(n, 4)
    assert parts[0][0] == 0 and parts[-1][1] == 600
    assert all(b == a2 for (_, b, _), (a2, _, _) in zip(parts[:-1], parts[1:]))
    assert all(slots == n[a:b].max() for a, b, slots in parts)
    work = sum((b - a) * slots for a, b, slots in parts)
    assert work / n.sum() < 1.08  # phases cost at most 8 % over the ideal
    assert work / (50 * 600) < 1.08  # and so about what BSO with N = 50 costs


@pytest.mark.parametrize("f_new,f_old,T,p", [
    (1.0, 0.0, 1.0, np.exp(-1.0)), (2.0, 0.0, 4.0, np.exp(-0.5)), (-1.0, 0.0, 1.0, 1.0),
    (np.inf, 0.0, 1e4, 0.0), (np.nan, 0.0, 1.0, 0.0),
])
def test_metropolis_acceptance_rate(f_new, f_old, T, p):
    n = 200_000
    u = jax.random.uniform(jax.random.key(0), (n,), jnp.float64)
    acc = metropolis_accept(u, jnp.float64(f_new), jnp.float64(f_old), T)
    rate = float(jnp.mean(acc))
    sigma = max(np.sqrt(p * (1 - p) / n), 1e-12)
    assert abs(rate - p) <= 5 * sigma


@pytest.mark.parametrize("name", SOLVERS)
# Tolerances: 10x the best of the 4 runs measured on the 2-core AMD EPYC VM (2026-11-23),
# measured value in the comment. Rastrigin's nearest local minima score 0.995: every
# tolerance there is far below, so a swarm stuck in one fails.
@pytest.mark.parametrize("fn,dim,half,tol", [
    (sphere, 10, 5.0, {"SEDSABSO": 2e-2,  # 1.8e-3
                       "BSO": 6e-3,  # 5.6e-4
                       "LDWPSO": 1e-8}),  # 1.0e-9
    (rosenbrock, 2, 2.0, {"SEDSABSO": 5e-6,  # 5.3e-7
                          "BSO": 4e-8,  # 3.9e-9
                          "LDWPSO": 3e-12}),  # 2.3e-13
    (rastrigin, 2, 5.12, {"SEDSABSO": 1e-10,  # 0.0 (best of 4; the others 1e-12)
                          "BSO": 1e-12,  # 9.9e-14
                          "LDWPSO": 1e-10}),  # 0.0
])
def test_reaches_documented_tolerance(name, fn, dim, half, tol):
    """Best of 4 runs of 300 iterations from the whole box; the tolerances are this
    budget's (the paper's settings are tuned for identification, not these functions)."""
    r = sj.minimise(fn, SOLVERS[name], -half * np.ones(dim), half * np.ones(dim),
                    key=jax.random.key(1), iterations=300, runs=4)
    assert float(jnp.min(r.f)) <= tol[name]
    # the reported best is monotone and is the fitness of the reported point
    assert np.all(np.diff(np.asarray(r.history_f), axis=-1) <= 0)
    np.testing.assert_allclose(jax.vmap(fn)(r.x), r.f, rtol=1e-9, atol=1e-15)


def _rs010n_problem(samples=300, box=0.05, seed=0):
    base = sj.base_parameters(sj.robots.rs010n())
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (samples, 3))
    qd, qdd = rng.normal(size=(2, samples, 3))
    true = np.asarray(base.values)
    tau = np.asarray(base.regressor(q, qd, qdd)) @ true
    half = np.maximum(box * np.abs(true), box)
    return sj.L1Residual.from_base(base, q, qd, qdd, tau), true - half, true + half, true


@pytest.mark.parametrize("name", SOLVERS)
def test_rs010n_identification_cuts_the_fitness(name):
    """Noise-free paper problem, box +-5 % around the true base parameters, 600
    iterations: every run at least halves Eq. 17 and the mean is cut at least 4x
    (measured: 3-20x per run; the paper's accuracy is the benchmark's business)."""
    problem, lo, hi, true = _rs010n_problem()
    r = sj.minimise(problem, SOLVERS[name], lo, hi, key=jax.random.key(0), iterations=600, runs=2)
    f, f0 = np.asarray(r.f), np.asarray(r.history_f[:, 0])
    assert np.all(f <= 0.5 * f0) and f.mean() <= 0.25 * f0.mean()
    assert np.all((np.asarray(r.x) >= lo - 1e-12) & (np.asarray(r.x) <= hi + 1e-12))
    if name == "SEDSABSO":
        assert np.all(np.asarray(r.sa_accepted) > 0)
        np.testing.assert_array_equal(r.history_n[0], sj.SEDSABSO().schedule(600))


def test_antenna_difference_matches_two_evaluations():
    """The one-pass antenna comparison of Eq. 17 equals f(x + a v) - f(x - a v) computed
    directly with numpy, and the black-box form agrees with it."""
    rng = np.random.default_rng(1)
    W, tau = rng.standard_normal((300, 7)), rng.standard_normal(300)
    X, V = rng.standard_normal((5, 7)), rng.standard_normal((5, 7))
    problem = sj.L1Residual(W, tau)
    f = lambda P: np.abs(P @ W.T - tau).sum(-1)  # noqa: E731
    expected = f(X + 0.3 * V) - f(X - 0.3 * V)
    diff, bad = problem.antenna_difference(problem.embed(X), problem.embed(V), 0.3)
    np.testing.assert_allclose(diff, expected, rtol=1e-12, atol=1e-9)
    assert not np.any(bad)
    box = sj.BlackBox(lambda x, args: jnp.abs(x @ W.T - tau).sum())
    diff_bb, _ = box.antenna_difference(jnp.asarray(X), jnp.asarray(V), 0.3)
    np.testing.assert_allclose(diff_bb, expected, rtol=1e-12, atol=1e-9)


def test_batched_draws_equal_one_call_per_key():
    keys = jax.random.split(jax.random.key(9), 3)
    batched = uniforms(keys, (4, 5), jnp.float64)
    for k, b in zip(keys, batched):
        np.testing.assert_array_equal(b, jax.random.uniform(k, (4, 5), jnp.float64))


def test_sedsabso_without_annealing():
    """q = 0 is BSO with the shrinking population: no SA trial, no acceptance, and the
    evaluations are exactly 3 per active beetle per iteration plus the initial slots."""
    solver = sj.SEDSABSO(n_trials=0)
    r = sj.minimise(sphere, solver, -5 * np.ones(4), 5 * np.ones(4), key=jax.random.key(1),
                    iterations=50)
    assert int(r.sa_accepted) == 0 and np.isfinite(float(r.f))
    assert int(r.n_evaluations) == solver.population_size + 3 * int(solver.schedule(50).sum())


def test_same_key_same_numbers_other_key_other_numbers():
    solver = SOLVERS["SEDSABSO"]
    box = (-5 * np.ones(10), 5 * np.ones(10))
    a = sj.minimise(sphere, solver, *box, key=jax.random.key(3), iterations=300, runs=4)
    b = sj.minimise(sphere, solver, *box, key=jax.random.key(3), iterations=300, runs=4)
    c = sj.minimise(sphere, solver, *box, key=jax.random.key(4), iterations=300, runs=4)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history_f, b.history_f)
    assert not np.array_equal(a.x, c.x)
    assert b.compile_s == 0.0  # the second call reused the compiled code


@pytest.mark.parametrize("batch", ["vmap", 1, 2, "auto", "shard"])
def test_batched_runs_equal_single_runs(batch):
    solver = SOLVERS["BSO"]
    box = (-2 * np.ones(2), 2 * np.ones(2))
    key = jax.random.key(5)
    many = sj.minimise(rosenbrock, solver, *box, key=key, iterations=300, runs=3, batch=batch)
    for i, k in enumerate(jax.random.split(key, 3)):
        one = sj.minimise(rosenbrock, solver, *box, key=k, iterations=300)
        np.testing.assert_allclose(one.x, many.x[i], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(one.history_f, many.history_f[i], rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("batch, message", [(0, "integer >= 1"), (True, "integer >= 1"),
                                            ("loop", "'auto', 'vmap', 'shard'")])
def test_bad_batch(batch, message):
    with pytest.raises(ValueError, match=message):
        sj.minimise(rosenbrock, SOLVERS["BSO"], -np.ones(2), np.ones(2), key=jax.random.key(0),
                    iterations=5, runs=2, batch=batch)


@pytest.mark.parametrize("name", SOLVERS)
def test_nan_fitness_never_becomes_the_best(name):
    def holed(x, args=None):  # NaN on half the box, where the true minimum would be
        return jnp.where(x[0] > 0.0, jnp.nan, jnp.sum((x - 1.0) ** 2))

    r = sj.minimise(holed, SOLVERS[name], -3 * np.ones(2), 3 * np.ones(2),
                    key=jax.random.key(2), iterations=300)
    assert np.isfinite(float(r.f)) and float(r.x[0]) <= 0.0
    assert int(r.n_nonfinite) > 0


@pytest.mark.parametrize("name", ["SEDSABSO", "LDWPSO"])
def test_float32_runs(name):
    """float32 cuts Eq. 17 like float64 (same criterion as above) and the fitness it
    reports is Eq. 17 at the returned point, evaluated in float64, to float32 rounding."""
    problem, lo, hi, _ = _rs010n_problem()
    r = sj.minimise(problem, SOLVERS[name], lo, hi, key=jax.random.key(0), iterations=600,
                    dtype=jnp.float32, runs=2)
    assert r.x.dtype == jnp.float32 and r.f.dtype == jnp.float32
    f, f0 = np.asarray(r.f, float), np.asarray(r.history_f[:, 0], float)
    assert np.all(f <= 0.5 * f0) and f.mean() <= 0.25 * f0.mean()
    W, tau = np.asarray(problem.W), np.asarray(problem.tau)
    exact = np.abs(np.asarray(r.x, float) @ W.T - tau).sum(-1)
    np.testing.assert_allclose(f, exact, rtol=1e-4)


@pytest.mark.parametrize("make,call,match", [
    (lambda: sj.SEDSABSO(population_size=0), {}, "population_size must be an integer >= 1"),
    (lambda: sj.BSO(population_size=0), {}, "population_size must be an integer >= 1"),
    (lambda: sj.SEDSABSO(n_trials=-1), {}, "n_trials must be an integer >= 0"),
    (lambda: sj.SEDSABSO(temperature=0.0), {}, "temperature must be > 0"),
    (lambda: sj.SEDSABSO(decay=1.0), {}, r"decay must lie in \(0, 1\)"),
    (lambda: sj.SEDSABSO(decay=0.0), {}, r"decay must lie in \(0, 1\)"),
    (lambda: sj.BSO(), {"iterations": 0}, "iterations must be an integer >= 1"),
    (lambda: sj.BSO(), {"runs": 0}, "runs must be an integer >= 1"),
    (lambda: sj.BSO(), {"upper": -np.ones(2)}, r"lower < upper; at index 0: lower -1 >= upper -1"),
    (lambda: sj.BSO(), {"upper": np.ones(3)}, "bounds must be two 1-D arrays of one length"),
    (lambda: sj.BSO(), {"dtype": jnp.int32}, "dtype must be float32 or float64"),
])
def test_bad_input_fails_before_compiling(make, call, match):
    kwargs = {"lower": -np.ones(2), "upper": np.ones(2), "iterations": 10} | call
    with pytest.raises(ValueError, match=match):
        sj.minimise(sphere, make(), key=jax.random.key(0), **kwargs)


@pytest.mark.parametrize("key, got", [
    (0, "0"), (np.int64(7), "np.int64(7)"),
    (np.zeros((2, 3)), "an array of dtype float64 and shape (2, 3)"),
])
def test_key_must_be_a_prng_key(key, got):
    message = f"key must be a JAX PRNG key, e.g. jax.random.key(0), got {got}"
    with pytest.raises(TypeError, match=f"^{re.escape(message)}$"):
        sj.minimise(sphere, sj.LDWPSO(), -np.ones(2), np.ones(2), key=key, iterations=5)


def test_raw_key_data_is_still_a_key():
    kw = dict(lower=-np.ones(2), upper=np.ones(2), iterations=5)
    typed = sj.minimise(sphere, sj.LDWPSO(), key=jax.random.key(3), **kw)
    raw = sj.minimise(sphere, sj.LDWPSO(), key=jax.random.PRNGKey(3), **kw)
    assert float(raw.f) == float(typed.f)


@pytest.mark.parametrize("name", [*SOLVERS, "jit"])
def test_a_fitness_must_return_a_scalar_per_point(name):
    message = "the fitness must return a scalar per point, got shape (3,) for x of shape (3,)"

    def call(key):
        return sj.minimise(lambda x, a: x ** 2, SOLVERS.get(name, sj.LDWPSO()), -jnp.ones(3),
                           jnp.ones(3), key=key, iterations=5, runs=2).f

    with pytest.raises(ValueError) as err:
        (jax.jit(call) if name == "jit" else call)(jax.random.key(0))
    assert str(err.value) == message  # JAX's note on its filtered traceback aside


def test_bounds_must_match_the_problem():
    problem, lo, hi, _ = _rs010n_problem(samples=20)
    with pytest.raises(ValueError, match="bounds have length 20, the fitness has 21 parameters"):
        sj.minimise(problem, sj.BSO(), lo[:20], hi[:20], key=jax.random.key(0), iterations=5)


def test_runs_shard_over_devices():
    """Four CPU devices (XLA flag, in a subprocess): runs are spread over them and give
    the numbers of the unsharded run."""
    code = textwrap.dedent("""
        import jax, numpy as np, jax.numpy as jnp
        jax.config.update("jax_enable_x64", True)
        import sedsabso_jax as sj
        assert len(jax.devices()) == 4
        f = lambda x, a: jnp.sum(x ** 2)
        kw = dict(lower=-np.ones(3), upper=np.ones(3), key=jax.random.key(0), iterations=50, runs=6)
        a = sj.minimise(f, sj.BSO(population_size=8), **kw)  # batch "auto": sharded
        b = sj.minimise(f, sj.BSO(population_size=8), batch="vmap", **kw)  # one device
        assert len(b.f.sharding.device_set) == 1
        assert a.x.shape == (6, 3)
        np.testing.assert_allclose(a.x, b.x, rtol=1e-12, atol=1e-14)
        print("devices used:", len(a.f.sharding.device_set))
    """)
    # host devices: the CPU platform, also on a machine with a GPU
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4",
               JAX_PLATFORMS="cpu")
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "devices used: 4" in run.stdout


def test_one_run_is_timed_without_a_second_compilation():
    from sedsabso_jax.optim._driver import time_one_of_many

    box = (-2 * np.ones(3), 2 * np.ones(3))
    solver = sj.BSO(population_size=9)
    kw = dict(key=jax.random.key(3), iterations=40)
    sj.minimise(rosenbrock, solver, *box, runs=4, **kw)  # compiles the batched executable
    compile_s, run_s = time_one_of_many(rosenbrock, solver, *box, runs=4, **kw)
    if jax.default_backend() == "cpu" and jax.device_count() == 1:
        assert compile_s == 0.0  # the batched executable, already compiled, runs one run
    assert run_s > 0.0  # how long it takes is the benchmark's business, not a unit test's


@pytest.mark.parametrize("name, f_runs, x00", [
    ("SEDSABSO", (0.9488408946863195, 0.7420115581537542), 0.7267455149914717),
    ("BSO", (0.7238839720397102, 0.8178445960378995), 0.5717979263388009),
    ("LDWPSO", (0.3746915547095892, 0.21844601599271482), 0.6867452795819949),
])
def test_seeded_runs_are_pinned(name, f_runs, x00):
    """A seed's numbers do not drift between versions: 2 runs of 25 iterations on
    Rosenbrock, key 42, as measured on the project's 2-core AMD EPYC VM (jax 0.10.2); a
    change to the random stream, the update rules or their order changes them. The
    tolerance (1e-9 relative) allows for floating-point reassociation on other CPUs."""
    r = sj.minimise(rosenbrock, SOLVERS[name], -2 * np.ones(3), 2 * np.ones(3),
                    key=jax.random.key(42), iterations=25, runs=2)
    np.testing.assert_allclose(np.asarray(r.f), f_runs, rtol=1e-9)
    assert float(np.asarray(r.x)[0, 0]) == pytest.approx(x00, rel=1e-9)
