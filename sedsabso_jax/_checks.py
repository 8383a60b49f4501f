"""Input checks shared by the public functions: clear errors before anything compiles."""

from __future__ import annotations

import jax.numpy as jnp


def joint_arrays(robot, *named_arrays: tuple[str, object], dtype=jnp.float64):
    """Convert joint-space arrays to ``dtype`` and check each ends in ``robot.n_joints``.

    Leading (batch) axes must broadcast against each other; the broadcast arrays are
    returned.
    """
    n = robot.n_joints
    arrays = []
    for name, value in named_arrays:
        try:
            arr = jnp.asarray(value, dtype=dtype)
        except (TypeError, ValueError) as err:
            raise TypeError(f"{name} must be a numeric array, got {type(value).__name__}") from err
        if arr.ndim == 0 or arr.shape[-1] != n:
            raise ValueError(
                f"{name} must have shape (..., {n}) for robot {robot.name!r} with {n} joints, "
                f"got shape {arr.shape}"
            )
        arrays.append(arr)
    try:
        shape = jnp.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError as err:
        shapes = ", ".join(f"{name} {a.shape}" for (name, _), a in zip(named_arrays, arrays))
        raise ValueError(f"batch shapes do not broadcast: {shapes}") from err
    return [jnp.broadcast_to(a, shape) for a in arrays]
