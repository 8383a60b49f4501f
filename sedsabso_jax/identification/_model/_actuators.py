"""What the motors add at the joints: their rotor inertia (:class:`Armature`) and the
friction of a motor that turns with several joints (:class:`CoupledMotorFriction`).
``K`` is the model's transmission (motor angles ``theta = K q``; ``K = 1`` without
one)."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
from typing import Any, ClassVar

import jax.numpy as jnp
import numpy as np

from ._term import AbstractTerm, InSimulator, ModelView, Signals, through_motors


class Armature(AbstractTerm):
    """``K_m^T IA_m (K_m . qdd)``: the rotor inertia ``IA_m`` of motor ``m`` (kg m^2,
    motor side), ``>= 0``. Without a transmission ``K = 1``: joint ``j``'s column is
    ``qdd_j``; with a diagonal ``K`` its effect at the joint is ``N_j^2 IA_j``."""

    name: ClassVar[str] = "armature"
    unit: ClassVar[str] = "kg m^2 for a rotor inertia IA (motor-side)"
    nonnegative: ClassVar[bool] = True

    def names(self, model: ModelView) -> tuple[str, ...]:
        return tuple(f"IA{m + 1}" for m in range(model.robot.n_joints))

    def columns(self, model: ModelView, s: Signals) -> Any:
        return through_motors(model.motor_matrix, list(range(model.robot.n_joints)),
                              s.qdd)

    held_in_full: ClassVar[bool] = True

    def held(self, model: ModelView, values: np.ndarray) -> InSimulator:
        """The joint-side rotor inertia ``diag(K^T IA K)``; a transmission that couples
        joints also couples their accelerations, which a per-joint armature cannot hold."""
        K = np.asarray(model.motor_matrix, float)
        inertia = K.T @ np.diag(np.asarray(values, float)) @ K
        coupled = inertia - np.diag(np.diag(inertia))
        return InSimulator(armature=np.diag(inertia).copy(), lost=(
            f"the coupled rotor inertia off the diagonal (up to {np.abs(coupled).max():.3g} "
            f"kg m^2)" if np.any(coupled) else ""))


class CoupledMotorFriction(AbstractTerm):
    """``K_m^T (FVM_m u_m + FCM_m sign(u_m))`` with ``u_m = K_m . qd``: the viscous and
    Coulomb friction (motor side, ``>= 0``) of each motor ``m`` that turns with several
    joints (a coupled wrist), which no single joint's friction describes. Columns
    ``FVM..`` then ``FCM..``, motors numbered from 1; the model's transmission must
    couple a motor."""

    name: ClassVar[str] = "coupling"
    unit: ClassVar[str] = ("N m s/rad and N m for a coupled motor's viscous and Coulomb "
                           "friction FVM, FCM (motor-side)")
    nonnegative: ClassVar[bool] = True

    def names(self, model: ModelView) -> tuple[str, ...]:
        motors = model.coupled_motors
        if not motors:
            raise ValueError("friction term 'coupling' needs a transmission with a motor that "
                             "turns several joints (a coupling)")
        return tuple(f"{k}{m + 1}" for k in ("FVM", "FCM") for m in motors)

    def columns(self, model: ModelView, s: Signals) -> Any:
        K, motors, qd = model.motor_matrix, list(model.coupled_motors), s.qd
        return jnp.concatenate([through_motors(K, motors, qd),
                               through_motors(K, motors, qd, sign=True)], -1)
