"""The driver: :func:`minimise` runs any swarm (:class:`~.swarm.AbstractSwarm`) inside one
jit-compiled function: ``lax.scan`` over iterations, the population evaluated at once
(``vmap`` for a black-box fitness, one matrix product for Eq. 17), many runs per call over
PRNG keys, runs spread over devices with ``jax.sharding``; compiled code cached.

A variable population (SEDSABSO's Eq. 15-16) runs in phases of static, shrinking slot
counts (:func:`~.swarm.phases`), so the work follows the active count.
"""

from __future__ import annotations

import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .box import check_bounds
from .fitness import as_fitness
from .result import Result
from .swarm import AbstractSwarm, phases, set_active, shrink


def iteration_randomness(solver, key, iterations: int, dim: int, dtype):
    """Every iteration's randomness, derived before the loop: the chain
    ``key, sub = split(key)`` gives iteration t its key ``sub``, from which
    ``solver.randomness`` derives keys (or small draws), vectorised over the iterations.
    Inside the loop a step then makes one batched draw for the population: on the CPU
    every ``jax.random`` call is a small loop of its own, a fixed cost per iteration
    (SEDSABSO made nine per iteration, now one). The numbers are the same as drawing
    each inside the loop."""
    def chain(key, _):
        key, sub = jax.random.split(key)
        return key, sub

    _, subs = jax.lax.scan(chain, key, None, length=iterations)
    return jax.vmap(lambda k: solver.randomness(k, dim, dtype))(subs)


def _single_run(solver: AbstractSwarm, fitness, lower, upper, key, iterations: int):
    sched = solver.schedule(iterations)
    key, k0 = jax.random.split(key)
    state = set_active(solver.init(fitness, lower, upper, k0), int(sched[0]))
    hist_f, hist_n = [], []
    keys = iteration_randomness(solver, key, iterations, lower.shape[0], lower.dtype)
    for a, b, slots in phases(sched, solver.n_phases):
        state = shrink(state, slots)
        n_t = jnp.asarray(sched[a:b], jnp.int32)
        constant = bool(np.all(sched[a:b] == slots))  # every slot active: nothing to drop

        def body(state, inp, constant=constant):
            t, n_active, key = inp
            if not constant:  # re-rank only when N(t) falls
                state = jax.lax.cond(n_active < jnp.sum(state.active), set_active,
                                     lambda s, n: s, state, n_active)
            state = solver.step(fitness, state, t, iterations, lower, upper, key)
            return state, (state.best_f, jnp.sum(state.active, dtype=jnp.int32))

        phase_keys = jax.tree.map(lambda k: k[a:b], keys)
        state, (fh, nh) = jax.lax.scan(body, state, (jnp.arange(a, b), n_t, phase_keys))
        hist_f.append(fh)
        hist_n.append(nh)
    return (state.best_x, state.best_f, jnp.concatenate(hist_f), jnp.concatenate(hist_n),
            state.sa_accepted, state.n_evaluations, state.n_nonfinite)


_COMPILED: dict = {}


def _compiled(fn, static, *args):
    """AOT-compile ``fn`` once per (static configuration, argument structure); return the
    executable and the seconds spent compiling (0 when reused)."""
    leaves, treedef = jax.tree_util.tree_flatten(args)
    spec = tuple((jnp.shape(x), jnp.result_type(x), getattr(x, "sharding", None))
                 for x in leaves)
    key = (fn, static, treedef, spec)
    if key in _COMPILED:
        return _COMPILED[key], 0.0
    t0 = time.perf_counter()
    exe = jax.jit(fn, static_argnums=(0,)).lower(static, *args).compile()
    _COMPILED[key] = exe
    return exe, time.perf_counter() - t0


def _run_one(static, solver_dyn, fitness, lower, upper, key):
    solver_static, iterations = static[:2]
    solver = eqx.combine(solver_dyn, solver_static)
    return _single_run(solver, fitness, lower, upper, key, iterations)


def _run_many(static, solver_dyn, fitness, lower, upper, keys, n_runs):
    """All runs, one per key. In sequence (batch 1), only the first ``n_runs`` are
    computed (the rest of the output stays zero): the same executable then times a
    single run without a second compilation."""
    one = lambda k: _run_one(static, solver_dyn, fitness, lower, upper, k)  # noqa: E731
    batch = static[2]
    if batch == "vmap":
        return jax.vmap(one)(keys)
    if batch > 1:
        return jax.lax.map(one, keys, batch_size=batch)  # chunks of vmapped runs

    def body(i, out):
        return jax.tree.map(lambda o, r: o.at[i].set(r), out, one(keys[i]))

    shapes = jax.eval_shape(one, keys[0])
    out = jax.tree.map(lambda a: jnp.zeros(keys.shape[:1] + a.shape, a.dtype), shapes)
    return jax.lax.fori_loop(0, n_runs, body, out)


def _batching(batch, runs: int, sharded: bool):
    """How ``runs`` runs share one compiled call: ``"vmap"`` (all at once) or an int k
    (``lax.map`` in chunks of k vmapped runs). ``"auto"``: vmap on accelerators and when
    sharded over several devices; on a single CPU device runs in sequence (k = 1), which
    compiles fastest and lets one run be timed through the same executable
    (:func:`time_one_of_many`). For throughput on the CPU, chunks of 5 measured best
    (2-core CPU, SEDSABSO, 10 runs, fastest of 3: float64 5.3 s vs 6.4 s in sequence and
    6.6 s all vmapped; float32 2.6 / 3.5 / 3.0 s; compilation 2-4 s longer)."""
    if batch == "auto":
        cpu = jax.default_backend() == "cpu"
        return 1 if cpu and not sharded else "vmap"
    if batch == "vmap":
        return batch
    if isinstance(batch, (int, np.integer)) and not isinstance(batch, bool) and batch >= 1:
        if sharded:
            raise ValueError("batch must be 'vmap' or 'auto' when runs are sharded over "
                             "several devices (shard=False to run them on one)")
        return int(min(batch, runs))
    raise ValueError(f"batch must be 'auto', 'vmap' or an integer >= 1, got {batch!r}")


def _prepare(fitness, solver, lower, upper, key, iterations, runs, args, dtype, shard,
             batch="auto"):
    """Check everything and build the compiled function's arguments (nothing runs)."""
    if not isinstance(solver, AbstractSwarm):
        raise TypeError(f"solver must be a swarm (SEDSABSO, BSO, LDWPSO or another "
                        f"AbstractSwarm), got {type(solver).__name__}")
    if not isinstance(iterations, (int, np.integer)) or iterations < 1:
        raise ValueError(f"iterations must be an integer >= 1, got {iterations!r}")
    if runs is not None and (not isinstance(runs, (int, np.integer)) or runs < 1):
        raise ValueError(f"runs must be an integer >= 1 or None, got {runs!r}")
    solver.check()
    fitness = as_fitness(fitness, args)
    dim = getattr(fitness, "dim", None)
    lower, upper = check_bounds(lower, upper, dim)
    dtype = jnp.dtype(dtype)
    if dtype not in (jnp.dtype(jnp.float32), jnp.dtype(jnp.float64)):
        raise ValueError(f"dtype must be float32 or float64, got {dtype}")
    cast = lambda a: a.astype(dtype) if eqx.is_inexact_array(a) else a  # noqa: E731
    fitness = jax.tree.map(cast, fitness)
    lo, hi = jnp.asarray(lower, dtype), jnp.asarray(upper, dtype)
    dyn, static = eqx.partition(solver, eqx.is_array)
    dyn = jax.tree.map(cast, dyn)
    if runs is None:
        return _run_one, (static, int(iterations)), (dyn, fitness, lo, hi, key)
    keys = jax.random.split(key, runs)
    devices = jax.devices()
    sharded = shard and len(devices) > 1
    static_key = (static, int(iterations), _batching(batch, runs, sharded))
    if sharded:
        # pad the runs to a multiple of the device count; the extra runs are dropped
        padded = math.ceil(runs / len(devices)) * len(devices)
        if padded > runs:
            extra = jax.random.split(jax.random.fold_in(key, 1), padded - runs)
            keys = jnp.concatenate([keys, extra])
        mesh = jax.sharding.Mesh(np.array(devices), ("runs",))
        spec = jax.sharding.PartitionSpec("runs")
        keys = jax.device_put(keys, jax.sharding.NamedSharding(mesh, spec))
    return _run_many, static_key, (dyn, fitness, lo, hi, keys, jnp.int32(runs))


def time_one_of_many(fitness, solver: AbstractSwarm, lower, upper, *, key, iterations: int,
                     runs: int, dtype=jnp.float64) -> tuple[float, float]:
    """``(compile_s, run_s)``: the wall time of ONE run through the executable that
    ``minimise(..., runs=runs)`` uses, where that executable runs in sequence (a single
    CPU device), so timing one run costs no compilation of its own; elsewhere the
    single-run executable is compiled and timed."""
    fn, static_key, call_args = _prepare(fitness, solver, lower, upper, key, iterations, runs,
                                         None, dtype, True, "auto")
    if static_key[2] != 1:
        r = minimise(fitness, solver, lower, upper, key=key, iterations=iterations,
                     dtype=dtype)
        return r.compile_s, r.run_s
    exe, compile_s = _compiled(fn, static_key, *call_args)
    one = (*call_args[:-1], jnp.int32(1))
    t0 = time.perf_counter()
    jax.block_until_ready(exe(*one))
    return compile_s, time.perf_counter() - t0


def minimise(fitness, solver: AbstractSwarm, lower, upper, *, key, iterations: int = 600,
             runs: int | None = None, args=None, dtype=jnp.float64, shard: bool = True,
             batch="auto") -> Result:
    """Minimise ``fitness`` over the box ``[lower, upper]`` with a swarm.

    ``fitness``: a callable ``f(x, args) -> scalar`` (evaluated under ``vmap``) or an
    :class:`~sedsabso_jax.L1Residual` (the paper's Eq. 17, evaluated through
    ``W x``). ``key``: a JAX PRNG key (``jax.random.key(seed)``); the same key gives the
    same result. ``runs``: that many independent runs in one compiled call (``vmap`` over
    keys split from ``key``), spread over the available devices when ``shard``; ``batch``
    says how they share the call (see :func:`_batching`: ``"auto"``, ``"vmap"`` or a
    chunk size for ``lax.map``); every choice gives the same numbers up to rounding.
    ``dtype``: float64 or float32 for positions and the fitness data.
    """
    fn, static_key, call_args = _prepare(fitness, solver, lower, upper, key, iterations, runs,
                                         args, dtype, shard, batch)
    exe, compile_s = _compiled(fn, static_key, *call_args)
    t0 = time.perf_counter()
    out = jax.block_until_ready(exe(*call_args))
    if runs is not None:
        out = tuple(o[:runs] for o in out)
    run_s = time.perf_counter() - t0
    x, f, hf, hn, sa, ne, nn = out
    return Result(method=type(solver).__name__, x=x, f=f, history_f=hf, history_n=hn,
                  sa_accepted=sa, n_evaluations=ne, n_nonfinite=nn, compile_s=compile_s,
                  run_s=run_s)
