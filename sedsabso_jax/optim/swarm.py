"""What every swarm shares: the solver interface, the population state, and the operations
on it (evaluation, personal and global bests, a shrinking population).

A swarm is an immutable solver (an ``equinox.Module`` whose fields are its
hyperparameters) implementing :class:`AbstractSwarm`; :func:`~sedsabso_jax.minimise`
(``driver.py``) runs any of them. A variable population (SEDSABSO's Eq. 15-16) uses a fixed
number of slots with an active mask; the driver splits the iterations into phases of
static, shrinking slot counts (:func:`phases`), so the work follows the active count while
everything compiles once.
"""

from __future__ import annotations

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .fitness import finite_or_inf


class AbstractSwarm(eqx.Module):
    """The interface :func:`~sedsabso_jax.minimise` runs: a static population
    :meth:`schedule`, :meth:`init` and :meth:`step` (one iteration), and :meth:`check`
    for the hyperparameters. Every swarm here moves its population with velocities
    clamped to ``vmax_fraction (upper - lower)``."""

    vmax_fraction: eqx.AbstractVar[float]

    @property
    @abc.abstractmethod
    def n_slots(self) -> int:
        """Population slots to allocate (the largest population of the run)."""

    def schedule(self, iterations: int) -> np.ndarray:
        """Active population per iteration (static, never growing). Default: all
        :attr:`n_slots` throughout."""
        return np.full(iterations, self.n_slots)

    @property
    def n_phases(self) -> int:
        """Compiled phases of static slot count the iterations are split into."""
        return 1

    def init(self, fitness, lower, upper, key) -> SwarmState:
        """The initial population: uniform in the box ``[lower, upper]``, velocities
        uniform in ``+-Vmax``."""
        return initial_state(fitness, lower, upper, key, self.n_slots,
                             self.vmax_fraction * (upper - lower))

    def randomness(self, key, dim: int, dtype):
        """What one iteration draws from, derived from the iteration's key: keys for the
        population's draws (their shape follows the phase) or small draws made up front.
        Default: two keys, for ``r1`` and ``r2`` of the velocity update."""
        return jax.random.split(key)

    def draw(self, randomness, shape, dtype):
        """One iteration's draws for a population of ``shape`` (slots, d), from what
        :meth:`randomness` returned: what :meth:`step` takes. Default: ``(r1, r2)``,
        uniform, one per slot and dimension."""
        return uniforms(randomness, shape, dtype)

    def evaluations(self, n_active):
        """Fitness evaluations one iteration makes with ``n_active`` members (a member's
        position counts once). Default: one per member."""
        return n_active

    def evaluation_counts(self, iterations: int, dim: int) -> np.ndarray:
        """Cumulative fitness evaluations after each iteration, the initial population
        included (what :attr:`~.result.Result.n_evaluations` reports at the end)."""
        return self.n_slots + np.cumsum(self.evaluations(self.schedule(iterations)))

    @abc.abstractmethod
    def step(self, fitness, state: SwarmState, t, iterations: int, lower, upper,
             draws) -> SwarmState:
        """Iteration ``t`` of ``iterations``; ``draws`` as returned by :meth:`draw`."""

    @abc.abstractmethod
    def check(self) -> None:
        """Raise ValueError on bad hyperparameters (called before anything compiles)."""


class SwarmState(eqx.Module):
    """One run's population. Inactive slots still move (masking them would cost more
    than moving them) but their personal bests are frozen and they never return: only
    active slots' personal bests can become the best. Nothing of the fitness's size is
    carried from one iteration to the next: a beetle's antenna difference (Eq. 12) at
    its current position is computed with that position's fitness, in the same pass,
    and carried as one number per slot."""

    x: Float[Array, "slots d"]
    v: Float[Array, "slots d"]
    antennae: Float[Array, " slots"]  # f(x + a v) - f(x - a v) (beetles; 0 otherwise)
    antennae_bad: Int[Array, " slots"]  # how many of those two were NaN or Inf
    pbest_x: Float[Array, "slots d"]
    pbest_f: Float[Array, " slots"]
    active: Bool[Array, " slots"]
    slot_nonfinite: Int[Array, " slots"]  # non-finite evaluations of each active slot
    guide_x: Float[Array, " d"]  # global best that steers the velocities (SA guide)
    guide_f: Float[Array, ""]
    best_x: Float[Array, " d"]  # best point ever evaluated: what is reported
    best_f: Float[Array, ""]
    temperature: Float[Array, ""]
    sa_accepted: Int[Array, ""]
    n_evaluations: Int[Array, ""]
    n_nonfinite: Int[Array, ""]  # non-finite evaluations not in slot_nonfinite

    @property
    def nonfinite_total(self):
        """Every non-finite evaluation so far (counted per slot inside the loop, where a
        sum per iteration would cost a reduction; summed here)."""
        return self.n_nonfinite + jnp.sum(self.slot_nonfinite, dtype=jnp.int32)


def evaluate(fitness, X, mask=None, raw=None):
    """Fitness of the members ``X`` (or their ``raw`` values when already computed),
    non-finite values mapped to +Inf, and per member 1 where a value was non-finite
    (0 outside ``mask`` when given)."""
    raw = fitness.evaluate(X) if raw is None else raw
    bad = ~jnp.isfinite(raw)
    if mask is not None:
        bad = bad & mask
    return finite_or_inf(raw), bad.astype(jnp.int32)


def initial_state(fitness, lower, upper, key, slots: int, vmax, temperature=0.0,
                  antenna=None) -> SwarmState:
    """Positions uniform in the box, velocities uniform in ``+-vmax``, evaluated; with
    ``antenna`` (the beetles' ``a``), also each slot's ``f(x + a v) - f(x - a v)``."""
    kx, kv = jax.random.split(key)
    d = lower.shape[0]
    x = lower + (upper - lower) * jax.random.uniform(kx, (slots, d), lower.dtype)
    v = vmax * jax.random.uniform(kv, (slots, d), lower.dtype, -1.0, 1.0)
    if antenna is None:
        raw, diff, diff_bad = None, jnp.zeros(slots, x.dtype), jnp.zeros(slots, jnp.int32)
    else:
        raw, diff, diff_bad = fitness.evaluate_with_antennae(x, v, antenna)
    f, bad = evaluate(fitness, x, raw=raw)
    i = jnp.argmin(f)
    return SwarmState(
        x=x, v=v, antennae=diff, antennae_bad=diff_bad, pbest_x=x, pbest_f=f,
        active=jnp.ones(slots, bool), slot_nonfinite=jnp.zeros(slots, jnp.int32),
        guide_x=x[i], guide_f=f[i], best_x=x[i], best_f=f[i],
        temperature=jnp.asarray(temperature, lower.dtype), sa_accepted=jnp.int32(0),
        n_evaluations=jnp.int32(slots), n_nonfinite=jnp.sum(bad, dtype=jnp.int32),
    )


def update_bests(state: SwarmState, x, f):
    """Take the new positions; update the active slots' personal bests and the best ever.
    Returns the state and the swarm's global best ``(x, f)`` among the active slots."""
    better = state.active & (f < state.pbest_f)
    pbest_f = jnp.where(better, f, state.pbest_f)
    pbest_x = jnp.where(better[:, None], x, state.pbest_x)
    masked = jnp.where(state.active, pbest_f, jnp.inf)
    i = jnp.argmin(masked)
    improve_best = masked[i] < state.best_f
    return eqx.tree_at(
        lambda s: (s.x, s.pbest_x, s.pbest_f, s.best_x, s.best_f),
        state,
        (x, pbest_x, pbest_f,
         jnp.where(improve_best, pbest_x[i], state.best_x),
         jnp.where(improve_best, masked[i], state.best_f)),
    ), (pbest_x[i], masked[i])


def set_active(state: SwarmState, n_active) -> SwarmState:
    """Keep the ``n_active`` slots with the best personal bests (worst dropped first)."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))
    rank = jnp.empty_like(order).at[order].set(jnp.arange(order.shape[0]))
    return eqx.tree_at(lambda s: s.active, state, rank < n_active)


def shrink(state: SwarmState, slots: int) -> SwarmState:
    """Reorder slots best first (active before inactive) and keep the first ``slots``
    (the per-slot non-finite counts move to the total first)."""
    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))[:slots]
    per_slot = ("x", "v", "antennae", "antennae_bad", "pbest_x", "pbest_f", "active")
    state = eqx.tree_at(lambda s: (s.n_nonfinite, s.slot_nonfinite), state,
                        (state.nonfinite_total, jnp.zeros(slots, jnp.int32)))
    return eqx.tree_at(lambda s: [getattr(s, k) for k in per_slot], state,
                       [getattr(state, k)[order] for k in per_slot])


def phases(schedule: np.ndarray, n_phases: int):
    """Split iterations into at most ``n_phases`` runs of iterations with a static slot
    count each: the largest active count inside the phase (N(t) never grows)."""
    K = len(schedule)
    bounds = sorted({round(k * K / n_phases) for k in range(n_phases)} | {K})
    return [(a, b, int(schedule[a:b].max())) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def uniforms(keys, shape, dtype):
    """``jax.random.uniform(k, shape, dtype)`` for each key of ``keys`` in one batched
    call, bit for bit (``tests/test_swarms.py`` checks it).

    For threefry keys (JAX's default, with ``jax_threefry_partitionable``, the default
    since JAX 0.5) the bits come from :func:`_threefry2x32`, the same hash written out
    round by round: XLA fuses it into one elementwise loop, where JAX's own CPU lowering
    runs it as a 5-trip loop (an iteration's r1, r2 for 50 x 21: 3.5 vs 7.1 us on the
    2-core AMD EPYC, ``python benchmarks/kernels.py``). Other keys go through
    ``jax.random.uniform``."""
    n = math.prod(shape)
    if not (jnp.issubdtype(keys.dtype, jax.dtypes.prng_key)
            and str(jax.random.key_impl(keys)) == "threefry2x32"
            and jax.config.jax_threefry_partitionable and n < 2**32):
        return jax.vmap(lambda k: jax.random.uniform(k, shape, dtype))(keys)
    dtype = jnp.dtype(dtype)
    kd = jax.random.key_data(keys)  # (..., 2) uint32
    lo = jax.lax.iota(np.uint32, n).reshape(shape)  # the flat index as (hi, lo) words
    k1, k2 = (kd[..., i].reshape(kd.shape[:-1] + (1,) * len(shape)) for i in (0, 1))
    b1, b2 = _threefry2x32(k1, k2, jnp.zeros_like(lo), lo)
    nbits, nmant = jnp.finfo(dtype).bits, jnp.finfo(dtype).nmant
    if nbits == 64:
        uint = np.uint64
        bits = (b1.astype(uint) << uint(32)) | b2.astype(uint)
    else:
        uint = np.uint32
        bits = b1 ^ b2
    one = np.array(1.0, dtype).view(uint)
    float_bits = jax.lax.shift_right_logical(bits, uint(nbits - nmant)) | one
    return jax.lax.bitcast_convert_type(float_bits, dtype) - jnp.asarray(1.0, dtype)


def _threefry2x32(k1, k2, x1, x2):
    """Threefry-2x32 with 20 rounds (Salmon et al., "Parallel random numbers: as easy as
    1, 2, 3", SC 2011), as JAX computes it: key schedule ``k1, k2, k1 ^ k2 ^
    0x1BD11BDA``, rotations 13 15 26 6 / 17 29 16 24, a key injection every 4 rounds."""
    ks = (k1, k2, k1 ^ k2 ^ np.uint32(0x1BD11BDA))
    x1, x2 = x1 + ks[0], x2 + ks[1]
    for i in range(5):
        for r in ((13, 15, 26, 6), (17, 29, 16, 24))[i % 2]:
            x1 = x1 + x2
            x2 = x1 ^ ((x2 << np.uint32(r)) | jax.lax.shift_right_logical(x2, np.uint32(32 - r)))
        x1 = x1 + ks[(i + 1) % 3]
        x2 = x2 + ks[(i + 2) % 3] + np.uint32(i + 1)
    return x1, x2


def check_population(n, name: str) -> None:
    """A population size must be an integer >= 1."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"{name} must be an integer >= 1, got {n!r}")


def check_velocity_update(c1: float, c2: float, vmax_fraction: float) -> None:
    """The velocity update's coefficients: ``c1, c2 >= 0`` and ``vmax_fraction > 0``."""
    if vmax_fraction <= 0:
        raise ValueError(f"vmax_fraction must be > 0, got {vmax_fraction}")
    if c1 < 0 or c2 < 0:
        raise ValueError(f"c1 and c2 must be >= 0, got c1={c1}, c2={c2}")
