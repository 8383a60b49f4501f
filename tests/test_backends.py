"""What depends on the backend: batch and block sizes chosen per backend (the accelerator's
choices tested here on the CPU by making ``jax.default_backend`` say "gpu"), memory
budgets and the memory a batch of runs needs, full float32 precision in the products
(``Precision.HIGHEST`` in the jaxprs), the swarms' lean kernels (random draws, Eq. 17's
evaluation paths, pinned seeded runs) and the accelerator's code path giving the CPU's
numbers."""

from __future__ import annotations

import importlib

import jax
import jax.extend
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.optim import _driver as driver
from sedsabso_jax.optim import _fitness as l1
from sedsabso_jax.optim._random import uniforms

# the modules (the packages re-export functions of the same names)
reg = importlib.import_module("sedsabso_jax.dynamics._regressor")
design = importlib.import_module("sedsabso_jax.excitation._design")
exfit = importlib.import_module("sedsabso_jax.excitation._fitness")


@pytest.fixture
def gpu(monkeypatch):
    """Code traced inside sees an accelerator backend (it still runs on the CPU). The
    compiled-code caches are emptied before and after, so nothing traced for one backend
    is reused for the other."""
    driver._COMPILED.clear()
    jax.clear_caches()
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    yield
    monkeypatch.undo()
    driver._COMPILED.clear()
    jax.clear_caches()


def l1_problem(m=1000, d=5, seed=7):
    """Eq. 17 with m rows."""
    rng = np.random.default_rng(seed)
    W = rng.standard_normal((m, d))
    true = rng.uniform(-1, 1, d)
    return sj.L1Residual(W, W @ true + 0.01 * rng.standard_normal(m)), true - 0.5, true + 0.5


# ------------------------------------------------------------------------------ batching
def test_regressor_chunks_per_backend(monkeypatch):
    # the CPU keeps its cache-sized chunks whatever the budget
    assert reg.chunk_size(3, 10_000) == 16 and reg.chunk_size(7, 10_000) == 8
    assert reg.chunk_size(3, 10_000, memory_budget=10**6) == 16
    # an accelerator takes all samples at once, or chunks as large as the budget allows
    assert reg.chunk_size(3, 10_000, backend="gpu") is None
    per = reg.sample_bytes(7)
    assert reg.chunk_size(7, 10_000, memory_budget=10**6, backend="gpu") == 10**6 // per
    assert reg.chunk_size(7, 10**9, backend="gpu") == reg.DEFAULT_MEMORY_BUDGET // per
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert reg.chunk_size(3, 10_000) is None


def test_regressor_all_at_once_equals_chunks(rng):
    """The accelerator's layout (one vectorised call, or other chunk sizes) gives the CPU's
    rows."""
    robot = sj.robots.rs010n()
    q, qd, qdd = (jnp.asarray(a) for a in rng.normal(size=(3, 37, 3)))
    chunked = reg._regressor_jit(robot, q, qd, qdd, jnp.dtype(jnp.float64), 16)
    for chunk in (None, 5, 64):
        np.testing.assert_allclose(reg._regressor_jit(robot, q, qd, qdd,
                                                      jnp.dtype(jnp.float64), chunk),
                                   chunked, rtol=1e-13, atol=1e-13)


def test_design_and_condition_batches_per_backend(monkeypatch):
    assert design.random_batch(4040, 3, 100) == design.RANDOM_BATCH
    assert exfit.condition_samples(3, 1000) == 50
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert design.random_batch(1000, 3, 100) == 1000  # all draws at once
    per_draw = 2 * 100 * reg.sample_bytes(3)
    assert design.random_batch(4040, 3, 100) == reg.DEFAULT_MEMORY_BUDGET // per_draw
    per_draw = 2 * 100 * reg.sample_bytes(7)
    assert design.random_batch(4040, 7, 100, memory_budget=10**7) == 10**7 // per_draw
    assert design.random_batch(4040, 7, 100, memory_budget=10**6) == 1  # at least one
    assert exfit.condition_samples(3, 1000) == 1000
    assert exfit.condition_samples(3, 1001) == 1050  # multiples of 50
    small = exfit.condition_samples(7, 10**6, memory_budget=10**6)
    assert small % 50 == 0 and 50 <= small * reg.sample_bytes(7) <= 2 * 10**6


@pytest.mark.parametrize("budget", [0, 10**6 - 1, 2.5e6, True, "1GB"])
def test_bad_memory_budget(budget):
    """A budget under 1 MB (or not an integer number of bytes) is one ValueError naming
    the limit, before anything compiles."""
    robot = sj.robots.rs010n()
    q = np.zeros((4, 3))
    match = r"memory_budget must be an integer number of bytes >= 1 MB \(1000000\)"
    base = sj.base_parameters(robot)
    calls = [
        lambda: sj.regressor(robot, q, q, q, memory_budget=budget),
        lambda: sj.inverse_dynamics(robot, robot.params, q, q, q, memory_budget=budget),
        lambda: base.regressor(q, q, q, memory_budget=budget),
        lambda: exfit.condition_number(base, q, q, q, memory_budget=budget),
        lambda: sj.design_excitation(robot, sj.JointLimits.rs010n(), memory_budget=budget,
                                     search=sj.excitation.DesignSearch(iterations=1),
                                     base=base),
    ]
    for call in calls:
        with pytest.raises(ValueError, match=match):
            call()


def test_runs_batched_per_backend(monkeypatch):
    assert driver._batching("auto", 10) == (1, False)  # in sequence on one CPU device
    assert driver._batching("shard", 10) == ("vmap", True)  # over every device (here one)
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert driver._batching("auto", 10, (10**6, 10**3)) == ("vmap", False)
    # runs that do not fit at once go in the largest chunks that do
    limit, _ = driver.memory_limit(jax.devices()[0])
    flight = limit // 7
    assert driver._batching("auto", 100, (flight, 0)) == (7, False)


def test_runs_that_do_not_fit_fail_before_compiling():
    """The error names the limit; nothing was compiled for it."""
    before = len(driver._COMPILED)
    box = (-np.ones(2), np.ones(2))
    kw = dict(key=jax.random.key(0), iterations=10**6)
    with pytest.raises(ValueError, match=r"batch='vmap': 100000 run\(s\).*more than the "
                                         r"limit of .* GiB \(half the RAM"):
        sj.minimise(lambda x, a: jnp.sum(x**2), sj.BSO(), *box, runs=10**5, batch="vmap",
                    **kw)
    with pytest.raises(ValueError, match="batch=1: 100000 run"):
        sj.minimise(lambda x, a: jnp.sum(x**2), sj.BSO(), *box, runs=10**5, **kw)
    assert len(driver._COMPILED) == before


# ----------------------------------------------------------------------------- precision
def _precisions(fn, *args):
    """The precision of every dot_general in ``fn``'s jaxpr (nested jaxprs included)."""
    found = []

    def walk(jaxpr):
        for eqn in jaxpr.eqns:
            if eqn.primitive.name == "dot_general":
                found.append(eqn.params["precision"])
            for sub in jax.extend.core.jaxprs_in_params(eqn.params):
                walk(sub)

    walk(jax.make_jaxpr(fn)(*args).jaxpr)
    return found


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_l1_products_ask_for_full_precision(monkeypatch, backend):
    """Every product of Eq. 17 (a population's, a few candidates', the row sums) asks for
    HIGHEST, so float32 is not computed with TF32 or bfloat16 passes on a GPU or TPU."""
    monkeypatch.setattr(jax, "default_backend", lambda: backend)
    prob, _, _ = l1_problem()
    assert (prob.W_constant is None) == (backend == "gpu")
    prob = jax.tree.map(lambda a: a.astype(jnp.float32), prob)
    highest = (jax.lax.Precision.HIGHEST, jax.lax.Precision.HIGHEST)
    for rows in (3, 60):
        X = jnp.ones((rows, 5), jnp.float32)
        for fn, args in ((prob.evaluate, (X,)),
                         (lambda X, V: prob.evaluate_with_antennae(X, V, 0.1), (X, X))):
            found = _precisions(fn, *args)
            assert found and all(p == highest for p in found), found


def test_dynamics_and_trajectory_products_ask_for_full_precision():
    robot = sj.robots.rs010n()
    q = jnp.zeros((4, 3), jnp.float32)
    highest = (jax.lax.Precision.HIGHEST, jax.lax.Precision.HIGHEST)
    found = _precisions(lambda q: reg.unchecked_regressor(robot, q, q, q), q)
    found += _precisions(lambda p, q: sj.inverse_dynamics(robot, p, q, q, q),
                         jnp.asarray(robot.params), np.zeros((4, 3)))
    from sedsabso_jax.excitation._trajectory import evaluate
    a = jnp.ones((3, 5), jnp.float32)
    found += _precisions(lambda a, c: evaluate(a, a, a[:, 0], jnp.arange(1.0, 6.0), c, c),
                         a, jnp.ones((7, 5), jnp.float32))
    assert len(found) >= 7 and all(p == highest for p in found), found


# --------------------------------------------------------------------------- lean kernels
@pytest.mark.parametrize("dtype", [jnp.float64, jnp.float32])
def test_uniforms_are_jax_random_uniform_bit_for_bit(dtype):
    """The threefry hash written out (fused by XLA) draws JAX's own numbers."""
    keys = jax.random.split(jax.random.key(3), 24).reshape(12, 2)
    for shape in ((50, 21), (7,), (3, 1, 4), ()):
        ours = jax.jit(jax.vmap(lambda k, shape=shape: uniforms(k, shape, dtype)))(keys)
        ref = jax.vmap(jax.vmap(lambda k, shape=shape: jax.random.uniform(k, shape, dtype)))(keys)
        np.testing.assert_array_equal(np.asarray(ours), np.asarray(ref))
    other = jax.random.split(jax.random.key(3, impl="rbg"))  # not threefry: JAX's path
    np.testing.assert_array_equal(uniforms(other, (4,), dtype),
                                  jax.vmap(lambda k: jax.random.uniform(k, (4,), dtype))(other))


@pytest.mark.parametrize("rows", [3, 20])
def test_eq_17_paths_give_its_values(monkeypatch, rows):
    """A few members (through W^T) and a population (fused product and sum, W a constant
    of the compiled code or an argument) give Eq. 17 and the antenna differences."""
    prob, lo, hi = l1_problem()
    rng = np.random.default_rng(1)
    X, V = (rng.uniform(lo, hi, (rows, 5)) for _ in range(2))
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    f = lambda X: np.abs(X @ W.T - tau).sum(1)  # noqa: E731
    monkeypatch.setattr(l1, "CONSTANT_BYTES", 0)
    for p in (prob, sj.L1Residual(W, tau)):  # W a constant, then an argument
        out = jax.jit(lambda X, V, p=p: (p.evaluate(X), *p.evaluate_with_antennae(X, V, 0.3)))(
            jnp.asarray(X), jnp.asarray(V))
        np.testing.assert_allclose(out[0], f(X), rtol=1e-13)
        np.testing.assert_allclose(out[1], f(X), rtol=1e-13)
        np.testing.assert_allclose(out[2], f(X + 0.3 * V) - f(X - 0.3 * V), rtol=1e-10,
                                   atol=1e-9)
        np.testing.assert_array_equal(out[3], 0)
    assert prob.W_constant is not None and sj.L1Residual(W, tau).W_constant is None


def test_a_constant_w_compiles_once_per_w():
    """W kept as a constant of the compiled code is compared by content: the same W with
    another tau reuses the compiled code; another W compiles anew."""
    prob, lo, hi = l1_problem(m=200)
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    kw = dict(key=jax.random.key(0), iterations=5)
    solver = sj.LDWPSO(population_size=11)
    sj.minimise(prob, solver, lo, hi, **kw)
    assert sj.minimise(sj.L1Residual(W, tau + 1.0), solver, lo, hi, **kw).compile_s == 0.0
    assert sj.minimise(sj.L1Residual(2 * W, tau), solver, lo, hi, **kw).compile_s > 0.0


PINNED_L1 = {
    "SEDSABSO": ((61.712366449354946, 94.42233998355239), 0.2017790789936301, 2836),
    "BSO": ((22.320014881118126, 19.299945731961678), 0.1933232195842163, 2420),
    "LDWPSO": ((15.760871960914638, 9.248628917793711), 0.21786833858241939, 820),
}


def _small(name):
    return {"SEDSABSO": sj.SEDSABSO(population_size=40, n_phases=2),
            "BSO": sj.BSO(population_size=20), "LDWPSO": sj.LDWPSO(population_size=20)}[name]


@pytest.mark.parametrize("name", PINNED_L1)
def test_seeded_eq_17_runs_are_pinned(name):
    """The lean kernels on Eq. 17 (W a constant of the compiled code, draws before each
    phase's loop, antennae carried as one number per beetle): 2 runs of 40 iterations,
    key 42, as measured on the project's 2-core AMD EPYC VM (jax 0.10.2). 1e-9 relative
    allows for the order of floating-point sums on other CPUs."""
    prob, lo, hi = l1_problem()
    f_runs, x00, n_eval = PINNED_L1[name]
    r = sj.minimise(prob, _small(name), lo, hi, key=jax.random.key(42), iterations=40, runs=2)
    np.testing.assert_allclose(np.asarray(r.f), f_runs, rtol=1e-9)
    assert float(np.asarray(r.x)[0, 0]) == pytest.approx(x00, rel=1e-9)
    assert int(r.n_evaluations[0]) == n_eval


def test_the_accelerator_path_gives_the_cpu_numbers(gpu):
    """With the backend saying "gpu": runs vmapped, draws inside the loop, Eq. 17 in one
    piece with x and v in one stacked product and plain row sums, N(t)'s re-ranking by a
    select. Same runs as the pinned CPU ones, the same numbers up to rounding."""
    prob, lo, hi = l1_problem()
    for name in PINNED_L1:
        f_runs, x00, n_eval = PINNED_L1[name]
        r = sj.minimise(prob, _small(name), lo, hi, key=jax.random.key(42), iterations=40,
                        runs=2)
        np.testing.assert_allclose(np.asarray(r.f), f_runs, rtol=1e-8)
        assert float(np.asarray(r.x)[0, 0]) == pytest.approx(x00, rel=1e-8)
        assert int(r.n_evaluations[0]) == n_eval


@pytest.mark.parametrize("name", PINNED_L1)
def test_every_nonfinite_evaluation_is_counted(name):
    """NaN everywhere: every evaluation (initial population, positions, antennae, annealing
    candidates) is non-finite, so the count equals the evaluations, across the phases'
    changes of slots (counted per slot inside the loop, summed at each change)."""
    r = sj.minimise(lambda x, a: jnp.nan * jnp.sum(x), _small(name), -np.ones(3),
                    np.ones(3), key=jax.random.key(0), iterations=30)
    assert int(r.n_nonfinite) == int(r.n_evaluations) > 0
