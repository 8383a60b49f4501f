"""Forward kinematics of a :class:`~sedsabso_jax.Robot` (product of exponentials), and the
small 3-vector helpers the regressor shares."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ._robot import Robot, joint_arrays


def cross(a: Float[Array, "*batch 3"], b: Float[Array, "*batch 3"]
          ) -> Float[Array, "*batch 3"]:
    """Cross product over the last axis, written out so XLA fuses it."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return jnp.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rotate(R: Float[Array, "*batch 3 3"], x: Float[Array, "*batch 3"]
           ) -> Float[Array, "*batch 3"]:
    """R x over the last axes: R (..., 3, 3), x (..., 3). Small products are written as
    multiply-and-sum, which XLA fuses, rather than as many tiny ``dot`` calls."""
    return jnp.sum(R * x[..., None, :], axis=-1)


def rotate_back(R: Float[Array, "*batch 3 3"], x: Float[Array, "*batch 3"]
                ) -> Float[Array, "*batch 3"]:
    """R^T x over the last axes."""
    return jnp.sum(R * x[..., :, None], axis=-2)


def joint_transforms(robot: Robot, q: Float[Array, "*batch n"]
                     ) -> tuple[Float[Array, "*batch n 3 3"], Float[Array, "*batch n 3"]]:
    """Every link's pose in its parent's frame, ``T_fixed @ exp([screw] q)``.

    Returns R (..., n, 3, 3) and p (..., n, 3). ``exp`` by Lynch & Park 2017, Prop. 3.25:
    ``R = I + sin q [w] + (1 - cos q) [w]^2``, ``p = (q I + (1 - cos q) [w] + (q - sin q)
    [w]^2) v``, which for a prismatic screw (w = 0) reduces to ``R = I, p = q v``.
    """
    dtype = q.dtype
    w, v = robot.screws[:, :3].astype(dtype), robot.screws[:, 3:].astype(dtype)
    zero = jnp.zeros_like(w[:, 0])
    W = jnp.stack([jnp.stack([zero, -w[:, 2], w[:, 1]], -1),
                   jnp.stack([w[:, 2], zero, -w[:, 0]], -1),
                   jnp.stack([-w[:, 1], w[:, 0], zero], -1)], -2)  # (n, 3, 3)
    W2 = jnp.matmul(W, W, precision=jax.lax.Precision.HIGHEST)  # float32 stays float32
    s, c = jnp.sin(q)[..., None], jnp.cos(q)[..., None]
    Rm = jnp.eye(3, dtype=dtype) + s[..., None] * W + (1.0 - c)[..., None] * W2
    pm = q[..., None] * v + (1.0 - c) * rotate(W, v) + (q[..., None] - s) * rotate(W2, v)
    Rf, pf = robot.T_fixed[:, :3, :3].astype(dtype), robot.T_fixed[:, :3, 3].astype(dtype)
    return jnp.sum(Rf[:, :, :, None] * Rm[..., None, :, :], -2), rotate(Rf, pm) + pf


def link_poses(robot: Robot, q: Float[Array, "*batch n"]
               ) -> tuple[Float[Array, "*batch n 3 3"], Float[Array, "*batch n 3"]]:
    """Every link frame in the base frame: R0 (..., n, 3, 3), p0 (..., n, 3)."""
    R, p = joint_transforms(robot, q)
    Rs, ps = [R[..., 0, :, :]], [p[..., 0, :]]
    for i in range(1, robot.n_joints):
        ps.append(ps[-1] + rotate(Rs[-1], p[..., i, :]))
        Rs.append(jnp.sum(Rs[-1][..., :, :, None] * R[..., i, None, :, :], -2))
    return jnp.stack(Rs, -3), jnp.stack(ps, -2)


@jax.jit
def _forward_kinematics(robot: Robot, q):
    R0, p0 = link_poses(robot, q)
    top = jnp.concatenate([R0, p0[..., None]], axis=-1)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0], q.dtype), top.shape[:-2] + (1, 4))
    return jnp.concatenate([top, bottom], axis=-2)


def forward_kinematics(robot: Robot, q: Float[ArrayLike, "*batch n"]
                       ) -> Float[Array, "... n 4 4"]:
    """Pose of every link frame in the base frame: ``(..., n) -> (..., n, 4, 4)``."""
    (q,) = joint_arrays(robot, ("q", q))
    return _forward_kinematics(robot, q)
