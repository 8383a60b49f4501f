"""The joint-torque regressor ``tau = Y(q, qd, qdd) P`` (the paper's Eq. 2).

Newton-Euler in the form that is linear in the inertial parameters (Khalil & Dombre,
*Modeling, Identification and Control of Robots*, 2002, Sec. 9.5; Atkeson, An & Hollerbach
1986), written so that every step is vectorised over the joints:

1. link poses in the base frame and every joint screw ``S_j`` there (``Ad_{T_0j} B_j``);
2. spatial twists and accelerations as cumulative sums over the chain (Lynch & Park 2017,
   Sec. 8.3): ``V_i = sum_{j<=i} S_j qd_j`` and
   ``dV_i = (0, -g) + sum_{j<=i} (S_j qdd_j + ad_{V_j} S_j qd_j)``;
3. link ``i``'s angular velocity ``w``, angular acceleration ``dw`` and the linear
   acceleration ``a`` of its origin (gravity included), in its own frame;
4. joint ``j``'s screw seen from link ``i``, ``(x, y) = Ad_{T_0i^-1} S_j`` (zero for
   ``j > i``); the torque of joint ``j`` due to link ``i``'s parameters is
   ``x . n_i + y . f_i`` with the Newton-Euler wrench about the origin (Khalil & Dombre
   2002, Eq. 9.83) ``n = I dw + w x (I w) + h x a``, ``f = m a + dw x h + w x (w x h)``,
   ``h = m c``. Expanded per parameter:

   - ``[Ixx Iyy Izz Ixy Ixz Iyz]``: ``L(dw)^T x + L(w)^T (x X w)`` with ``I u = L(u) I``,
   - ``m``: ``y . a``,
   - ``[mx my mz]``: ``a X x - dw X y + w X (w X y)``,

   and the friction columns ``sign(qd_j), qd_j`` on the diagonal.

Exact (no differentiation, no approximation), jit-compiled, batched over any leading axes.
On the CPU the samples are processed in chunks under ``lax.map`` (see :func:`chunk_size`)
so that the ``(n, n)`` intermediates stay in cache; on a GPU or TPU all at once, or in
chunks as large as a memory budget in bytes allows.
"""

from __future__ import annotations

import math
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float

from ._kinematics import cross, link_poses, rotate, rotate_back
from ._robot import Robot, joint_arrays

#: Bytes a batch of samples may take on an accelerator when no ``memory_budget`` is given.
DEFAULT_MEMORY_BUDGET = 2**30
#: The smallest ``memory_budget`` accepted (1 MB).
MIN_MEMORY_BUDGET = 10**6


def check_memory_budget(memory_budget: object) -> int:
    """``memory_budget`` in bytes (None: :data:`DEFAULT_MEMORY_BUDGET`); ValueError unless
    an integer >= :data:`MIN_MEMORY_BUDGET` (1 MB)."""
    if memory_budget is None:
        return DEFAULT_MEMORY_BUDGET
    if (isinstance(memory_budget, bool) or not isinstance(memory_budget, (int, np.integer))
            or memory_budget < MIN_MEMORY_BUDGET):
        raise ValueError(f"memory_budget must be an integer number of bytes >= 1 MB "
                         f"({MIN_MEMORY_BUDGET}), got {memory_budget!r}")
    return int(memory_budget)


def sample_bytes(n_joints: int, itemsize: int = 8) -> int:
    """An upper estimate of the memory one sample's regressor takes while computed: XLA's
    CPU code keeps about 22 n^2 numbers of intermediates and writes 12 n^2
    (``compile().memory_analysis()``, 3 and 7 joints); twice that, for other backends'
    fusion choices."""
    return 64 * n_joints**2 * itemsize


def chunk_size(n_joints: int, samples: int | None = None, *, itemsize: int = 8,
               memory_budget: int | None = None, backend: str | None = None) -> int | None:
    """Samples per ``lax.map`` chunk, None for all at once.

    On the CPU the intermediates grow as n^2 per sample and the fastest chunks are small:
    measured on a 2-core CPU (``python -m benchmarks.regressor``, 10,000 samples), 16 was
    fastest for 3 joints and 8 for 7 joints (1, 2, 4, 8, 16, 32 tried). On an accelerator
    (``backend``, default ``jax.default_backend()``) all ``samples`` at once (``vmap``),
    or when they would take more than ``memory_budget`` bytes (:func:`sample_bytes`;
    default :data:`DEFAULT_MEMORY_BUDGET`) the largest chunks within it."""
    budget = check_memory_budget(memory_budget)
    if (backend or jax.default_backend()) == "cpu":
        return 16 if n_joints <= 4 else 8
    per_sample = sample_bytes(n_joints, itemsize)
    if samples is not None and samples * per_sample <= budget:
        return None
    return max(1, budget // per_sample)


def unchecked_regressor(robot: Robot, q: Float[Array, "*batch n"], qd: Float[Array, "*batch n"],
                        qdd: Float[Array, "*batch n"]) -> Float[Array, "*batch n p"]:
    """The regressor for arrays of shape ``(..., n)`` without checks or chunking, for use
    inside code that is traced anyway (the excitation design's fitness)."""
    n = robot.n_joints
    dtype = q.dtype
    R0, p0 = link_poses(robot, q)
    S_w = rotate(R0, robot.screws[:, :3].astype(dtype))  # joint screws, base frame
    S_v = rotate(R0, robot.screws[:, 3:].astype(dtype)) + cross(p0, S_w)
    qd_, qdd_ = qd[..., None], qdd[..., None]
    V_w = jnp.cumsum(S_w * qd_, -2)  # spatial twist of each link
    V_v = jnp.cumsum(S_v * qd_, -2)
    A_w = jnp.cumsum(S_w * qdd_ + cross(V_w, S_w) * qd_, -2)
    A_v = jnp.cumsum(S_v * qdd_ + (cross(V_v, S_w) + cross(V_w, S_v)) * qd_, -2)
    A_v = A_v - robot.gravity.astype(dtype)  # the base accelerates against gravity
    # Body quantities of link i in its frame (Ad_{T_0i^-1} of the spatial ones).
    w = rotate_back(R0, V_w)
    v = rotate_back(R0, V_v + cross(V_w, p0))
    dw = rotate_back(R0, A_w)
    a = rotate_back(R0, A_v + cross(A_w, p0)) + cross(w, v)
    # Screw of joint j seen from link i: axes (..., j, i, 3); zero where j > i.
    upper = jnp.triu(jnp.ones((n, n), dtype))[..., None]
    R0i, p0i = R0[..., None, :, :, :], p0[..., None, :, :]
    Sj_w, Sj_v = S_w[..., :, None, :], S_v[..., :, None, :]
    x = rotate_back(R0i, Sj_w) * upper
    y = rotate_back(R0i, Sj_v + cross(Sj_w, p0i)) * upper
    w, dw, a = w[..., None, :, :], dw[..., None, :, :], a[..., None, :, :]
    u = cross(x, w)

    def c(k: int) -> tuple[Array, Array, Array, Array]:
        return x[..., k], u[..., k], w[..., k], dw[..., k]

    (x0, u0, w0, d0), (x1, u1, w1, d1), (x2, u2, w2, d2) = c(0), c(1), c(2)
    h = cross(a, x) - cross(dw, y) + cross(w, cross(w, y))
    eye = jnp.eye(n, dtype=dtype)
    columns = [
        d0 * x0 + w0 * u0,  # Ixx
        d1 * x1 + w1 * u1,  # Iyy
        d2 * x2 + w2 * u2,  # Izz
        d1 * x0 + d0 * x1 + w1 * u0 + w0 * u1,  # Ixy
        d2 * x0 + d0 * x2 + w2 * u0 + w0 * u2,  # Ixz
        d2 * x1 + d1 * x2 + w2 * u1 + w1 * u2,  # Iyz
        jnp.sum(y * a, -1),  # m
        h[..., 0], h[..., 1], h[..., 2],  # mx my mz
        eye * jnp.sign(qd)[..., None, :],  # Fc
        eye * qd[..., None, :],  # Fv
    ]
    Y = jnp.stack(columns, -1)  # (..., j, i, 12)
    return Y.reshape(Y.shape[:-2] + (12 * n,))


def _chunked(robot: Robot, q, qd, qdd, chunk: int | None):
    batch, n = q.shape[:-1], q.shape[-1]
    flat = [x.reshape((-1, n)) for x in (q, qd, qdd)]
    if chunk is None or chunk >= flat[0].shape[0]:
        Y = unchecked_regressor(robot, *flat)  # all samples at once
    else:
        Y = jax.lax.map(lambda s: unchecked_regressor(robot, *s), flat, batch_size=chunk)
    return Y.reshape(batch + Y.shape[1:])


@partial(jax.jit, static_argnames=("dtype", "chunk"))
def _regressor_jit(robot, q, qd, qdd, dtype, chunk=None):
    return _chunked(robot, q.astype(dtype), qd.astype(dtype), qdd.astype(dtype), chunk)


def padded_samples(samples: int, multiple: int = 1) -> int:
    """The number of samples :func:`padded_regressor` computes: ``samples`` rounded up to
    one of eight lengths per doubling (at most an eighth more; up to 15 samples exactly),
    then to a multiple of ``multiple`` (the ``lax.map`` chunk, whose remainder would
    compile a second body and double the compilation's time). Recordings of nearby
    lengths (a validation's outer splits, recordings of one motion) then share one
    compilation, which takes seconds and hundreds of memory maps; each sample's row is
    computed alone, so the padding (zeros) changes no row."""
    step = 1 << max(0, samples.bit_length() - 4)
    return -(-(-(-samples // step) * step) // multiple) * multiple


@partial(jax.jit, static_argnames="padded")
def _flat_padded(q, qd, qdd, padded: int):
    return [jnp.pad(x.reshape(-1, x.shape[-1]), ((0, padded - math.prod(x.shape[:-1])),
                                                 (0, 0))) for x in (q, qd, qdd)]


def _chunk(robot: Robot, samples: int, dtype, memory_budget) -> int | None:
    return chunk_size(robot.n_joints, samples, itemsize=jnp.dtype(dtype).itemsize,
                      memory_budget=memory_budget)


def _compiled(robot: Robot, q, qd, qdd, dtype, chunk: int | None, padded: int) -> Array:
    """:func:`_regressor_jit` at ``padded`` samples (flattened where more than given) in
    ``chunk``s (:func:`_chunk`)."""
    if padded > math.prod(q.shape[:-1]):
        q, qd, qdd = _flat_padded(q, qd, qdd, padded)
    return _regressor_jit(robot, q, qd, qdd, jnp.dtype(dtype), chunk)


def padded_regressor(robot: Robot, q: Float[ArrayLike, "*batch n"],
                     qd: Float[ArrayLike, "*batch n"], qdd: Float[ArrayLike, "*batch n"], *,
                     dtype: DTypeLike = jnp.float64, memory_budget: int | None = None
                     ) -> tuple[Float[Array, "S n p"], tuple[int, ...]]:
    """:func:`regressor` at :func:`padded_samples` samples, flattened, and the batch
    shape: ``(Y, batch)``, the rows past ``prod(batch)`` padding, for a caller that takes
    rows of it anyway (:func:`take`; the base regressor's columns), so that recordings of
    nearby lengths share one compilation."""
    check_memory_budget(memory_budget)
    q, qd, qdd = joint_arrays(robot, ("q", q), ("qd", qd), ("qdd", qdd), dtype=dtype)
    batch = q.shape[:-1]
    samples = math.prod(batch)
    if isinstance(q, jax.core.Tracer):
        padded, chunk = samples, _chunk(robot, samples, dtype, memory_budget)
    else:  # the chunk of the rounded length, then a multiple of it
        chunk = _chunk(robot, padded_samples(samples), dtype, memory_budget)
        padded = padded_samples(samples, chunk or 1)
    Y = _compiled(robot, q, qd, qdd, dtype, chunk, padded)
    return Y.reshape((-1,) + Y.shape[-2:]), batch


@partial(jax.jit, static_argnames=("batch", "columns"))
def take(Y: Float[Array, "S n p"], batch: tuple[int, ...], columns: tuple[int, ...]
         ) -> Float[Array, "*batch n c"]:
    """The rows of :func:`padded_regressor`'s ``Y`` that are samples, in their ``batch``
    shape, and their ``columns``: one copy."""
    return Y[:math.prod(batch), :, np.asarray(columns)].reshape(batch + Y.shape[1:2]
                                                                + (len(columns),))


def regressor(robot: Robot, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
              qdd: Float[ArrayLike, "*batch n"], *, dtype: DTypeLike = jnp.float64,
              memory_budget: int | None = None) -> Float[Array, "... n p"]:
    """Joint-torque regressor ``Y`` with ``tau = Y @ robot.params`` (Eq. 2).

    ``q, qd, qdd`` of shape ``(..., n)`` (leading axes broadcast) give ``(..., n, 12 n)``,
    columns ordered as :attr:`Robot.param_names`. Computed in ``dtype`` (float64 by
    default). ``memory_budget``: bytes the samples may take at once on an accelerator
    (:func:`chunk_size`; at least 1 MB). Compiled once per robot structure, batch shape,
    dtype and chunk size (:func:`padded_regressor`: once per rounded number of samples).
    """
    check_memory_budget(memory_budget)
    q, qd, qdd = joint_arrays(robot, ("q", q), ("qd", qd), ("qdd", qdd), dtype=dtype)
    samples = math.prod(q.shape[:-1])
    return _compiled(robot, q, qd, qdd, dtype, _chunk(robot, samples, dtype, memory_budget),
                     samples)


def inverse_dynamics(robot: Robot, params: Float[ArrayLike, " p"],
                     q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                     qdd: Float[ArrayLike, "*batch n"], *,
                     memory_budget: int | None = None) -> Float[Array, "... n"]:
    """Joint torques ``tau = Y(q, qd, qdd) @ params`` (Eq. 1-2), ``(..., n)``, float64;
    ``memory_budget`` as for :func:`regressor`."""
    check_memory_budget(memory_budget)
    q, qd, qdd = joint_arrays(robot, ("q", q), ("qd", qd), ("qdd", qdd))
    params = jnp.asarray(params, dtype=jnp.float64)
    if params.shape != (robot.n_params,):
        raise ValueError(
            f"params must have shape ({robot.n_params},) for robot {robot.name!r} "
            f"(12 per joint), got {params.shape}"
        )
    # Reuses the regressor's compiled code: one compilation serves both functions.
    samples = math.prod(q.shape[:-1])
    Y = _compiled(robot, q, qd, qdd, jnp.float64,
                  _chunk(robot, samples, jnp.float64, memory_budget), samples)
    return jnp.matmul(Y, params, precision=jax.lax.Precision.HIGHEST)
