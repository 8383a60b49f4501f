"""A torque sensor's zero: :class:`Offset`, one per joint, or one per joint and
recording."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
from typing import Any, ClassVar

import jax.numpy as jnp
import numpy as np

from ._term import AbstractTerm, InSimulator, ModelView, Signals


class Offset(AbstractTerm):
    """``OFF_j``: a constant torque per joint (a torque sensor's zero). With a model of
    ``R > 1`` recordings, one per joint and recording, ``OFFj.r``: rows of recording ``r``
    carry 1 in column ``OFFj.r``, rows of no recording (new motions) ``1/R`` in each,
    the offsets' mean."""

    name: ClassVar[str] = "offset"
    unit: ClassVar[str] = "N m for a torque offset OFF"
    nonnegative: ClassVar[bool] = False

    def names(self, model: ModelView) -> tuple[str, ...]:
        n, R = model.robot.n_joints, model.recordings
        if R > 1:
            return tuple(f"OFF{j + 1}.{r + 1}" for j in range(n) for r in range(R))
        return tuple(f"OFF{j + 1}" for j in range(n))

    def columns(self, model: ModelView, s: Signals) -> Any:
        n, R, batch = model.robot.n_joints, model.recordings, s.batch
        if R == 1:
            return jnp.broadcast_to(jnp.eye(n), batch + (n, n))
        if s.recording is None:
            share = jnp.full(batch + (R,), 1.0 / R)
        else:
            index = np.asarray(s.recording)
            if index.shape != batch or index.dtype.kind not in "iu" or (
                    index.size and (index.min() < 0 or index.max() >= R)):
                raise ValueError(f"recording must hold one integer in [0, {R}) per sample "
                                 f"{batch}, got shape {index.shape}")
            share = jnp.asarray((index[..., None] == np.arange(R)).astype(float))
        # joint j's row: its recording's indicator
        E = jnp.zeros(batch + (n, n, R)).at[..., np.arange(n), np.arange(n), :].set(
            share[..., None, :])
        return E.reshape(batch + (n, n * R))

    held_in_full: ClassVar[bool] = True

    def held(self, model: ModelView, values: np.ndarray) -> InSimulator:
        """The actuators' bias: each joint's offset (with one per recording, their mean,
        as new motions get)."""
        n = model.robot.n_joints
        return InSimulator(offset=np.asarray(values, float).reshape(n, -1).mean(axis=1))
