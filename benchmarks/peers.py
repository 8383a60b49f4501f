"""mealpy's and evosax's particle swarms on the paper's identification problem: same
process, same fitness (Eq. 17, ``f(p) = sum |W p - tau|``), same budget (50 particles,
``iterations`` generations after the initial swarm) as the rows of :mod:`benchmarks.swarms`.

- mealpy ``OriginalPSO`` (numpy, one particle's fitness per call, as mealpy evaluates it):
  ``w = 0.8, c1 = c2 = 2``; mealpy's own bound handling (a coordinate that leaves the box
  is redrawn uniformly inside it) and its own velocity limit ``0.5 (ub - lb)``. Note that
  mealpy's original PSO moves a particle only when the new position is better than its
  current one.
- evosax ``algorithms.PSO`` (JAX): ``inertia_coeff = 0.8, cognitive_coeff =
  social_coeff = 2``; initial swarm uniform in the box, positions clipped to the box
  before each evaluation (evosax has no bounds; the clipped positions are what it is
  told). The whole run (init, ``iterations`` x ask / clip / fitness / tell) is one jitted
  ``lax.scan``; compile time apart, runs timed after compilation; many runs per call
  are the run vmapped over keys (:func:`evosax_many`). ``dtype="float32"`` is traced
  and compiled with JAX's 64-bit mode off, so everything is float32: under x64 evosax
  draws its r1, r2 in float64 and the velocity, the positions and the fitness's product
  follow (the earlier "float32" row computed in float64 and was 2.4-2.7x slower than
  float32). evosax draws one r1 and one r2 per particle (shared across dimensions).

Neither library is a dependency of sedsabso-jax. evosax 0.3.2 (with flax 0.12.8, optax)
resolves with jax 0.10 / numpy 2 as is. mealpy 3.0.3 declares ``numpy<=1.26.0``, which
would pull numpy 1.26 and with it jax 0.7, but it runs on numpy 2: install it without its
dependencies (it needs pandas at import; opfunu only appears in its docstrings):

    pip install "evosax>=0.3.2" pandas
    pip install --no-deps "mealpy==3.0.3"
    python -m benchmarks.peers [--iterations 600] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

PARTICLES = 50
W_INERTIA, C1, C2 = 0.8, 2.0, 2.0
SEEDS = (1, 2, 3, 4, 5)


def timing(times):
    """Time per run: the fastest of the seeds (the shared machine only ever adds time) and
    the median beside it."""
    return {"time_per_run_s": float(np.min(times)),
            "time_per_run_median_s": float(np.median(times))}


def mealpy_row(W, tau, lo, hi, true, iterations, particles=PARTICLES):
    """mealpy 3 ``OriginalPSO``; raises ImportError when mealpy is not installed."""
    from mealpy import FloatVar
    from mealpy.swarm_based.PSO import OriginalPSO

    W, tau = np.asarray(W, dtype=float), np.asarray(tau, dtype=float)
    lo, hi, true = (np.asarray(a, dtype=float) for a in (lo, hi, true))

    def fitness(p):
        return float(np.abs(W @ p - tau).sum())

    def run(seed, epochs):
        problem = {"bounds": FloatVar(lb=lo, ub=hi, name="p"), "obj_func": fitness,
                   "minmax": "min", "log_to": None}
        model = OriginalPSO(epoch=epochs, pop_size=particles, c1=C1, c2=C2, w=W_INERTIA)
        t0 = time.perf_counter()
        best = model.solve(problem, seed=seed)
        return time.perf_counter() - t0, best.target.fitness, np.asarray(best.solution)

    run(0, 1)  # warm-up (imports, first calls)
    times, fs, errs = [], [], []
    for seed in SEEDS:
        t, f, x = run(seed, iterations)
        times.append(t)
        fs.append(f)
        errs.append(np.abs(x - true).max())
    return {"method": "mealpy OriginalPSO", "dtype": "float64", "compile_s": 0.0,
            **timing(times), "fitness_mean": float(np.mean(fs)),
            "max_abs_error_mean": float(np.mean(errs))}


def evosax_compiled(W, tau, lo, hi, iterations, particles=PARTICLES, dtype="float64",
                    runs=None):
    """``(executable, compile_s)`` of evosax's PSO run ``key -> (best f, best x)`` (vmapped
    over ``runs`` keys when given), traced and compiled with 64-bit mode on for float64
    and off for float32. Raises ImportError without evosax."""
    import jax
    import jax.numpy as jnp
    from evosax.algorithms import PSO

    with jax.enable_x64(dtype == "float64"):
        dt = jnp.dtype(dtype)
        W, tau = jnp.asarray(W, dt), jnp.asarray(tau, dt)
        lo, hi = jnp.asarray(lo, dt), jnp.asarray(hi, dt)

        def fitness(X):
            return jnp.abs(X @ W.T - tau).sum(-1)

        strategy = PSO(population_size=particles, solution=jnp.zeros(lo.shape, dt))
        params = strategy.default_params.replace(inertia_coeff=W_INERTIA, cognitive_coeff=C1,
                                                 social_coeff=C2)

        def run(key):
            key, k_pop, k_init = jax.random.split(key, 3)
            x0 = jax.random.uniform(k_pop, (particles, lo.size), dt, lo, hi)
            state = strategy.init(k_init, x0, fitness(x0), params)

            def step(state, key):
                k_ask, k_tell = jax.random.split(key)
                x, state = strategy.ask(k_ask, state, params)
                x = jnp.clip(x, lo, hi)
                state, _ = strategy.tell(k_tell, x, fitness(x), state, params)
                return state, None

            state, _ = jax.lax.scan(step, state, jax.random.split(key, iterations))
            return state.best_fitness, state.best_solution

        fn = run if runs is None else jax.vmap(run)
        key = jax.random.key(0) if runs is None else jax.random.split(jax.random.key(0), runs)
        t0 = time.perf_counter()
        compiled = jax.jit(fn).lower(key).compile()
        return compiled, time.perf_counter() - t0


def evosax_many(W, tau, lo, hi, iterations, runs, dtype="float64", particles=PARTICLES):
    """``(compile_s, seconds for one call of runs runs)``: evosax's PSO vmapped over
    ``runs`` keys, one call timed after compilation (and a warm-up call for fewer than
    100 runs, where it matters)."""
    import jax

    compiled, compile_s = evosax_compiled(W, tau, lo, hi, iterations, particles, dtype, runs)
    if runs < 100:
        jax.block_until_ready(compiled(jax.random.split(jax.random.key(1), runs)))
    keys = jax.random.split(jax.random.key(2), runs)
    t0 = time.perf_counter()
    jax.block_until_ready(compiled(keys))
    return compile_s, time.perf_counter() - t0


def evosax_row(W, tau, lo, hi, true, iterations, particles=PARTICLES, dtype="float64"):
    """evosax ``algorithms.PSO`` in one jitted scan; raises ImportError without evosax."""
    import jax

    dt = np.dtype(dtype)
    compiled, compile_s = evosax_compiled(W, tau, lo, hi, iterations, particles, dtype)
    jax.block_until_ready(compiled(jax.random.key(0)))  # warm-up
    times, fs, errs = [], [], []
    for seed in SEEDS:
        t0 = time.perf_counter()
        f, x = jax.block_until_ready(compiled(jax.random.key(seed)))
        times.append(time.perf_counter() - t0)
        assert f.dtype == dt, (f.dtype, dt)  # float32 is float32 throughout
        fs.append(float(f))
        errs.append(np.abs(np.asarray(x, dtype=float) - true).max())
    return {"method": "evosax PSO", "dtype": dt.name, "compile_s": compile_s,
            **timing(times), "fitness_mean": float(np.mean(fs)),
            "max_abs_error_mean": float(np.mean(errs))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iterations", type=int, default=600)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    import jax

    from benchmarks.problems import rs010n_problem

    jax.config.update("jax_enable_x64", True)
    prob, lo, hi, true = rs010n_problem()
    W, tau = np.asarray(prob.W), np.asarray(prob.tau)
    rows = []
    evosax32 = lambda *a: evosax_row(*a, dtype="float32")  # noqa: E731
    for name, fn in (("mealpy", mealpy_row), ("evosax", evosax_row), ("evosax", evosax32)):
        try:
            rows.append(fn(W, tau, lo, hi, true, args.iterations))
        except ImportError as exc:
            print(f"{name} not available ({exc}); see this module's docstring")
    print(f"RS010N, {W.shape[0]} torque rows, {W.shape[1]} base parameters, "
          f"{PARTICLES} particles, {args.iterations} iterations")
    print(f"{'method':24s} {'dtype':7s} {'compile_s':>9s} {'run_s':>7s} {'f mean':>9s} "
          f"{'max|err|':>8s}")
    for r in rows:
        print(f"{r['method']:24s} {r['dtype']:7s} {r['compile_s']:9.2f} "
              f"{r['time_per_run_s']:7.3f} {r['fitness_mean']:9.3g} "
              f"{r['max_abs_error_mean']:8.3g}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"iterations": args.iterations, "rows": rows}, fh, indent=2)


if __name__ == "__main__":
    main()
