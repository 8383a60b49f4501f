"""A payload as a torque-model term (:class:`PayloadInertia`): the inertial parameters
of a body fixed to one link, in the recordings that carry it, and where the body sits
(:func:`payload_frame`)."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import os
from typing import Any, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ...dynamics._inertia import transform_params
from ...dynamics._regressor import regressor
from ...dynamics._robot import LINK_PARAMETERS, N_LINK_PARAMETERS, Robot
from ...dynamics._urdf import fixed_link_pose
from .._model._term import AbstractTerm, ModelView, Signals

#: The payload's parameter names, in :attr:`~._payload.Payload.params10`'s order.
PAYLOAD_PARAMETERS = LINK_PARAMETERS[:10]


def frame_map(T: np.ndarray) -> np.ndarray:
    """``A`` with ``p_link = A p_frame`` for a frame at pose ``T`` in the link's frame
    (the change of a body's 10 inertial parameters, linear)."""
    return np.stack([transform_params(T, e) for e in np.eye(10)], axis=1)


def payload_frame(robot: Robot, link: str, urdf: str | os.PathLike[str] | None
                  ) -> tuple[int, np.ndarray]:
    """``(index of the moving link, pose of link's frame in it)``; a ValueError for a link
    the robot (or its URDF) lacks."""
    if not isinstance(link, str):
        raise TypeError(f"link must be a link name (robot.link_names), got {link!r}")
    if link in robot.link_names:
        return robot.link_names.index(link), np.eye(4)
    if urdf is None:
        raise ValueError(f"link {link!r} is not a moving link of robot {robot.name!r} "
                         f"({', '.join(robot.link_names)}); a link fixed to one (a flange, "
                         f"tool0) needs the robot's URDF (urdf=, --robot FILE.urdf)")
    moving, T = fixed_link_pose(urdf, link, robot.link_names)
    return robot.link_names.index(moving), T


def _as_frame(value: object) -> object:
    """A 4x4 pose as 16 floats (row by row); anything else as given."""
    try:
        T = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return value
    return tuple(float(v) for v in T.reshape(-1)) if T.shape == (4, 4) else value


class PayloadInertia(AbstractTerm):
    """``Y_k A p`` on the rows of the recordings that carry the payload: link ``link``'s
    10 inertial columns of the full regressor (``XX YY ZZ XY XZ YZ M MX MY MZ``), times
    ``A``, the change from the payload's ``frame`` (a 4x4 pose in the link's frame) to
    the link's (:func:`frame_map`): the payload's inertial parameters ``p`` in its own
    frame, a body (:attr:`body`: physically consistent fits constrain it as they do the
    links). ``carried``: the recordings (indices) with the payload; rows of no recording
    (a new motion) carry it."""

    link: int
    frame: tuple[float, ...] = eqx.field(converter=_as_frame)
    carried: tuple[int, ...] = eqx.field(converter=tuple)
    name: ClassVar[str] = "payload"
    unit: ClassVar[str] = "the payload's inertial parameters payload_* as a body's"
    nonnegative: ClassVar[bool] = False

    def __check_init__(self):
        if not (isinstance(self.frame, tuple) and len(self.frame) == 16
                and np.all(np.isfinite(self.frame))):
            raise ValueError(f"frame must be a finite 4x4 pose, got {self.frame!r}")
        if not all(isinstance(r, (int, np.integer)) and r >= 0 for r in self.carried):
            raise ValueError(f"carried must be recording indices >= 0, got {self.carried!r}")

    @property
    def body(self) -> bool:
        return True

    def names(self, model: ModelView) -> tuple[str, ...]:
        if not 0 <= self.link < model.robot.n_joints:
            raise ValueError(f"link must be a moving link's index in [0, "
                             f"{model.robot.n_joints}), got {self.link}")
        return tuple(f"payload_{p}" for p in PAYLOAD_PARAMETERS)

    def columns(self, model: ModelView, s: Signals) -> Any:
        k = N_LINK_PARAMETERS * self.link
        A = frame_map(np.asarray(self.frame).reshape(4, 4))
        Y = regressor(model.robot, s.q, s.qd, s.qdd)[..., k:k + 10] @ A
        if s.recording is None:
            return Y
        on = jnp.isin(jnp.asarray(s.recording), np.asarray(self.carried, dtype=int))
        return jnp.where(on[..., None, None], Y, 0.0)

    def settings(self) -> dict:
        return {"payload_link": self.link, "payload_carried": list(self.carried)}
