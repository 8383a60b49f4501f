"""Friction of each joint's own velocity beyond the base regressor's viscous and Coulomb
friction: :class:`Quadratic`, :class:`SmoothCoulomb` and :class:`Stribeck`."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import abc
from typing import Any, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ._scales import AbstractScale, scale
from ._term import AbstractTerm, InSimulator, ModelView, Signals, diagonal

#: Velocity scale (rad/s or m/s) of :class:`SmoothCoulomb` unless told.
SMOOTH_VELOCITY = 0.02
#: Stribeck velocity (rad/s or m/s) of :class:`Stribeck` unless told.
STRIBECK_VELOCITY = 0.1
#: The box a fit searches a velocity scale in (rad/s or m/s).
VELOCITY_BOUNDS = (1e-4, 1.0)


class AbstractJointFriction(AbstractTerm):
    """A friction term of each joint's own velocity: one column per joint, ``PREFIXj``,
    with :meth:`torque` on the joint's own row."""

    prefix: eqx.AbstractClassVar[str]

    @abc.abstractmethod
    def torque(self, s: Signals) -> Any:
        """Each joint's column value at the samples of ``s``, ``(..., n)``."""

    def names(self, model: ModelView) -> tuple[str, ...]:
        return tuple(f"{self.prefix}{j + 1}" for j in range(model.robot.n_joints))

    def columns(self, model: ModelView, s: Signals) -> Any:
        return diagonal(self.torque(s), model.robot.n_joints)


class Quadratic(AbstractJointFriction):
    """``FQ_j qd_j |qd_j|``: friction growing with the velocity squared (a lubricant's
    drag at speed), ``>= 0`` for a physical body."""

    name: ClassVar[str] = "quadratic"
    unit: ClassVar[str] = "N m s^2/rad^2 for velocity-squared friction FQ"
    prefix: ClassVar[str] = "FQ"
    nonnegative: ClassVar[bool] = True

    def torque(self, s: Signals) -> Any:
        return s.qd * jnp.abs(s.qd)


class SmoothCoulomb(AbstractScale):
    """Coulomb friction without the jump at rest: ``tanh(qd_j / velocity)`` in place of
    ``sign(qd_j)`` in each joint's Coulomb column (``velocity`` in rad/s or m/s, > 0:
    one, one per joint, or with ``fitted=True`` one per joint searched by the fit within
    its declared bounds, 1e-4 to 1 rad/s, from ``smallest`` up where given:
    ``smooth:fit:0.02`` in the command line's text); no columns of its own."""

    velocity: float | tuple[float, ...] = scale(SMOOTH_VELOCITY, bounds=VELOCITY_BOUNDS,
                                                unit="rad/s", symbol="v_smooth")
    fitted: bool = False
    smallest: float | None = None
    narrowed_by: ClassVar[tuple[str, int] | None] = ("smallest", 0)
    narrowed_example: ClassVar[float] = SMOOTH_VELOCITY
    name: ClassVar[str] = "smooth"
    nonnegative: ClassVar[bool] = False

    def names(self, model: ModelView) -> tuple[str, ...]:
        if None in model.base.joint_columns("FC"):
            raise ValueError("the smooth Coulomb term needs every joint's Coulomb column in "
                             "the base set")
        self.check_joints(model.robot.n_joints)
        return ()

    def columns(self, model: ModelView, s: Signals) -> Any:
        return jnp.zeros(s.batch + (model.robot.n_joints, 0))

    def coulomb(self, qd: Any) -> Any:
        return jnp.tanh(qd / self.per_joint(qd.shape[-1]))

    def held(self, model: ModelView, values: np.ndarray) -> InSimulator:
        """The Coulomb level is the simulator's (MuJoCo's ``frictionloss``); the shape near
        rest is its solver's, not ``tanh``."""
        return InSimulator(lost=f"the tanh(qd/v) shape of the Coulomb friction near rest (v = "
                         f"{', '.join(f'{v:.3g}' for v in np.atleast_1d(self.velocity))})")


class Stribeck(AbstractScale):
    """``FS_j exp(-(qd_j / velocity)^2) c_j(qd)``: the friction above Coulomb's that
    a joint shows near rest and loses as it speeds up (Stribeck's curve; ``FS_j >= 0``,
    the static friction's excess), ``velocity`` the Stribeck velocity (rad/s or m/s,
    > 0: one, one per joint, or fitted), ``c_j`` the model's Coulomb shape. Its columns
    are ``FS1..``."""

    velocity: float | tuple[float, ...] = scale(STRIBECK_VELOCITY, bounds=VELOCITY_BOUNDS,
                                                unit="rad/s", symbol="v_stribeck")
    fitted: bool = False
    name: ClassVar[str] = "stribeck"
    unit: ClassVar[str] = "N m for Stribeck's excess friction FS"
    nonnegative: ClassVar[bool] = True

    def names(self, model: ModelView) -> tuple[str, ...]:
        n = model.robot.n_joints
        self.check_joints(n)
        return tuple(f"FS{j + 1}" for j in range(n))

    def columns(self, model: ModelView, s: Signals) -> Any:
        n = model.robot.n_joints
        return diagonal(jnp.exp(-(s.qd / self.per_joint(n)) ** 2) * s.coulomb, n)
