"""The excitation design's objective, the paper's Eq. 9: the condition number of the stacked
base regressor, with a penalty when a joint limit is violated; and the exact condition
number of a sampled motion."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..dynamics._base_parameters import BaseParameters
from ..dynamics._limits import JointLimits
from ..dynamics._regressor import check_memory_budget, sample_bytes, unchecked_regressor
from ..dynamics._robot import Robot
from ._trajectory import basis, evaluate

#: Eq. 9's penalty when a trajectory violates a limit.
PENALTY = 1e8
#: The fitness tightens every limit by this fraction, so that a design that touches a limit
#: still passes :func:`._checks.check_trajectory` after round-off (the optimum sits on the
#: limits).
LIMIT_MARGIN = 1e-9


#: Samples per regressor call in :func:`condition_number` on the CPU: the batch shape
#: that :func:`~sedsabso_jax.base_parameters` has already compiled (50 states).
_COND_CHUNK = 50


def condition_samples(n_joints: int, samples: int, memory_budget: int | None = None) -> int:
    """Samples per regressor call in :func:`condition_number`: on the CPU 50 (a shape
    already compiled, so no new compilation for any ``T``); on an accelerator all of
    them, a multiple of 50, or as many multiples of 50 as ``memory_budget`` bytes allow
    (at least 50)."""
    budget = check_memory_budget(memory_budget)
    if jax.default_backend() == "cpu":
        return _COND_CHUNK
    fit = max(1, budget // (_COND_CHUNK * sample_bytes(n_joints)))
    return _COND_CHUNK * min(fit, -(-samples // _COND_CHUNK))


def condition_number(base: BaseParameters, q: Float[ArrayLike, "T n"],
                     qd: Float[ArrayLike, "T n"], qdd: Float[ArrayLike, "T n"], *,
                     memory_budget: int | None = None) -> float:
    """2-norm condition number of the stacked base regressor ``W_b`` (Eq. 8) at the samples
    ``(T, n)``: ``sigma_max / sigma_min`` by an SVD (``inf`` when rank-deficient).

    The regressor is evaluated in blocks of :func:`condition_samples` samples: 50 on the
    CPU, the batch shape that ``base_parameters`` compiles by default, so no new
    compilation is needed for any ``T``; on an accelerator at once, or in blocks within
    ``memory_budget`` bytes."""
    n = base.robot.n_joints
    check_memory_budget(memory_budget)
    arrays = []
    for name, value in (("q", q), ("qd", qd), ("qdd", qdd)):
        arr = np.asarray(value, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != n:
            raise ValueError(f"{name} must have shape (samples, {n}), got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} contains NaN or Inf")
        arrays.append(arr)
    if not arrays[0].shape == arrays[1].shape == arrays[2].shape:
        raise ValueError(f"q, qd, qdd must have one shape, got "
                         f"{[a.shape for a in arrays]}")
    T = arrays[0].shape[0]
    chunk = condition_samples(n, T, memory_budget)
    pad = -T % chunk
    padded = [np.concatenate([a, np.zeros((pad, n))]) for a in arrays]
    blocks = [np.asarray(base.regressor(*(a[i: i + chunk] for a in padded)))
              for i in range(0, T + pad, chunk)]
    W = np.concatenate(blocks)[:T].reshape(-1, base.rank)
    s = np.linalg.svd(W, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def _gram_condition_number(W):
    """cond(W) as sqrt(lambda_max / lambda_min) of ``W^T W``: a (rank, rank) eigenproblem
    instead of an SVD of the tall W (several times faster under vmap on a CPU); accurate
    while cond(W) << 1e8, which covers every trajectory worth keeping. ``inf`` when
    ``lambda_min <= 0`` (rank-deficient)."""
    lam = jnp.linalg.eigvalsh(jnp.matmul(W.T, W, precision=jax.lax.Precision.HIGHEST))
    return jnp.where(lam[0] > 0, jnp.sqrt(lam[-1] / jnp.where(lam[0] > 0, lam[0], 1.0)),
                     jnp.inf)


def sampling_margin(n_harmonics: int, samples: int) -> float:
    """Relative tightening ``delta = pi^2 N^2 / (2 S^2)`` that makes limits checked at ``S``
    equally spaced samples over a period hold between the samples too.

    Each of ``qd``, ``qdd`` and ``q - centre`` is a trigonometric polynomial ``p`` of degree
    ``N`` in ``wf t``, so ``|p''| <= (N wf)^2 max|p|`` (Bernstein's inequality, twice). At
    the time where ``|p|`` peaks, ``p' = 0``, and the nearest sample is at most ``h / 2``
    away (``h = 2 pi / (wf S)``), so by Taylor ``max|p| (1 - (N wf h)^2 / 8) <= max over
    the samples``, and ``(N wf h)^2 / 8 = pi^2 N^2 / (2 S^2)``: 1.2 % for N = 5, S = 100.
    """
    return math.pi**2 * n_harmonics**2 / (2.0 * samples**2)


class DesignProblem(eqx.Module):
    """Everything Eq. 9 needs, as a pytree passed to :func:`design_fitness` through
    ``minimise(args=...)``; built by :meth:`build`."""

    robot: Robot
    kw: Array
    cond_basis: tuple[Array, Array]  # cos, sin at the design times
    check_basis: tuple[Array, Array] | None  # cos, sin over one period; None: the same
    centre: Array  # mid position range (0 when unbounded)
    half: Array  # allowed |q - centre|, tightened (inf when unbounded)
    qd_max: Array  # tightened
    qdd_max: Array  # tightened
    columns: tuple[int, ...] = eqx.field(static=True)
    n: int = eqx.field(static=True)
    N: int = eqx.field(static=True)
    graded: bool = eqx.field(static=True)

    def split(self, x: Float[Array, " d"]
              ) -> tuple[Float[Array, "n N"], Float[Array, "n N"], Float[Array, " n"]]:
        n, N = self.n, self.N
        return x[: n * N].reshape(n, N), x[n * N: 2 * n * N].reshape(n, N), x[2 * n * N:]

    @classmethod
    def build(cls, robot: Robot, base: BaseParameters, limits: JointLimits, N: int, wf: float,
              duration: float, S: int, graded: bool = True) -> DesignProblem:
        """The fitness data: cond on ``S`` times over ``[0, duration)``, limits checked at ``S``
        times over one period, tightened by :func:`sampling_margin` and ``LIMIT_MARGIN``, so a
        feasible design satisfies the limits at every time, not only at the samples."""
        delta = sampling_margin(N, S)
        if delta >= 0.5:
            raise ValueError(f"design_samples={S} is too few for {N} harmonics (sampling "
                             f"margin {delta:.3g}); use at least {math.ceil(math.pi * N)}")
        period = 2 * math.pi / wf
        kw, c, s = basis(duration * np.arange(S) / S, N, wf)
        shared = abs(duration - period) <= 1e-12 * period
        check = None if shared else basis(period * np.arange(S) / S, N, wf)[1:]
        shrink = (1.0 - delta) * (1.0 - LIMIT_MARGIN)
        q_min, q_max = np.asarray(limits.q_min), np.asarray(limits.q_max)
        bounded = np.isfinite(q_min) & np.isfinite(q_max)
        return cls(
            robot=robot, kw=kw, cond_basis=(c, s), check_basis=check,
            centre=jnp.asarray(np.where(bounded, (q_max + q_min) / 2, 0.0)),
            half=jnp.asarray(np.where(bounded, (q_max - q_min) / 2 * shrink, np.inf)),
            qd_max=limits.qd_max * shrink, qdd_max=limits.qdd_max * shrink,
            columns=base.indices, n=robot.n_joints, N=N, graded=bool(graded),
        )


def design_fitness(x: Float[Array, " d"], problem: DesignProblem) -> Float[Array, ""]:
    """Eq. 9 at coefficients ``x`` (:meth:`~sedsabso_jax.FourierTrajectory.to_vector` order):
    ``cond(W_b)`` at the design times, plus :data:`PENALTY` if a limit is violated at the
    check times (and, with ``problem.graded``, ``PENALTY`` times the summed relative excess
    over the limits)."""
    a, b, q0 = problem.split(x)
    c, s = problem.cond_basis
    q, qd, qdd = evaluate(a, b, q0, problem.kw, c, s)
    W = unchecked_regressor(problem.robot, q, qd, qdd)[..., jnp.asarray(problem.columns)]
    cond = _gram_condition_number(W.reshape(-1, len(problem.columns)))
    if problem.check_basis is not None:
        c, s = problem.check_basis
        q, qd, qdd = evaluate(a, b, q0, problem.kw, c, s)
    # largest |value| / limit per joint and kind; > 1 is a violation
    ratios = jnp.stack([jnp.max(jnp.abs(q - problem.centre), 0) / problem.half,
                        jnp.max(jnp.abs(qd), 0) / problem.qd_max,
                        jnp.max(jnp.abs(qdd), 0) / problem.qdd_max])
    violated = jnp.any(ratios > 1.0)
    penalty = PENALTY * violated
    if problem.graded:
        penalty = penalty + PENALTY * jnp.sum(jnp.maximum(ratios - 1.0, 0.0))
    return cond + penalty
