"""The torque model an identification fits: the base regressor plus friction terms.

Model (``friction``, terms joined by ``+``)::

    tau = Yb(q, qd, qdd) beta                   base regressor, Coulomb + viscous friction
          + OFF_j                               "offset": a constant torque per joint
          + FQ_j qd_j |qd_j|                    "quadratic": velocity-squared friction
    sign(qd_j) -> tanh(qd_j / smooth_velocity)  "smooth": Coulomb term without the jump

The extra columns come after the base columns, named ``OFF1..OFFn`` and ``FQ1..FQn``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import _deprecation
from ..dynamics.base_parameters import BaseParameters
from ..dynamics.robot import N_LINK_PARAMETERS, Robot

FRICTION_TERMS = ("viscous-coulomb", "offset", "quadratic", "smooth")
#: Velocity scale (rad/s or m/s) of the "smooth" Coulomb term tanh(qd / v).
SMOOTH_VELOCITY = 0.02


@dataclasses.dataclass(frozen=True, eq=False)
class TorqueModel:
    """A linear torque model: the base regressor of ``robot`` plus extra friction terms
    (see the module docstring).

    ``regressor(q, qd, qdd)`` is ``(..., n, d)`` with ``d = base.rank + len(extras) * n``;
    ``predict(values, q, qd, qdd)`` is ``regressor @ values``.
    """

    base: BaseParameters
    friction: str = "viscous-coulomb"
    smooth_velocity: float = SMOOTH_VELOCITY

    @property
    def robot(self) -> Robot:
        return self.base.robot

    @property
    def terms(self) -> tuple[str, ...]:
        return tuple(self.friction.split("+"))

    @property
    def extras(self) -> tuple[str, ...]:
        """Extra column groups in order: ``"OFF"`` and/or ``"FQ"``."""
        return tuple(k for t, k in (("offset", "OFF"), ("quadratic", "FQ")) if t in self.terms)

    @property
    def names(self) -> tuple[str, ...]:
        n = self.robot.n_joints
        return tuple(self.base.names) + tuple(f"{k}{j + 1}" for k in self.extras
                                              for j in range(n))

    @property
    def dim(self) -> int:
        return self.base.rank + len(self.extras) * self.robot.n_joints

    def regressor(self, q, qd, qdd) -> np.ndarray:
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        Y = np.asarray(self.base.regressor(q, qd, qdd))
        n = self.robot.n_joints
        batch = Y.shape[:-2]
        qd = np.broadcast_to(qd, batch + (n,))
        rows = np.arange(n)
        if "smooth" in self.terms:
            Y = Y.copy()
            Y[..., rows, self._fc_columns()] = np.tanh(qd / self.smooth_velocity)
        cols = [Y]
        for k in self.extras:
            E = np.zeros(batch + (n, n))
            E[..., rows, rows] = 1.0 if k == "OFF" else qd * np.abs(qd)
            cols.append(E)
        return np.concatenate(cols, -1) if len(cols) > 1 else Y

    def predict(self, values, q, qd, qdd) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        if values.shape != (self.dim,):
            raise ValueError(f"values must have shape ({self.dim},), got {values.shape}")
        return self.regressor(q, qd, qdd) @ values

    def _fc_columns(self) -> np.ndarray:
        """Base column of each joint's Coulomb coefficient (friction never regroups)."""
        full = [self.base.indices.index(N_LINK_PARAMETERS * j + 10)
                if N_LINK_PARAMETERS * j + 10 in self.base.indices else -1
                for j in range(self.robot.n_joints)]
        if min(full) < 0:
            raise ValueError("friction='...+smooth' needs every joint's Coulomb column in the "
                             "base set")
        return np.asarray(full)


def canonical_friction(friction) -> str:
    """``friction`` with its terms checked, ``viscous-coulomb`` added, in canonical order."""
    if not isinstance(friction, str) or not friction:
        raise ValueError(f"friction must be a string of terms joined by '+' from "
                         f"{FRICTION_TERMS}, got {friction!r}")
    terms = {t.strip() for t in friction.split("+")}
    unknown = terms - set(FRICTION_TERMS)
    if unknown:
        raise ValueError(f"unknown friction term(s) {sorted(unknown)}; known: {FRICTION_TERMS} "
                         f"(joined by '+', e.g. 'viscous-coulomb+offset')")
    terms.add("viscous-coulomb")
    return "+".join(t for t in FRICTION_TERMS if t in terms)


__getattr__ = _deprecation.module_getattr(__name__, {
    "Model": ("sedsabso_jax.identification.model", "TorqueModel"),
})
