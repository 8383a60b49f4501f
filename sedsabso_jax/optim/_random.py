"""The swarms' random numbers: uniform draws for a whole population from one key per
draw, bit for bit ``jax.random.uniform`` (:func:`uniforms`), and every iteration's keys
derived before a run's loop (:func:`iteration_randomness`).

An iteration's randomness comes from its key ``sub`` of the chain ``key, sub =
split(key)``; a swarm derives from it what the iteration draws (:meth:`~._swarm.
AbstractSwarm.randomness`: keys for the population's draws, or small draws made up front)
and then the population's draws themselves (:meth:`~._swarm.AbstractSwarm.draw`). A run
may make a phase's population draws before the phase's loop (:func:`fits_before_loop`);
the numbers are the same either way.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, Float, PRNGKeyArray


class Drawing(Protocol):
    """What draws an iteration's random numbers (a swarm: :class:`~._swarm.AbstractSwarm`)."""

    def randomness(self, key: PRNGKeyArray, dim: int, dtype: DTypeLike) -> Any: ...

    def draw(self, randomness: Any, shape: tuple[int, ...], dtype: DTypeLike) -> Any: ...

#: Largest population draws made before a phase's loop, per run (bytes), see
#: :func:`fits_before_loop`.
BEFORE_LOOP_BYTES = 32 * 2**20


def next_key(key: PRNGKeyArray) -> tuple[PRNGKeyArray, PRNGKeyArray]:
    """``(key, sub) = split(key)``: the chain an iteration's randomness comes from."""
    key, sub = jax.random.split(key)
    return key, sub


def iteration_randomness(solver: Drawing, key: PRNGKeyArray, iterations: int, dim: int,
                         dtype: DTypeLike) -> Any:
    """Every iteration's randomness (``solver.randomness`` of its key ``sub``, the chain of
    :func:`next_key` from ``key``), derived before the loop and vectorised over the
    iterations: the same numbers as deriving each inside the loop."""
    def chain(key: PRNGKeyArray, _: None) -> tuple[PRNGKeyArray, PRNGKeyArray]:
        return next_key(key)

    _, subs = jax.lax.scan(chain, key, None, length=iterations)
    return jax.vmap(lambda k: solver.randomness(k, dim, dtype))(subs)


def fits_before_loop(solver: Drawing, randomness: Any, shape: tuple[int, ...],
                     dtype: DTypeLike, length: int) -> bool:
    """Whether a phase's population draws (``length`` iterations of ``shape``) fit in
    :data:`BEFORE_LOOP_BYTES`. Made inside the loop, XLA fuses the hash into each fusion
    that reads a draw and computes it there again (slower on the CPU,
    ``docs/explanation/swarms-kernels.md``). The driver asks
    for draws before the loop only for a run compiled on its own on the CPU: on an
    accelerator, or inside a caller's ``jit``/``vmap`` (whose batch size is unknown
    here), recomputing them costs no memory."""
    one = jax.tree.map(lambda r: r[0], randomness)
    out = jax.eval_shape(lambda r: solver.draw(r, shape, dtype), one)
    size = sum(math.prod(o.shape) * o.dtype.itemsize for o in jax.tree.leaves(out))
    return size * length <= BEFORE_LOOP_BYTES


def uniforms(keys: PRNGKeyArray, shape: tuple[int, ...], dtype: DTypeLike
             ) -> Float[Array, "*keys_and_shape"]:
    """``jax.random.uniform(k, shape, dtype)`` for each key of ``keys`` in one batched
    call, bit for bit (``tests/test_swarms.py`` checks it).

    For threefry keys (JAX's default, with ``jax_threefry_partitionable``, the default
    since JAX 0.5) the bits come from :func:`_threefry2x32`, the same hash written out
    round by round: XLA fuses it into one elementwise loop, where JAX's own CPU lowering
    runs it as a 5-trip loop (``docs/explanation/swarms-kernels.md``). Other keys go through
    ``jax.random.uniform``. Element ``i`` of the flattened ``shape`` depends on ``i``
    alone, so the first rows of a larger draw are a smaller draw."""
    n = math.prod(shape)
    if not (jnp.issubdtype(keys.dtype, jax.dtypes.prng_key)
            and str(jax.random.key_impl(keys)) == "threefry2x32"
            and jax.config.jax_threefry_partitionable  # type: ignore[attr-defined]
            and n < 2**32):
        return jax.vmap(lambda k: jax.random.uniform(k, shape, dtype))(keys)
    dtype = jnp.dtype(dtype)
    kd = jax.random.key_data(keys)  # (..., 2) uint32
    lo = jax.lax.iota(np.uint32, n).reshape(shape)  # the flat index as (hi, lo) words
    k1, k2 = (kd[..., i].reshape(kd.shape[:-1] + (1,) * len(shape)) for i in (0, 1))
    b1, b2 = _threefry2x32(k1, k2, jnp.zeros_like(lo), lo)
    nbits, nmant = jnp.finfo(dtype).bits, jnp.finfo(dtype).nmant
    uint: type[np.unsignedinteger[Any]]
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
