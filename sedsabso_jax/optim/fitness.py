"""Fitness functions for the optimisers, seen through two maps.

Every fitness here is ``value(embed(x))`` with ``embed`` LINEAR: for a black-box
``f(x, args)`` the embedding is ``x`` itself and ``value`` calls ``f``; for the paper's
identification fitness (Eq. 17) the embedding is ``W x`` and ``value`` is the L1 norm of
the residual. Linearity lets a swarm evaluate ``x + s V`` from ``embed(x) + s embed(V)``
without a new product with ``W`` (``W (x + s V) = W x + s W V``).

What the swarms call: :meth:`evaluate` (raw fitness of a population) and
:meth:`evaluate_with_antennae` (that and the beetles' antenna difference, Eq. 12, at the
same points; for Eq. 17 from ``W x``, ``W v`` and one pass over the residuals). Every
matrix product asks for ``Precision.HIGHEST``: float32 stays float32 on a GPU or TPU (no
TF32 / bfloat16 passes), so the fitness reported is Eq. 17 at the returned point to
float32 rounding on every backend.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float


def finite_or_inf(f):
    """NaN or Inf fitness counts as +Inf, so it never becomes a best."""
    return jnp.where(jnp.isfinite(f), f, jnp.inf)


class BlackBox(eqx.Module):
    """Any scalar fitness ``fn(x, args)``; the population is evaluated under ``vmap``."""

    fn: Callable[[Array, Any], Array] = eqx.field(static=True)
    args: Any = None

    def embed(self, X):
        return X

    def value(self, E):
        flat = E.reshape((-1, E.shape[-1]))
        return jax.vmap(lambda x: self.fn(x, self.args))(flat).reshape(E.shape[:-1])

    def __call__(self, x):
        return self.fn(x, self.args)

    def evaluate(self, X):
        """Raw fitness of every member (row) of ``X``."""
        return self.value(X)

    def blocked(self, rows: int):
        """The same fitness for populations of ``rows`` (see
        :meth:`L1Residual.blocked`): itself."""
        return self

    def antenna_difference(self, E, G, a):
        """``(f(x + a v) - f(x - a v), non-finite count)`` per member from ``E = x``,
        ``G = v``: two evaluations; a NaN or Inf value counts as +Inf."""
        fl, fr = self.value(E + a * G), self.value(E - a * G)
        bad = (~jnp.isfinite(fl)).astype(jnp.int32) + (~jnp.isfinite(fr)).astype(jnp.int32)
        return finite_or_inf(fl) - finite_or_inf(fr), bad

    def evaluate_with_antennae(self, X, V, a):
        """``(f(x), f(x + a v) - f(x - a v), the antennae's non-finite count)`` per member:
        three evaluations each, made as ONE evaluation of the stacked points, so ``fn``
        appears once in the compiled step (a fitness that branches over many functions,
        as the BBOB suite of ``sedsabso-jax compare`` does, compiles a third as much)."""
        n = X.shape[0]
        f = self.value(jnp.concatenate([X, X + a * V, X - a * V]))
        fl, fr = f[n:2 * n], f[2 * n:]
        bad = (~jnp.isfinite(fl)).astype(jnp.int32) + (~jnp.isfinite(fr)).astype(jnp.int32)
        return f[:n], finite_or_inf(fl) - finite_or_inf(fr), bad


class L1Residual(eqx.Module):
    """The paper's Eq. 17: ``f(p) = sum_i |W p - tau|_1`` over samples and joints.

    ``W`` is the stacked base regressor (Eq. 8), ``(m, d)`` with ``m = samples x joints``,
    and ``tau`` the measured torques stacked the same way. ``W`` is stored transposed,
    ``(d, m)`` contiguous (:attr:`WT`), the layout a product ``X W^T`` reads without a
    transposed copy: on the 2-core AMD EPYC the 3-row product of SEDSABSO's annealing
    candidates took 20 us with ``W`` stored (m, d) and 7.5 us with ``W^T`` (float64, 21 x
    3000; ``python benchmarks/kernels.py``).
    """

    WT: Float[Array, "d m"]
    tau: Float[Array, " m"]

    def __init__(self, W, tau, dtype=jnp.float64):
        W = np.asarray(W, dtype=float)
        tau = np.asarray(tau, dtype=float)
        if W.ndim > 2:  # (samples, joints, d) -> stacked
            W = W.reshape(-1, W.shape[-1])
        tau = tau.reshape(-1)
        if W.ndim != 2 or W.shape[0] != tau.shape[0]:
            raise ValueError(f"W must be (m, d) and tau (m,); got W {W.shape}, tau {tau.shape}")
        if not (np.all(np.isfinite(W)) and np.all(np.isfinite(tau))):
            raise ValueError("W or tau contains NaN or Inf")
        self.WT = jnp.asarray(np.ascontiguousarray(W.T), dtype=dtype)
        self.tau = jnp.asarray(tau, dtype=dtype)

    @classmethod
    def from_base(cls, base, q, qd, qdd, tau, dtype=jnp.float64) -> L1Residual:
        """Eq. 17 for a :class:`~sedsabso_jax.BaseParameters` set and data
        ``q, qd, qdd, tau`` of shape ``(samples, n)``."""
        return cls(np.asarray(base.regressor(q, qd, qdd)), np.asarray(tau), dtype=dtype)

    @property
    def W(self) -> Float[Array, "m d"]:
        """The stacked base regressor ``(m, d)`` (a transposed view of :attr:`WT`)."""
        return self.WT.T

    @property
    def dim(self) -> int:
        return self.WT.shape[0]

    def embed(self, X):
        """``X W^T``: the residuals' linear part for every member (row) of ``X``."""
        return _matmul(X, self.WT)

    def value(self, E):
        return _row_sum(jnp.abs(E - self.tau))

    def evaluate(self, X):
        """Eq. 17 for every member (row) of ``X``."""
        return self.value(self.embed(X))

    def __call__(self, x):
        return self.value(self.embed(x))

    def antenna_difference(self, E, G, a):
        """``(f(x + a v) - f(x - a v), non-finite count)`` per member from ``E = W x``,
        ``G = W v`` in ONE pass over the residuals: ``|r + a g| - |r - a g|`` summed."""
        diff = _row_sum(_antenna_terms(E - self.tau, G, a))
        return diff, (~jnp.isfinite(diff)).astype(jnp.int32)

    def evaluate_with_antennae(self, X, V, a):
        """``(f(x), f(x + a v) - f(x - a v), its non-finite count)`` per member from
        ``W x`` and ``W v`` and one pass over the residuals ``r = W x - tau`` (``|r|``
        and ``|r + a g| - |r - a g|``). The (members x m) arrays live only inside this
        call: a swarm carries the per-member results, not ``W x`` and ``W v``. On an
        accelerator ``x`` and ``v`` go through one stacked product (one BLAS call); on
        the CPU two products measured faster (50 beetles, 2-core AMD EPYC: 258 vs 294 us
        per iteration float64, 128 vs 167 us float32; ``python benchmarks/kernels.py``)."""
        if jax.default_backend() == "cpu":
            E, G = self.embed(X), self.embed(V)
        else:
            n = X.shape[-2]
            EG = self.embed(jnp.concatenate([X, V], -2))
            E, G = EG[..., :n, :], EG[..., n:, :]
        return _l1_with_antennae(E - self.tau, G, a)

    def blocked(self, rows: int):
        """This fitness laid out for populations of ``rows`` members, made once per
        phase outside the swarm's loop. On the CPU the residuals are taken in blocks of
        ``c`` of the ``m`` rows of ``W``, ``c`` such that a (rows x c) array takes at
        most :data:`CPU_BLOCK_BYTES`, so the arrays of one block stay in the core's L2
        cache between the product and the pass that sums them (the last block padded with
        zero rows of ``W`` and ``tau``, which add exactly 0 to every sum); the sums are
        accumulated block by block. Elsewhere (and when one block holds all rows)
        itself."""
        d, m = self.WT.shape
        c = _block_width(rows, self.WT.dtype.itemsize)
        if jax.default_backend() != "cpu" or c >= m:
            return self
        k = -(-m // c)
        c = -(-m // k)
        WT = jnp.pad(self.WT, ((0, 0), (0, k * c - m)))
        return L1Blocks(self, WT.reshape(d, k, c).transpose(1, 0, 2),
                        jnp.pad(self.tau, (0, k * c - m)).reshape(k, c))


#: Bytes of one (members x block) array of Eq. 17's residuals on the CPU
#: (:meth:`L1Residual.blocked`): on the 2-core AMD EPYC (1 MiB L2 per core), BSO's
#: evaluation with 50 beetles took 198 us per iteration in blocks of 300 rows vs 258 us
#: on all 3000 at once (float64), 97 vs 128 us in blocks of 600 (float32), and 300 to
#: 350 us in blocks over 150 KiB (``python benchmarks/kernels.py``); 128 KiB was also
#: best for 37 and 67 members and in whole runs (64 to 192 KiB tried).
CPU_BLOCK_BYTES = 128 * 2**10


def _block_width(rows: int, itemsize: int) -> int:
    return max(8, CPU_BLOCK_BYTES // (max(rows, 1) * itemsize))


class L1Blocks(eqx.Module):
    """Eq. 17 with the rows of ``W`` in blocks (:meth:`L1Residual.blocked`): what the
    swarms call, the same values up to the order of the sums."""

    full: L1Residual
    WT_blocks: Float[Array, "k d c"]
    tau_blocks: Float[Array, "k c"]

    @property
    def dim(self) -> int:
        return self.full.dim

    def blocked(self, rows: int):
        return self.full.blocked(rows)

    def _scan(self, fn, X, n_out):
        def body(acc, block):
            return tuple(a + s for a, s in zip(acc, fn(*block))), None

        zero = jnp.zeros(X.shape[:-1], X.dtype)
        sums, _ = jax.lax.scan(body, (zero,) * n_out, (self.WT_blocks, self.tau_blocks))
        return sums

    def evaluate(self, X):
        """Eq. 17 for every member (row) of ``X``."""
        if X.shape[-2] * self.full.WT.shape[1] * X.dtype.itemsize <= CPU_BLOCK_BYTES:
            return self.full.evaluate(X)  # a few members (SEDSABSO's candidates)
        (f,) = self._scan(lambda WT, tau: (_row_sum(jnp.abs(_matmul(X, WT) - tau)),), X, 1)
        return f

    def evaluate_with_antennae(self, X, V, a):
        """As :meth:`L1Residual.evaluate_with_antennae`, block by block."""
        f, diff = self._scan(lambda WT, tau: _l1_with_antennae(
            _matmul(X, WT) - tau, _matmul(V, WT), a)[:2], X, 2)
        return f, diff, (~jnp.isfinite(diff)).astype(jnp.int32)


def _matmul(X, WT):
    return jnp.matmul(X, WT, precision=HIGHEST)


def _l1_with_antennae(R, G, a):
    """Row sums ``(|r|, |r + a g| - |r - a g|)`` and the second's non-finite flags."""
    diff = _row_sum(_antenna_terms(R, G, a))
    return _row_sum(jnp.abs(R)), diff, (~jnp.isfinite(diff)).astype(jnp.int32)


HIGHEST = jax.lax.Precision.HIGHEST


def _antenna_terms(R, G, a):
    """``|r + a g| - |r - a g|`` elementwise: the antennae's residuals, whose row sums are
    ``f(x + a v) - f(x - a v)`` for Eq. 17."""
    return jnp.abs(R + a * G) - jnp.abs(R - a * G)


def _row_sum(A):
    """Sum over the last (long) axis. On the CPU as a product with ones: XLA's CPU row
    reduction measured slower inside the swarms' loops (BSO run: about -10 % float64,
    -15 % float32); elsewhere a plain reduction, which fuses with the ``abs`` that feeds
    it (a product would be a separate BLAS call, and on a GPU its float32 default
    precision is TF32)."""
    if jax.default_backend() == "cpu":
        return jnp.matmul(A, jnp.ones(A.shape[-1], A.dtype), precision=HIGHEST)
    return jnp.sum(A, -1)


def as_fitness(fitness, args=None):
    """A fitness object from a callable ``f(x, args)`` or one of the classes above."""
    if isinstance(fitness, (BlackBox, L1Residual)):
        if args is not None:
            raise ValueError("args only go with a plain callable fitness")
        return fitness
    if callable(fitness):
        return BlackBox(fitness, args)
    raise TypeError(f"fitness must be callable f(x, args) or an L1Residual, got {type(fitness)}")
