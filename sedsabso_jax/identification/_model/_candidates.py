"""The torque models the default chooses among (:data:`FRICTION_CANDIDATES`,
:func:`candidate_models`)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ...dynamics._base_parameters import BaseParameters, base_parameters
from ...dynamics._robot import Robot
from ...measurements._transmission import TransmissionLike, coupled_motors
from .._default._policy import DEFAULT
from ._actuators import CoupledMotorFriction
from ._offset import Offset
from ._term import AbstractTerm
from ._torque_model import TorqueModel

#: The candidate torque models' terms of :func:`~sedsabso_jax.select_model`
#: (:attr:`~.._default._policy.Default.frictions` of the default).
FRICTION_CANDIDATES: tuple[tuple[AbstractTerm, ...], ...] = DEFAULT.frictions


def candidate_models(robot: Robot,
                     frictions: Iterable[Iterable[AbstractTerm]] = FRICTION_CANDIDATES, *,
                     transmission: TransmissionLike = None, recordings: int = 1,
                     base: BaseParameters | None = None) -> tuple[TorqueModel, ...]:
    """The torque models of ``robot`` with each set of terms of ``frictions`` (default
    :data:`FRICTION_CANDIDATES`), simplest first: with the
    :class:`~._actuators.CoupledMotorFriction` where ``transmission`` couples a motor,
    with one :class:`~._offset.Offset` per recording for ``recordings > 1``, the base
    parameters computed once (``base``: given), and each model once (``()`` and
    ``(Offset(),)`` are one model with offsets per recording). Where a joint's Coulomb
    column regroups with other base columns, the default candidates keep the jump: a
    term that shapes the Coulomb columns (:meth:`~._term.AbstractTerm.coulomb`, the
    smooth Coulomb) is left out."""
    if base is None:
        base = base_parameters(robot)
    model = TorqueModel.of(robot, transmission=transmission, base=base)
    coupled = bool(coupled_motors(model.motor_matrix))
    models: list[TorqueModel] = []
    for terms in frictions:
        terms = tuple(terms)
        added = ((CoupledMotorFriction(),) if coupled else ()) + (
            (Offset(),) if recordings > 1 else ())
        terms += tuple(t for t in added if t not in terms)
        if frictions is FRICTION_CANDIDATES and None in base.joint_columns("FC"):
            still = np.zeros((1, robot.n_joints))
            terms = tuple(t for t in terms if t.coulomb(still) is None)
        model = TorqueModel.of(robot, terms, transmission=transmission, base=base,
                               recordings=recordings)
        if all(m.friction != model.friction for m in models):
            models.append(model)
    return tuple(models)
