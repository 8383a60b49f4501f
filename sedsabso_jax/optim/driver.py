"""The driver: :func:`minimise` runs any swarm (:class:`~.swarm.AbstractSwarm`) inside one
jit-compiled function: ``lax.scan`` over iterations, the population evaluated at once
(``vmap`` for a black-box fitness, one matrix product for Eq. 17), many runs per call over
PRNG keys, runs spread over devices with ``jax.sharding``; compiled code cached.

A variable population (SEDSABSO's Eq. 15-16) runs in phases of static, shrinking slot
counts (:func:`~.swarm.phases`), so the work follows the active count.
"""

from __future__ import annotations

import contextvars
import math
import os
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .box import check_bounds
from .external import Evosax
from .fitness import as_fitness
from .result import Result
from .swarm import AbstractSwarm, phases, set_active, shrink


def iteration_randomness(solver, key, iterations: int, dim: int, dtype):
    """Every iteration's randomness, derived before the loop: the chain
    ``key, sub = split(key)`` gives iteration t its key ``sub``, from which
    ``solver.randomness`` derives keys (or small draws), vectorised over the iterations.
    The population's draws (``solver.draw``) are then made per phase before its loop
    (:func:`_single_run`) or inside it. The numbers are the same either way, and the same
    as drawing each inside the loop."""
    def chain(key, _):
        key, sub = jax.random.split(key)
        return key, sub

    _, subs = jax.lax.scan(chain, key, None, length=iterations)
    return jax.vmap(lambda k: solver.randomness(k, dim, dtype))(subs)


#: Largest pre-drawn randomness per phase of one run (bytes), see :func:`_single_run`.
PREDRAW_BYTES = 32 * 2**20
#: Runs traced together in one vmapped call (1 while a run is traced on its own).
_IN_FLIGHT = contextvars.ContextVar("in_flight", default=1)


def _predraws(solver, randomness, shape, dtype, length: int) -> bool:
    """Whether one phase's population draws are made before its loop: on the CPU, for a
    run traced on its own, when they take at most :data:`PREDRAW_BYTES`. Inside the loop
    XLA fuses the hash into each fusion that reads a draw, and computes it there again:
    with ``PREDRAW_BYTES = 0`` a float64 run took 56 % longer for LDWPSO (122 vs 79 ms),
    32 % for BSO (184 vs 140 ms), 23 % for SEDSABSO (213 vs 172 ms) (2-core AMD EPYC,
    same process, fastest of 9 seeds). On an accelerator the draws stay in the loop,
    where recomputing them is cheap and memory is not spent on them."""
    if jax.default_backend() != "cpu" or _IN_FLIGHT.get() > 1:
        return False
    one = jax.tree.map(lambda r: r[0], randomness)
    out = jax.eval_shape(lambda r: solver.draw(r, shape, dtype), one)
    size = sum(math.prod(o.shape) * o.dtype.itemsize for o in jax.tree.leaves(out))
    return size * length <= PREDRAW_BYTES


def _rerank(state, n_active, drop):
    """``set_active(state, n_active)`` where ``drop`` (N(t) falls at this iteration, known
    from the static schedule): a select on accelerators, where a ``lax.cond`` would read
    its predicate back to the host every iteration; a ``lax.cond`` on the CPU, which
    skips the sort when nothing falls."""
    if jax.default_backend() == "cpu":
        return jax.lax.cond(drop, set_active, lambda s, n: s, state, n_active)
    return eqx.tree_at(lambda s: s.active, state,
                       jnp.where(drop, set_active(state, n_active).active, state.active))


def _single_run(solver: AbstractSwarm, fitness, lower, upper, key, iterations: int):
    """One run: the phases of :func:`~.swarm.phases`, each a ``lax.scan``. Where N(t)
    falls is static: the active count before iteration t is N(t - 1) (N(a) after a phase
    starting at a has shrunk the slots), so the history of N is the schedule itself."""
    sched = solver.schedule(iterations)
    key, k0 = jax.random.split(key)
    state = set_active(solver.init(fitness, lower, upper, k0), int(sched[0]))
    dim, dtype = lower.shape[0], lower.dtype
    rand = iteration_randomness(solver, key, iterations, dim, dtype)
    hist_f = []
    for a, b, slots in phases(sched, solver.n_phases):
        state = shrink(state, slots)
        before = np.concatenate([[min(sched[max(a - 1, 0)], slots)], sched[a:b - 1]])
        drops = sched[a:b] < before  # N(t) falls: re-rank, the worst leave
        shape = (slots, dim)
        phase_rand = jax.tree.map(lambda r, a=a, b=b: r[a:b], rand)
        predraw = _predraws(solver, phase_rand, shape, dtype, b - a)
        if predraw:
            phase_rand = jax.vmap(lambda r, shape=shape: solver.draw(r, shape, dtype))(
                phase_rand)

        def body(state, inp, predraw=predraw, shape=shape, rerank=bool(drops.any())):
            t, n_active, drop, r = inp
            if rerank:
                state = _rerank(state, n_active, drop)
            draws = r if predraw else solver.draw(r, shape, dtype)
            state = solver.step(fitness, state, t, iterations, lower, upper, draws)
            return state, state.best_f

        inputs = (jnp.arange(a, b), jnp.asarray(sched[a:b], jnp.int32), jnp.asarray(drops),
                  phase_rand)
        state, fh = jax.lax.scan(body, state, inputs)
        hist_f.append(fh)
    return (state.best_x, state.best_f, jnp.concatenate(hist_f), jnp.asarray(sched, jnp.int32),
            state.sa_accepted, state.n_evaluations, state.nonfinite_total)


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
    if isinstance(solver, Evosax):
        return solver.single_run(fitness, lower, upper, key, iterations)
    return _single_run(solver, fitness, lower, upper, key, iterations)


def _run_many(static, solver_dyn, fitness, lower, upper, keys, n_runs):
    """All runs, one per key. In sequence (batch 1), only the first ``n_runs`` are
    computed (the rest of the output stays zero): the same executable then times a
    single run without a second compilation."""
    one = lambda k: _run_one(static, solver_dyn, fitness, lower, upper, k)  # noqa: E731
    batch = static[2]
    if batch == "vmap" or batch > 1:
        token = _IN_FLIGHT.set(keys.shape[0] if batch == "vmap" else batch)
        try:
            if batch == "vmap":
                return jax.vmap(one)(keys)
            return jax.lax.map(one, keys, batch_size=batch)  # chunks of vmapped runs
        finally:
            _IN_FLIGHT.reset(token)

    def body(i, out):
        return jax.tree.map(lambda o, r: o.at[i].set(r), out, one(keys[i]))

    shapes = jax.eval_shape(one, keys[0])
    out = jax.tree.map(lambda a: jnp.zeros(keys.shape[:1] + a.shape, a.dtype), shapes)
    return jax.lax.fori_loop(0, n_runs, body, out)


def _batching(batch, runs: int, sharded: bool, run_bytes: tuple[int, int] = (0, 0)):
    """How ``runs`` runs share one compiled call: ``"vmap"`` (all at once) or an int k
    (``lax.map`` in chunks of k vmapped runs). ``"auto"``: on a single CPU device runs in
    sequence (k = 1), which compiles fastest and lets one run be timed through the same
    executable (:func:`time_one_of_many`); on accelerators and when sharded over several
    devices vmap, or on one accelerator the largest chunks that fit :func:`memory_limit`
    when all runs at once would not. ``run_bytes``: a run's memory while in flight and
    its output (:func:`run_bytes`). Runs that do not fit (an explicit ``"vmap"`` or
    chunk, or one run alone) raise ValueError naming the limit, before anything
    compiles. For throughput on the CPU, chunks of 5 measured best (2-core CPU, SEDSABSO,
    10 runs, fastest of 3: float64 5.3 s vs 6.4 s in sequence and 6.6 s all vmapped;
    float32 2.6 / 3.5 / 3.0 s; compilation 2-4 s longer)."""
    devices = jax.devices()
    per_device = math.ceil(runs / len(devices)) if sharded else runs
    limit, where = memory_limit(devices[0])
    flight, out = run_bytes
    need = lambda k: k * flight + per_device * out  # noqa: E731
    fits = lambda k: limit is None or need(k) <= limit  # noqa: E731

    def too_big(k, what):
        return ValueError(
            f"{what}: {per_device} run(s) with {k} in flight need about "
            f"{need(k) / 2**30:.3g} GiB, more than the limit of {limit / 2**30:.3g} GiB "
            f"({where}); use fewer runs or a smaller batch=k")

    if batch == "auto":
        if jax.default_backend() == "cpu" and not sharded:
            batch = 1
        elif fits(per_device) or sharded:
            batch = "vmap"
        else:
            batch = max(1, int((limit - per_device * out) // max(flight, 1)))
    if batch == "vmap":
        if not fits(per_device):
            raise too_big(per_device, "batch='vmap'")
        return batch
    if isinstance(batch, (int, np.integer)) and not isinstance(batch, bool) and batch >= 1:
        if sharded:
            raise ValueError("batch must be 'vmap' or 'auto' when runs are sharded over "
                             "several devices (shard=False to run them on one)")
        batch = int(min(batch, runs))
        if not fits(batch):
            raise too_big(batch, f"batch={batch}")
        return batch
    raise ValueError(f"batch must be 'auto', 'vmap' or an integer >= 1, got {batch!r}")


def memory_limit(device) -> tuple[int | None, str]:
    """``(bytes, what)``: how much memory runs in flight may take on ``device``: half of
    its memory (``memory_stats()["bytes_limit"]`` on a GPU or TPU; the machine's RAM for
    the CPU), the rest left to XLA's own buffers and everything else. ``None`` when
    unknown."""
    stats = None
    try:
        stats = device.memory_stats()
    except Exception:  # noqa: BLE001 - not every backend implements it
        pass
    if stats and stats.get("bytes_limit"):
        total, what = int(stats["bytes_limit"]), f"half of {device.device_kind}'s memory"
    elif device.platform == "cpu" and hasattr(os, "sysconf"):
        total, what = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"), "half the RAM"
    else:
        return None, "unknown"
    return total // 2, f"{what}, {total / 2**30:.3g} GiB"


def run_bytes(solver, fitness, dim: int, dtype, iterations: int) -> tuple[int, int]:
    """Upper estimates, in bytes, of ``(one run's memory while in flight, its output)``:
    the population's arrays of the fitness's size (Eq. 17: members x m residuals, about
    6 live at once without blocking), its state and per-iteration randomness; the output
    is the run's history. For a black box, what ``fn`` allocates inside is not
    counted."""
    itemsize = jnp.dtype(dtype).itemsize
    slots = getattr(solver, "n_slots", None)
    if slots is None:  # another kind of solver (an evosax strategy): its population
        population = getattr(solver, "population", None)
        slots = population(dim) if callable(population) else 1
    m = getattr(getattr(fitness, "tau", None), "shape", (dim,))[0]
    flight = (6 * slots * max(m, dim) * itemsize + 12 * slots * dim * itemsize
              + iterations * 16 * (dim + 8))  # keys and small draws per iteration
    return int(flight), int(iterations * (itemsize + 4) + 4 * dim * itemsize)


def _prepare(fitness, solver, lower, upper, key, iterations, runs, args, dtype, shard,
             batch="auto"):
    """Check everything and build the compiled function's arguments (nothing runs)."""
    if not isinstance(solver, (AbstractSwarm, Evosax)):
        raise TypeError(f"solver must be a swarm (SEDSABSO, BSO, LDWPSO or another "
                        f"AbstractSwarm) or an Evosax strategy, got {type(solver).__name__}")
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
    devices = jax.devices()
    sharded = shard and len(devices) > 1
    static_key = (static, int(iterations), _batching(
        batch, runs, sharded, run_bytes(solver, fitness, lo.shape[0], dtype, iterations)))
    keys = jax.random.split(key, runs)
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
    """Minimise ``fitness`` over the box ``[lower, upper]`` with a swarm (or an evosax
    strategy through :class:`~.external.Evosax`).

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
    method = f"evosax {solver.name}" if isinstance(solver, Evosax) else type(solver).__name__
    return Result(method=method, x=x, f=f, history_f=hf, history_n=hn,
                  sa_accepted=sa, n_evaluations=ne, n_nonfinite=nn, compile_s=compile_s,
                  run_s=run_s)
