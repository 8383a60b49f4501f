"""Friction at rest: :class:`Presliding`, a term whose columns carry Dahl's presliding
state along each recording (:mod:`._dahl`)."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
from typing import Any, ClassVar

import numpy as np

from ._dahl import dahl_state
from ._scales import AbstractScale, scale
from ._term import InSimulator, ModelView, Signals, diagonal

#: Characteristic displacement (rad or m) of :class:`Presliding` unless told.
PRESLIDING_DISPLACEMENT = 0.002
#: How :class:`Presliding`'s state may be integrated.
SCANS = ("auto", "sequential", "associative")
#: The largest displacement (rad or m) the default's friction at rest searches
#: (``Presliding(fitted=True, largest=...)``, :data:`~.._validation._kept_terms.KEPT_TERMS`):
#: presliding is the contacts' small elastic deformation before they slide, and the
#: larger displacements a search finds are a slow hysteresis that predicts held-out
#: motion worse (the measurements: docs/explanation/identification-defaults.md).
LARGEST_AT_REST = 0.02


class Presliding(AbstractScale):
    """``FP_j z_j``: friction that a joint holds at rest and after a reversal builds up
    over a displacement, Dahl's model (:mod:`._dahl`): ``z_j`` the presliding state,
    integrated along the recorded positions (``dz/dq = (1 - z sign(qd)) / q_c``), each
    recording from ``z = 0``, ``FP_j >= 0`` (N m or N) the friction it saturates at.
    Beside the Coulomb column ``FC_j sign(qd_j)``, which it equals in steady sliding, it
    adds what sliding friction does not predict: the torque held while the joint stands
    still and the gradual reversal. ``displacement`` is ``q_c`` (rad or m, > 0: one, one
    per joint, or with ``fitted=True`` one per joint searched by the fit within its
    declared bounds, 1e-5 to 0.5 rad, up to ``largest`` where given:
    ``presliding:fit:0.02`` in the command line's text). The columns read each
    recording's samples in time order, whole: a split's rows are the whole recording's,
    taken. ``scan``: how the state is
    integrated, ``"sequential"`` (a ``lax.scan``), ``"associative"`` (a prefix
    composition, parallel in time) or ``"auto"``, per backend (:data:`~._dahl.SEQUENTIAL`)."""

    displacement: float | tuple[float, ...] = scale(
        PRESLIDING_DISPLACEMENT, bounds=(1e-5, 0.5), unit="rad", symbol="q_c")
    fitted: bool = False
    scan: str = "auto"
    largest: float | None = None
    narrowed_by: ClassVar[tuple[str, int] | None] = ("largest", 1)
    narrowed_example: ClassVar[float] = LARGEST_AT_REST
    name: ClassVar[str] = "presliding"
    unit: ClassVar[str] = "N m for friction at rest FP (the torque it saturates at)"

    def held(self, model: ModelView, values: Any) -> InSimulator:
        """Dry friction: ``FP`` is the torque it saturates at in steady sliding, which a
        simulator's dry friction (MuJoCo's ``frictionloss``, a constraint that also holds
        the joint at rest) adds to the Coulomb level."""
        return InSimulator(frictionloss=np.asarray(values, dtype=float),
                           lost="its gradual build-up over the displacement q_c after a "
                           "reversal (a simulator's dry friction turns at once)")
    nonnegative: ClassVar[bool] = True

    def __check_init__(self):  # equinox also runs AbstractScale's
        if self.scan not in SCANS:
            raise ValueError(f"Presliding's scan must be one of {SCANS}, got {self.scan!r}")

    def names(self, model: ModelView) -> tuple[str, ...]:
        n = model.robot.n_joints
        self.check_joints(n)
        return tuple(f"FP{j + 1}" for j in range(n))

    def columns(self, model: ModelView, s: Signals) -> Any:
        n = model.robot.n_joints
        dq, start = s.increments()
        sequential = None if self.scan == "auto" else self.scan == "sequential"
        z = dahl_state(dq, start, self.per_joint(n), sequential=sequential)
        return diagonal(z, n)

    def settings(self) -> dict:
        out = super().settings()
        return out if self.scan == "auto" else {**out, "presliding_scan": self.scan}
