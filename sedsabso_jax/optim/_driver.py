"""The driver: :func:`minimise` runs any solver of the contract
(:class:`~._solver.AbstractSolver`: the swarms, any evosax strategy) for many runs in one
jit-compiled call: one run per PRNG key, the runs in sequence, in vmapped chunks or all at
once, spread over devices with ``jax.sharding``; compiled code cached, compilation and run
timed apart.

Inside a caller's ``jax.jit`` or ``jax.vmap``, :func:`minimise` is the same computation,
traced into the caller's program (no compilation, timing or sharding of its own).
"""

from __future__ import annotations

import collections
import dataclasses
import math
import os
import time
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.experimental import multihost_utils
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float, Int, PRNGKeyArray

from .. import _x64
from ._box import check_bounds
from ._fitness import Fitness, FitnessLike, as_fitness
from ._result import Result
from ._solver import AbstractSolver

#: How many compiled runs :func:`minimise` keeps (least recently used dropped first).
CACHE_SIZE = 32


class RunConfig(eqx.Module):
    """The static configuration of a compiled call: ``iterations`` per run, how the runs
    share the call (``batch``: None for one run, ``"vmap"`` or a chunk size, see
    :func:`_batching`), and whether a run may make its random draws before its loops
    (``predraw``: a run compiled on its own on the CPU)."""

    iterations: int = eqx.field(static=True)
    batch: str | int | None = eqx.field(static=True, default=None)
    predraw: bool = eqx.field(static=True, default=False)


class CompiledRuns:
    """The compiled calls of :func:`minimise`, one per (configuration, argument
    structure), least recently used dropped beyond ``size``; :func:`clear_compiled`
    empties it."""

    def __init__(self, size: int = CACHE_SIZE):
        self.size = size
        self._calls: collections.OrderedDict = collections.OrderedDict()

    def get(self, fn, config: RunConfig, static, *args):
        """The executable of ``fn(config, static, *args)`` and the seconds spent
        compiling it (0 when reused)."""
        leaves, treedef = jax.tree_util.tree_flatten(args)
        spec = tuple((jnp.shape(x), jnp.result_type(x),
                      x.sharding if isinstance(x, jax.Array) else None) for x in leaves)
        key = (fn, config, static, treedef, spec)
        if key in self._calls:
            self._calls.move_to_end(key)
            return self._calls[key], 0.0
        t0 = time.perf_counter()
        exe = jax.jit(fn, static_argnums=(0, 1)).lower(config, static, *args).compile()
        self._calls[key] = exe
        while len(self._calls) > self.size:
            self._calls.popitem(last=False)
        return exe, time.perf_counter() - t0

    def __len__(self) -> int:
        return len(self._calls)

    def clear(self) -> None:
        self._calls.clear()


_COMPILED = CompiledRuns()


def clear_compiled() -> None:
    """Drop every run :func:`~sedsabso_jax.minimise` compiled (the next call of each
    configuration compiles again), e.g. to free memory in a long session."""
    _COMPILED.clear()


def _run_one(config: RunConfig, solver_static, solver_dyn, fitness, lower, upper, key
             ) -> Result:
    solver = eqx.combine(solver_dyn, solver_static)
    return solver.run(fitness, lower, upper, key, config.iterations, predraw=config.predraw)


def _run_many(config: RunConfig, solver_static, solver_dyn, fitness, lower, upper, keys,
              n_runs) -> Result:
    """All runs, one per key. In sequence (batch 1), only the first ``n_runs`` are
    computed (the rest of the output stays zero): the same executable then times a
    single run without a second compilation."""
    def one(k: PRNGKeyArray) -> Result:
        return _run_one(config, solver_static, solver_dyn, fitness, lower, upper, k)

    if config.batch == "vmap":
        return jax.vmap(one)(keys)
    assert isinstance(config.batch, int)
    if config.batch > 1:
        return jax.lax.map(one, keys, batch_size=config.batch)  # chunks of vmapped runs

    def body(i: Int[Array, ""], out: Result) -> Result:
        return jax.tree.map(lambda o, r: o.at[i].set(r), out, one(keys[i]))

    shapes = jax.eval_shape(one, keys[0])
    out = jax.tree.map(lambda a: jnp.zeros(keys.shape[:1] + a.shape, a.dtype), shapes)
    return jax.lax.fori_loop(0, n_runs, body, out)


#: What ``batch`` of :func:`minimise` may be besides a chunk size.
BATCHES = ("auto", "vmap", "shard")


def _batching(batch, runs: int, run_bytes: tuple[int, int] = (0, 0), traced: bool = False
              ) -> tuple[str | int, bool]:
    """``(mode, sharded)``: how ``runs`` runs share one compiled call. ``mode`` is
    ``"vmap"`` (all at once) or an int k (``lax.map`` in chunks of k vmapped runs);
    ``sharded``: the runs spread over every device (``jax.sharding``, vmapped on each).
    ``batch``: ``"vmap"`` or k on one device; ``"shard"`` over every device; ``"auto"``:
    over every device when there are several, else on a single CPU device in sequence
    (k = 1), which compiles fastest and lets one run be timed through the same executable
    (:func:`time_one_of_many`), on one accelerator vmap, or the largest chunks that fit
    :func:`memory_limit` when all runs at once would not. Inside a caller's
    transformation (``traced``) nothing is sharded. ``run_bytes``: a run's memory while
    in flight and its output (:func:`run_bytes`). Runs that do not fit (an explicit
    ``"vmap"`` or chunk, or one run alone) raise ValueError naming the limit, before
    anything compiles. For throughput on the CPU, chunks of a few runs may beat the
    sequence (``docs/explanation/swarms-kernels.md``)."""
    chunk = isinstance(batch, (int, np.integer)) and not isinstance(batch, bool) and batch >= 1
    if not chunk and batch not in BATCHES:
        raise ValueError(f"batch must be 'auto', 'vmap', 'shard' or an integer >= 1, got "
                         f"{batch!r}")
    if batch == "shard" and traced:
        raise ValueError("batch='shard' spreads the runs over the devices, which a call "
                         "inside jax.jit or jax.vmap cannot: use 'auto', 'vmap' or k")
    devices = jax.devices()
    sharded = batch == "shard" or (batch == "auto" and len(devices) > 1 and not traced)
    per_device = math.ceil(runs / len(devices)) if sharded else runs
    limit, where = memory_limit(devices[0])
    flight, out = run_bytes
    need = lambda k: k * flight + per_device * out  # noqa: E731
    fits = lambda k: limit is None or need(k) <= limit  # noqa: E731

    def too_big(k: int, what: str) -> ValueError:
        return ValueError(
            f"{what}: {per_device} run(s) with {k} in flight need about "
            f"{need(k) / 2**30:.3g} GiB, more than the limit of {limit / 2**30:.3g} GiB "  # type: ignore[operator]
            f"({where}); use fewer runs or a smaller batch=k")

    if batch == "auto" and not sharded:
        if jax.default_backend() == "cpu":
            batch, chunk = 1, True
        elif not fits(per_device):
            return max(1, int((limit - per_device * out) // max(flight, 1))), False  # type: ignore[operator]
    if chunk:
        k = int(min(batch, runs))
        if not fits(k):
            raise too_big(k, f"batch={k}")
        return k, False
    if not fits(per_device):
        raise too_big(per_device, f"batch={batch!r}")
    return "vmap", sharded


def memory_limit(device: jax.Device) -> tuple[int | None, str]:
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


def run_bytes(solver: AbstractSolver, fitness: Fitness, dim: int, dtype: DTypeLike, iterations: int
              ) -> tuple[int, int]:
    """Upper estimates, in bytes, of ``(one run's memory while in flight, its output)``:
    the population's arrays of the fitness's size (Eq. 17: members x m residuals, about
    6 live at once without blocking), its state and per-iteration randomness; the output
    is the run's history. For a black box, what ``fn`` allocates inside is not
    counted."""
    itemsize = jnp.dtype(dtype).itemsize
    slots = solver.population(dim)
    m = fitness.rows or dim
    flight = (6 * slots * max(m, dim) * itemsize + 12 * slots * dim * itemsize
              + iterations * 16 * (dim + 8))  # keys and small draws per iteration
    return int(flight), int(iterations * (itemsize + 4) + 4 * dim * itemsize)


def check_key(key: Any) -> None:
    """A typed PRNG key (``jax.random.key``) or raw key data (``jax.random.PRNGKey``, a
    uint32 array); anything else (``key=0``) is a TypeError saying what to pass."""
    dtype = getattr(key, "dtype", None)
    if isinstance(key, (jax.Array, np.ndarray)) and dtype is not None and (
            jax.dtypes.issubdtype(dtype, jax.dtypes.prng_key)
            or (dtype == np.uint32 and np.ndim(key) >= 1)):
        return
    got = (repr(key) if dtype is None or np.ndim(key) == 0 else
           f"an array of dtype {dtype} and shape {tuple(np.shape(key))}")
    raise TypeError(f"key must be a JAX PRNG key, e.g. jax.random.key(0), got {got}")


def _check_common(fitness, solver, key, iterations, runs, args, dtype):
    check_key(key)
    if not isinstance(solver, AbstractSolver):
        raise TypeError(f"solver must be an optimiser of the solver contract (SEDSABSO, "
                        f"BSO, LDWPSO, an Evosax strategy or another AbstractSolver), got "
                        f"{type(solver).__name__}")
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) \
            or iterations < 1:
        raise ValueError(f"iterations must be an integer >= 1, got {iterations!r}")
    if runs is not None and (isinstance(runs, bool) or not isinstance(runs, (int, np.integer))
                             or runs < 1):
        raise ValueError(f"runs must be an integer >= 1 or None, got {runs!r}")
    return as_fitness(fitness, args), _x64.float_dtype(dtype)


def _cast_all(dtype, *trees):
    cast = lambda a: a.astype(dtype) if eqx.is_inexact_array(a) else a  # noqa: E731
    return tuple(jax.tree.map(cast, t) for t in trees)


def _prepare(fitness, solver, lower, upper, key, iterations, runs, args, dtype, batch):
    """Check everything and build the compiled function, its configuration and its
    arguments (nothing runs)."""
    fitness, dtype = _check_common(fitness, solver, key, iterations, runs, args, dtype)
    lower, upper = check_bounds(lower, upper, fitness.dim)
    lo, hi = jnp.asarray(lower, dtype), jnp.asarray(upper, dtype)
    dyn, static = eqx.partition(solver, eqx.is_array)
    fitness, dyn = _cast_all(dtype, fitness, dyn)
    cpu = jax.default_backend() == "cpu"
    if runs is None:
        return (_run_one, RunConfig(int(iterations), predraw=cpu), static,
                (dyn, fitness, lo, hi, key))
    mode, sharded = _batching(batch, runs, run_bytes(solver, fitness, lo.shape[0], dtype,
                                                     iterations))
    config = RunConfig(int(iterations), batch=mode, predraw=cpu and mode == 1)
    keys = jax.random.split(key, runs)
    if sharded:
        keys = _sharded_keys(key, keys)
    return _run_many, config, static, (dyn, fitness, lo, hi, keys, jnp.int32(runs))


def _sharded_keys(key: PRNGKeyArray, keys: PRNGKeyArray) -> PRNGKeyArray:
    """``keys`` padded to a multiple of the device count (the extra runs are dropped
    afterwards) and spread over every device of every process (``jax.devices()``: the
    global devices after ``jax.distributed.initialize``), each process placing the shards
    of its own devices: every process computes the same keys from the same seed."""
    devices = jax.devices()
    runs = keys.shape[0]
    padded = math.ceil(runs / len(devices)) * len(devices)
    if padded > runs:
        extra = jax.random.split(jax.random.fold_in(key, 1), padded - runs)
        keys = jnp.concatenate([keys, extra])
    mesh = jax.sharding.Mesh(np.array(devices), ("runs",))
    data = np.asarray(jax.random.key_data(keys))
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("runs", None))
    spread = jax.make_array_from_callback(data.shape, sharding, lambda index: data[index])
    return jax.random.wrap_key_data(spread, impl=jax.random.key_impl(keys))


def under_trace(*trees: Any) -> bool:
    """Whether the call is being traced by a caller's transformation: an argument is a
    tracer (``vmap``, ``grad``, ``jit``) or a new array is one (inside ``jit``)."""
    if any(isinstance(x, jax.core.Tracer) for x in jax.tree.leaves(trees)):
        return True
    return isinstance(jnp.zeros(()), jax.core.Tracer)


def _traced(fitness, solver, lower, upper, key, iterations, runs, args, dtype, batch
            ) -> Result:
    """:func:`minimise` inside a caller's transformation: the same runs, traced. The box's
    values may be traced: ``lower < upper`` is checked when the program runs
    (``equinox.error_if``)."""
    fitness, dtype = _check_common(fitness, solver, key, iterations, runs, args, dtype)
    lo, hi = jnp.asarray(lower, dtype), jnp.asarray(upper, dtype)
    dim = fitness.dim
    if lo.ndim != 1 or hi.shape != lo.shape or (dim is not None and lo.shape[0] != dim):
        raise ValueError(f"bounds must be two 1-D arrays of one length"
                         f"{'' if dim is None else f' ({dim}, the fitness parameters)'}; "
                         f"got lower {lo.shape}, upper {hi.shape}")
    lo = eqx.error_if(lo, jnp.any(~(lo < hi)), "minimise: the bounds need lower < upper "
                      "everywhere (finite); a traced box has one where they do not")
    fitness, solver = _cast_all(dtype, fitness, solver)
    iterations = int(iterations)

    def one(k: PRNGKeyArray) -> Result:
        return solver.run(fitness, lo, hi, k, iterations)

    if runs is None:
        return one(key)
    keys = jax.random.split(key, runs)
    mode, _ = _batching(batch, runs, run_bytes(solver, fitness, lo.shape[0], dtype,
                                               iterations), traced=True)
    if mode == "vmap":
        return jax.vmap(one)(keys)
    assert isinstance(mode, int)
    return jax.lax.map(one, keys, batch_size=mode if mode > 1 else None)


def time_one_of_many(fitness: FitnessLike, solver: AbstractSolver,
                     lower: Float[ArrayLike, " d"], upper: Float[ArrayLike, " d"], *,
                     key: PRNGKeyArray, iterations: int, runs: int,
                     dtype: DTypeLike | None = None) -> tuple[float, float]:
    """``(compile_s, run_s)``: the wall time of ONE run through the executable that
    ``minimise(..., runs=runs)`` uses, where that executable runs in sequence (a single
    CPU device), so timing one run costs no compilation of its own; elsewhere the
    single-run executable is compiled and timed."""
    fn, config, static, call_args = _prepare(fitness, solver, lower, upper, key, iterations,
                                             runs, None, dtype, "auto")
    if config.batch != 1:
        r = minimise(fitness, solver, lower, upper, key=key, iterations=iterations,
                     dtype=dtype)
        return float(r.compile_s or 0.0), float(r.run_s or 0.0)
    exe, compile_s = _COMPILED.get(fn, config, static, *call_args)
    one = (*call_args[:-1], jnp.int32(1))
    t0 = time.perf_counter()
    jax.block_until_ready(exe(*one))
    return compile_s, time.perf_counter() - t0


def minimise(fitness: FitnessLike, solver: AbstractSolver, lower: Float[ArrayLike, " d"],
             upper: Float[ArrayLike, " d"], *, key: PRNGKeyArray, iterations: int = 600,
             runs: int | None = None, args: Any = None, dtype: DTypeLike | None = None,
             batch: Literal["auto", "vmap", "shard"] | int = "auto") -> Result:
    """Minimise ``fitness`` over the box ``[lower, upper]`` with ``solver`` (a swarm,
    an :class:`~._external.Evosax` strategy, any :class:`~._solver.AbstractSolver`).

    Args:
        fitness: a callable ``f(x, args) -> scalar`` (optimistix's convention: ``x`` a 1-D
            array, ``args`` whatever ``args`` below holds; evaluated under ``vmap``; a
            fitness of one argument is refused before anything is traced, one that
            returns more than a scalar per point while it is traced), a
            :class:`~sedsabso_jax.BlackBox` or an :class:`~sedsabso_jax.L1Residual` (the
            paper's Eq. 17, evaluated through ``W x``).
        solver: the optimiser and its hyperparameters.
        lower: the box's lower corner, a 1-D array.
        upper: its upper corner, of the same length.
        key: a JAX PRNG key (``jax.random.key(seed)``, or ``jax.random.PRNGKey``'s raw
            data); the same key gives the same result. An integer is refused (TypeError).
        iterations: iterations (generations) per run.
        runs: that many independent runs in one call (keys split from ``key``), with a
            leading ``runs`` axis on every array of the result; None: one run, no axis.
        args: passed to a callable fitness as its second argument.
        dtype: float64 or float32 for positions and the fitness data; None: float64 in
            JAX's 64-bit mode, else float32.
        batch: how the runs share the call: ``"vmap"`` (all at once on one device), an
            integer k (``lax.map`` over chunks of k vmapped runs on one device),
            ``"shard"`` (vmapped, spread over every device with ``jax.sharding``), or
            ``"auto"``: spread over the devices when there are several, otherwise in
            sequence on a CPU (fastest to compile, and one run can be timed through the
            same executable) or vmapped on an accelerator, in the largest chunks that fit
            half its memory when all at once would not. Every choice gives the same
            numbers up to rounding. Runs that do not fit are a ValueError naming the
            limit, raised before anything compiles.

    Called from Python, the run is compiled ahead of time once per configuration and
    cached (the :data:`CACHE_SIZE` most recent; :func:`clear_compiled` empties it), and
    :attr:`~._result.Result.compile_s` and ``run_s`` time it. Called inside ``jax.jit``
    or ``jax.vmap`` (over keys, boxes or ``args``), it is the same pure computation
    traced into the caller's program and gives the same numbers to rounding; there
    ``compile_s`` and ``run_s`` are None, nothing is sharded, and the box's values may
    be traced: a box with ``lower >= upper`` somewhere then fails when the program runs
    (``equinox.error_if``), not before. A single CPU device, outside any trace, draws
    each phase's random numbers before its loop; traced, they are drawn inside it (same
    numbers, slower on the CPU).
    """
    if under_trace(key, lower, upper, args, fitness, solver):
        return _traced(fitness, solver, lower, upper, key, iterations, runs, args, dtype,
                       batch)
    fn, config, static, call_args = _prepare(fitness, solver, lower, upper, key, iterations,
                                             runs, args, dtype, batch)
    exe, compile_s = _COMPILED.get(fn, config, static, *call_args)
    t0 = time.perf_counter()
    out = jax.block_until_ready(exe(*call_args))
    if jax.process_count() > 1:  # runs on other hosts' devices: every process gets them all
        out = multihost_utils.process_allgather(out, tiled=True)
    if runs is not None:
        out = jax.tree.map(lambda o: o[:runs], out)
    run_s = time.perf_counter() - t0
    return dataclasses.replace(out, compile_s=compile_s, run_s=run_s)
