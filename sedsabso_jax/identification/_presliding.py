"""Friction at rest: :class:`Presliding`, a term whose columns integrate Dahl's
presliding state along each recording (:mod:`._friction_state`), registered after the
terms of :mod:`._terms` (its columns come last)."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import dataclasses
from typing import ClassVar

import equinox as eqx
import numpy as np

from ._friction_state import presliding_state
from ._scales import as_scale, check_scale, per_joint, searched
from ._term_base import AbstractTerm, Shapes, Signals, TorqueModelView, diagonal

#: Characteristic displacement (rad or m) of :class:`Presliding` unless told.
PRESLIDING_DISPLACEMENT = 0.002


class Presliding(AbstractTerm):
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

    def __check_init__(self):
        check_scale("Presliding's displacement", self.displacement)
        if not isinstance(self.fitted, bool):
            raise ValueError(f"Presliding's fitted must be True or False, got {self.fitted!r}")

    @property
    def stateful(self) -> bool:
        return True

    def per_joint(self, n: int) -> np.ndarray:
        """The displacement ``q_c`` of each of ``n`` joints."""
        return per_joint("presliding's displacement", self.displacement, n)

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

    @property
    def text(self) -> str:
        d = self.displacement
        if self.fitted:
            return "presliding:fit"
        if d == PRESLIDING_DISPLACEMENT:
            return "presliding"
        return "presliding:" + (f"{d:g}" if isinstance(d, float) else ",".join(f"{v:g}"
                                                                               for v in d))

    @classmethod
    def parse(cls, option: str | None) -> AbstractTerm:
        if option is None or option == "fit":
            return cls(fitted=option == "fit")
        try:
            values = [float(v) for v in option.split(",")]
        except ValueError:
            raise ValueError(f"friction term 'presliding': expected presliding:fit or "
                             f"presliding:DISPLACEMENT (rad or m, one or one per joint, "
                             f"comma-separated), got presliding:{option}") from None
        return cls(values[0] if len(values) == 1 else tuple(values))

    def shapes(self, model: TorqueModelView) -> Shapes | None:
        if not self.fitted:
            return None
        return searched("q_c", self.per_joint(model.robot.n_joints), self.bounds)

    def with_shapes(self, values: np.ndarray) -> AbstractTerm:
        return dataclasses.replace(self, displacement=tuple(float(v) for v in values))

    def settings(self) -> dict:
        d = self.displacement
        out: dict = {"presliding_displacement": list(d) if isinstance(d, tuple) else d}
        if self.fitted:
            out["presliding_fitted"] = True
        return out
