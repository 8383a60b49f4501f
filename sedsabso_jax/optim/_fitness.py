"""Fitness functions for the optimisers, seen through two maps.

Every fitness here is ``value(embed(x))`` with ``embed`` LINEAR: for a black-box
``f(x, args)`` the embedding is ``x`` itself and ``value`` calls ``f``; for the paper's
identification fitness (Eq. 17) the embedding is ``W x`` and ``value`` is the L1 norm of
the residual. Linearity lets a swarm evaluate ``x + s V`` from ``embed(x) + s embed(V)``
without a new product with ``W`` (``W (x + s V) = W x + s W V``).

What the swarms call: :meth:`AbstractFitness.evaluate` (raw fitness of a population)
and :meth:`AbstractFitness.evaluate_with_antennae` (that and the beetles' antenna
difference, Eq. 12, at the same points; for Eq. 17 from ``W x``, ``W v`` and one pass over
the residuals). Every matrix product asks for ``Precision.HIGHEST``: float32 stays
float32 on a GPU or TPU (no TF32 / bfloat16 passes), so the fitness reported is Eq. 17
at the returned point to float32 rounding on every backend.
"""

from __future__ import annotations

import abc
import hashlib
import inspect
from collections.abc import Callable
from typing import Any, Protocol, TypeAlias

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float, Int

from .. import _x64


def finite_or_inf(f: Float[Array, "*shape"]) -> Float[Array, "*shape"]:
    """NaN or Inf fitness counts as +Inf, so it never becomes a best."""
    return jnp.where(jnp.isfinite(f), f, jnp.inf)


class _RegressorSource(Protocol):
    """What :meth:`L1Residual.from_base` needs of a base-parameter set
    (:class:`~sedsabso_jax.BaseParameters`): its regressor ``(samples, n, d)``."""

    def regressor(self, q: Any, qd: Any, qdd: Any) -> Any: ...


class AbstractFitness(eqx.Module):
    """What the solvers evaluate: a fitness ``value(embed(x))`` with a linear ``embed``
    (module docstring)."""

    @property
    @abc.abstractmethod
    def dim(self) -> int | None:
        """The number of parameters ``x`` has, or None where the fitness does not fix it."""

    @property
    @abc.abstractmethod
    def rows(self) -> int | None:
        """The size of ``embed(x)`` where it is larger than ``x`` (Eq. 17's residuals), or
        None: what one evaluation's memory scales with."""

    @abc.abstractmethod
    def evaluate(self, X: Float[Array, "*batch d"]) -> Float[Array, "*batch"]:
        """Raw fitness of every member (row) of ``X``."""

    @abc.abstractmethod
    def evaluate_with_antennae(self, X: Float[Array, "k d"], V: Float[Array, "k d"],
                               a: Float[ArrayLike, ""]
                               ) -> tuple[Float[Array, " k"], Float[Array, " k"], Int[Array, " k"]]:
        """``(f(x), f(x + a v) - f(x - a v), the antennae's non-finite count)`` per member."""


def antenna_difference(fl: Float[Array, " k"], fr: Float[Array, " k"]
                       ) -> tuple[Float[Array, " k"], Int[Array, " k"]]:
    """``(f(xl) - f(xr), how many of the two were NaN or Inf)`` per member from the two
    antennae's raw values; a NaN or Inf value counts as +Inf."""
    bad = (~jnp.isfinite(fl)).astype(jnp.int32) + (~jnp.isfinite(fr)).astype(jnp.int32)
    return finite_or_inf(fl) - finite_or_inf(fr), bad


def check_arity(fn: Callable[..., Any]) -> None:
    """A fitness is called ``fn(x, args)`` (optimistix's convention): refuse one that
    cannot take two positional arguments, before anything is traced. A callable whose
    signature Python cannot read is trusted."""
    try:
        signature = inspect.signature(fn)
    except (TypeError, ValueError):
        return
    try:
        signature.bind(None, None)
    except TypeError:
        name = getattr(fn, "__name__", type(fn).__name__)
        raise TypeError(f"the fitness is called f(x, args) (optimistix's convention: args "
                        f"is minimise's args=, None by default); {name}{signature} takes "
                        f"other arguments: wrap it, e.g. lambda x, args: {name}(x)") from None


class BlackBox(AbstractFitness):
    """Any scalar fitness ``fn(x, args)``; the population is evaluated under ``vmap``."""

    fn: Callable[[Array, Any], Array] = eqx.field(static=True)
    args: Any = None

    def __check_init__(self) -> None:
        if not callable(self.fn):
            raise TypeError(f"fn must be callable f(x, args), got {type(self.fn).__name__}")
        check_arity(self.fn)

    @property
    def dim(self) -> None:
        return None

    @property
    def rows(self) -> None:
        return None

    def embed(self, X: Float[Array, "*batch d"]) -> Float[Array, "*batch d"]:
        return X

    def value(self, E: Float[Array, "*batch d"]) -> Float[Array, "*batch"]:
        flat = E.reshape((-1, E.shape[-1]))
        f = jnp.asarray(jax.vmap(lambda x: self.fn(x, self.args))(flat))
        if f.size != flat.shape[0]:  # checked while tracing, before anything runs
            raise ValueError(f"the fitness must return a scalar per point, got shape "
                             f"{tuple(f.shape[1:])} for x of shape {tuple(flat.shape[1:])}")
        return f.reshape(E.shape[:-1])

    def __call__(self, x: Float[Array, " d"]) -> Float[Array, ""]:
        return self.fn(x, self.args)

    def evaluate(self, X: Float[Array, "*batch d"]) -> Float[Array, "*batch"]:
        """Raw fitness of every member (row) of ``X``."""
        return self.value(X)

    def antenna_difference(self, E: Float[Array, "*batch d"], G: Float[Array, "*batch d"],
                           a: Float[ArrayLike, ""]
                           ) -> tuple[Float[Array, "*batch"], Int[Array, "*batch"]]:
        """``(f(x + a v) - f(x - a v), non-finite count)`` per member from ``E = x``,
        ``G = v``: two evaluations; a NaN or Inf value counts as +Inf."""
        return antenna_difference(self.value(E + a * G), self.value(E - a * G))

    def evaluate_with_antennae(self, X: Float[Array, "k d"], V: Float[Array, "k d"],
                               a: Float[ArrayLike, ""]
                               ) -> tuple[Float[Array, " k"], Float[Array, " k"], Int[Array, " k"]]:
        """``(f(x), f(x + a v) - f(x - a v), the antennae's non-finite count)`` per member:
        three evaluations each, made as ONE evaluation of the stacked points, so ``fn``
        appears once in the compiled step (a fitness that branches over many functions,
        as the BBOB suite of ``sedsabso-jax compare`` does, compiles a third as much)."""
        n = X.shape[0]
        f = self.value(jnp.concatenate([X, X + a * V, X - a * V]))
        return (f[:n], *antenna_difference(f[n:2 * n], f[2 * n:]))


class L1Residual(AbstractFitness):
    """The paper's Eq. 17: ``f(p) = sum_i |W p - tau|_1`` over samples and joints.

    ``W`` is the stacked base regressor (Eq. 8), ``(m, d)`` with ``m = samples x joints``,
    and ``tau`` the measured torques stacked the same way. ``W`` is kept in both layouts,
    ``(m, d)`` and transposed ``(d, m)`` (:attr:`WT`): a few rows' product (SEDSABSO's
    annealing candidates) reads ``W^T``.

    On the CPU a ``W`` of at most :data:`CONSTANT_BYTES` is also kept as static data
    (compared by content), which the swarms' compiled code embeds as a constant: XLA
    then lays it out for the product once, at compilation, instead of in every product.
    The price: a new ``W`` compiles anew; the same ``W`` (and any ``tau``) reuses the
    compiled code. Why each layout: ``docs/explanation/swarms-kernels.md``.
    """

    W: Float[Array, "m d"]
    WT: Float[Array, "d m"]
    tau: Float[Array, " m"]
    W_constant: _Constant | None = eqx.field(static=True)

    def __init__(self, W: Float[ArrayLike, "*rows d"], tau: Float[ArrayLike, "*rows"],
                 dtype: DTypeLike | None = None):
        dtype = _x64.float_dtype(dtype)
        if isinstance(W, jax.core.Tracer) or isinstance(tau, jax.core.Tracer):
            self._init_traced(W, tau, dtype)
            return
        W = np.asarray(W, dtype=float)
        tau = np.asarray(tau, dtype=float)
        if W.ndim > 2:  # (samples, joints, d) -> stacked
            W = W.reshape(-1, W.shape[-1])
        tau = tau.reshape(-1)
        if W.ndim != 2 or W.shape[0] != tau.shape[0]:
            raise ValueError(f"W must be (m, d) and tau (m,); got W {W.shape}, tau {tau.shape}")
        if not (np.all(np.isfinite(W)) and np.all(np.isfinite(tau))):
            raise ValueError("W or tau contains NaN or Inf")
        self.W = jnp.asarray(W, dtype=dtype)
        self.WT = jnp.asarray(np.ascontiguousarray(W.T), dtype=dtype)
        self.tau = jnp.asarray(tau, dtype=dtype)
        small = W.nbytes <= CONSTANT_BYTES and jax.default_backend() == "cpu"
        self.W_constant = _Constant(W) if small else None

    def _init_traced(self, W, tau, dtype):
        """Data traced by a caller's ``jit``/``vmap`` (several data sets in one call): the
        shapes are checked, the values cannot be; ``W`` is an argument, not a constant."""
        W, tau = jnp.asarray(W, dtype), jnp.asarray(tau, dtype)
        if W.ndim > 2:
            W = W.reshape(-1, W.shape[-1])
        tau = tau.reshape(-1)
        if W.ndim != 2 or W.shape[0] != tau.shape[0]:
            raise ValueError(f"W must be (m, d) and tau (m,); got W {W.shape}, tau {tau.shape}")
        self.W, self.WT, self.tau, self.W_constant = W, W.T, tau, None

    @classmethod
    def from_base(cls, base: _RegressorSource, q: Float[ArrayLike, "samples n"],
                  qd: Float[ArrayLike, "samples n"], qdd: Float[ArrayLike, "samples n"],
                  tau: Float[ArrayLike, "samples n"], dtype: DTypeLike | None = None
                  ) -> L1Residual:
        """Eq. 17 for a :class:`~sedsabso_jax.BaseParameters` set and data
        ``q, qd, qdd, tau`` of shape ``(samples, n)``."""
        return cls(np.asarray(base.regressor(q, qd, qdd)), np.asarray(tau), dtype=dtype)

    @property
    def dim(self) -> int:
        return self.W.shape[1]

    def embed(self, X: Float[Array, "*batch d"]) -> Float[Array, "*batch m"]:
        """``X W^T``: the residuals' linear part for every member (row) of ``X``."""
        if X.ndim > 1 and X.shape[-2] <= FEW_ROWS:
            return _matmul(X, self.WT)
        if self.W_constant is not None:  # a constant of the compiled code, in X's dtype
            return _matmul(X, np.asarray(self.W_constant.array.T, dtype=X.dtype))
        return _matmul(X, self.W.T)

    def value(self, E: Float[Array, "*batch m"]) -> Float[Array, "*batch"]:
        return _row_sum(jnp.abs(E - self.tau))

    def evaluate(self, X: Float[Array, "*batch d"]) -> Float[Array, "*batch"]:
        """Eq. 17 for every member (row) of ``X``: for a population one product and one
        reduction, which XLA's CPU fuses into one kernel, so no (members x m) array is
        written."""
        if X.ndim > 1 and X.shape[-2] <= FEW_ROWS:
            return self.value(self.embed(X))
        return jnp.sum(jnp.abs(self.embed(X) - self.tau), -1)

    def __call__(self, x: Float[Array, " d"]) -> Float[Array, ""]:
        return self.value(self.embed(x))

    @property
    def rows(self) -> int:
        """``m``: the residuals of one evaluation."""
        return self.tau.shape[0]

    def antenna_difference(self, E: Float[Array, "*batch m"], G: Float[Array, "*batch m"],
                           a: Float[ArrayLike, ""]
                           ) -> tuple[Float[Array, "*batch"], Int[Array, "*batch"]]:
        """``(f(x + a v) - f(x - a v), non-finite count)`` per member from ``E = W x``,
        ``G = W v`` in ONE pass over the residuals: ``|r + a g| - |r - a g|`` summed."""
        diff = _row_sum(_antenna_terms(E - self.tau, G, a))
        return diff, (~jnp.isfinite(diff)).astype(jnp.int32)

    def evaluate_with_antennae(self, X: Float[Array, "k d"], V: Float[Array, "k d"],
                               a: Float[ArrayLike, ""]
                               ) -> tuple[Float[Array, " k"], Float[Array, " k"], Int[Array, " k"]]:
        """``(f(x), f(x + a v) - f(x - a v), its non-finite count)`` per member, from
        ``W x``, ``W v`` and the residuals ``r = W x - tau``: ``|r + a g| - |r - a g|``
        summed. The (members x m) arrays live only inside this call: a swarm carries
        the per-member results, not ``W x`` and ``W v``. On the CPU ``f`` is its own
        fused product and reduction (:meth:`evaluate`) and the antennae a second pass;
        on an accelerator
        ``x`` and ``v`` go through one stacked product (one BLAS call) and plain
        reductions."""
        if jax.default_backend() == "cpu":
            f = self.evaluate(X)
            diff, bad = self.antenna_difference(self.embed(X), self.embed(V), a)
            return f, diff, bad
        n = X.shape[-2]
        EG = self.embed(jnp.concatenate([X, V], -2))
        R = EG[..., :n, :] - self.tau
        diff = _row_sum(_antenna_terms(R, EG[..., n:, :], a))
        return _row_sum(jnp.abs(R)), diff, (~jnp.isfinite(diff)).astype(jnp.int32)


#: What the solvers take as ``fitness``: a fitness object (:func:`as_fitness` makes one
#: from a callable ``f(x, args)``).
Fitness: TypeAlias = AbstractFitness
#: What :func:`~sedsabso_jax.minimise` takes as ``fitness``: a fitness object or a callable
#: ``f(x, args) -> scalar``.
FitnessLike: TypeAlias = Callable[[Array, Any], Array] | AbstractFitness

#: Up to this many members a product reads ``W^T`` (:class:`L1Residual`).
FEW_ROWS = 8
#: The largest ``W`` (bytes) an :class:`L1Residual` keeps as a constant of the compiled
#: code on the CPU (RS010N's 3000 x 21: 0.5 MB); a larger one is an argument.
CONSTANT_BYTES = 4 * 2**20


class _Constant:
    """A NumPy array as static data of a pytree: hashed and compared by content (its
    shape, dtype and SHA-1 digest), so equal data reuses compiled code."""

    __slots__ = ("array", "_key")

    def __init__(self, array: ArrayLike) -> None:
        self.array = np.ascontiguousarray(array)
        self.array.flags.writeable = False
        self._key = (self.array.shape, self.array.dtype.str,
                     hashlib.sha1(self.array.tobytes()).hexdigest())

    def __hash__(self) -> int:
        return hash(self._key)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Constant) and self._key == other._key

    def __repr__(self) -> str:
        return f"constant{self.array.shape}"


def _matmul(X, WT):
    return jnp.matmul(X, WT, precision=HIGHEST)


HIGHEST = jax.lax.Precision.HIGHEST


def _antenna_terms(R, G, a):
    """``|r + a g| - |r - a g|`` elementwise: the antennae's residuals, whose row sums are
    ``f(x + a v) - f(x - a v)`` for Eq. 17."""
    return jnp.abs(R + a * G) - jnp.abs(R - a * G)


def _row_sum(A):
    """Sum over the last (long) axis. On the CPU as a product with ones, faster there
    inside the swarms' loops than XLA's row reduction; elsewhere a plain reduction, which
    fuses with the ``abs`` that feeds it (a product would be a separate BLAS call, and on
    a GPU its float32 default precision is TF32)."""
    if jax.default_backend() == "cpu":
        return jnp.matmul(A, jnp.ones(A.shape[-1], A.dtype), precision=HIGHEST)
    return jnp.sum(A, -1)


def as_fitness(fitness: FitnessLike, args: Any = None) -> Fitness:
    """A fitness object from a callable ``f(x, args)`` or one of the classes above."""
    if isinstance(fitness, AbstractFitness):
        if args is not None:
            raise ValueError("args only go with a plain callable fitness")
        return fitness
    if callable(fitness):
        return BlackBox(fitness, args)
    raise TypeError(f"fitness must be a callable f(x, args), a BlackBox or an L1Residual, "
                    f"got {type(fitness).__name__}")
