"""The checks of a torque model given to an identification (:func:`model_of`) and the
warning of the columns it leaves out (:func:`regrouped_message`)."""

from __future__ import annotations

from ...dynamics._robot import Robot
from ._torque_model import TorqueModel


def model_of(robot: Robot, model: TorqueModel | None) -> TorqueModel:
    """``model``, checked to be a :class:`TorqueModel` of ``robot``; None: the robot's
    rigid-body model with viscous and Coulomb friction."""
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
    if model is None:
        return TorqueModel.of(robot)
    if not isinstance(model, TorqueModel):
        raise TypeError(f"model must be a TorqueModel (TorqueModel.of(robot, terms); "
                        f"parse_friction reads the command line's 'a+b' text), got {model!r}")
    if model.robot.n_params != robot.n_params or model.robot.n_joints != robot.n_joints:
        raise ValueError(f"model is a TorqueModel of robot {model.robot.name!r} with "
                         f"{model.robot.n_joints} joints, not of {robot.name!r}")
    return model


def regrouped_message(model: TorqueModel) -> str:
    """The warning that extra columns of ``model`` were left out."""
    return (f"identify: {', '.join(model.regrouped)} cannot be identified apart from the base "
            f"parameters (their columns are in the base regressor's span); left out of the "
            f"model")
