"""Friction at rest: :class:`Presliding`, a term whose columns integrate Dahl's
presliding state along each recording (:mod:`._friction_state`), registered after the
terms of :mod:`._terms` (its columns come last)."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
from typing import ClassVar

import equinox as eqx
import numpy as np

from ._friction_state import presliding_state
from ._scales import AbstractScale, as_scale
from ._term_base import Signals, TorqueModelView, diagonal

#: Characteristic displacement (rad or m) of :class:`Presliding` unless told.
PRESLIDING_DISPLACEMENT = 0.002


class Presliding(AbstractScale):
    """``FP_j z_j``: friction that a joint holds at rest and after a reversal builds up
    over a displacement, Dahl's model (:mod:`._friction_state`): ``z_j`` the presliding
    state, integrated along the recorded positions (``dz/dq = (1 - z sign(qd)) / q_c``),
    ``FP_j >= 0`` (N m or N) the friction it saturates at. Beside the Coulomb column
    ``FC_j sign(qd_j)``, which it equals in steady sliding, it adds what sliding friction
    does not predict: the torque held while the joint stands still and the gradual
    reversal. ``displacement`` is ``q_c`` (rad or m, > 0: one, one per joint, or with
    ``fitted=True`` one per joint searched by the fit within :attr:`bounds`). The columns
    need each recording's samples in time order (:attr:`stateful`)."""

    displacement: float | tuple[float, ...] = eqx.field(default=PRESLIDING_DISPLACEMENT,
                                                        converter=as_scale)
    fitted: bool = False
    name: ClassVar[str] = "presliding"
    nonnegative: ClassVar[bool] = True
    #: The displacements' search box (rad or m).
    bounds: ClassVar[tuple[float, float]] = (1e-5, 0.5)
    scale_name: ClassVar[str] = "displacement"
    scale_unit: ClassVar[str] = "rad or m"
    default_scale: ClassVar[float] = PRESLIDING_DISPLACEMENT
    symbol: ClassVar[str] = "q_c"

    @property
    def stateful(self) -> bool:
        return True

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        n = model.robot.n_joints
        self.per_joint(n)
        return tuple(f"FP{j + 1}" for j in range(n))

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        n = model.robot.n_joints
        z = presliding_state(s.q, s.recording, self.per_joint(n))
        return diagonal(z, s.q.shape[:-1], n)

    def coulomb(self, qd: np.ndarray) -> None:
        return None
