"""The equations of the drive gains, the robot's torque model and a payload of known mass
(Gautier & Briot, "Global identification of joint drive gains and dynamic parameters of
robots", ASME J. Dyn. Sys., Meas., Control 136(5), 2014).

The recordings hold, in place of torques, what the drives report: a current ``c_m`` per
motor. Motor ``m``'s torque is ``g_m c_m`` (its drive gain ``g_m``, torque per unit of
current), and the joints' torques are ``K^T (g * c)`` (``K`` the transmission, motor
angles from joint angles; ``K = 1`` when the currents are the joints' own). With the
torque model's regressor ``Y`` (base parameters and the model's terms, values ``x``) and
the payload's columns ``Y_p`` on the loaded recordings (:class:`~.._payload._term.PayloadInertia`,
its 10 inertial parameters ``p`` in its own frame)::

    Y x + Y_p p - C g = 0,        C[t, j, m] = K[m, j] c_m(t)

The system is homogeneous: the gains and every parameter can be scaled together. The
payload's known mass ``M`` fixes the scale (and its centre of mass ``r``, when known, its
first moments ``M r``): their columns move to the right-hand side::

    [Y_free, -C] [x_free; g] = -M (y_M + r_x y_MX + r_y y_MY + r_z y_MZ)

a linear system in the free values and the gains (:class:`GainEquations`), solved by
:mod:`._solvers`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from jaxtyping import Float

from .._model._torque_model import TorqueModel
from .._payload._term import PAYLOAD_PARAMETERS, PayloadInertia

#: The payload's columns that a known mass (and centre of mass) fixes.
MASS, FIRST_MOMENTS = "M", ("MX", "MY", "MZ")


@dataclasses.dataclass(frozen=True, eq=False)
class GainEquations:
    """The rows of one model (module docstring): ``A (T, n, d)`` the model's regressor
    (its payload columns zero on the unloaded recordings), ``current (T, m)`` the recorded
    currents, ``motors`` the transmission ``K``, ``fixed`` the model's columns whose
    values are known (``known`` their values). The unknowns are the other model values,
    then the gains."""

    model: TorqueModel
    A: np.ndarray
    current: np.ndarray
    motors: np.ndarray
    fixed: np.ndarray
    known: np.ndarray

    @property
    def C(self) -> Float[np.ndarray, "T n m"]:
        """Each gain's column: ``C[t, j, m] = K[m, j] c_m(t)``."""
        return self.current[:, None, :] * self.motors.T[None]

    @property
    def known_torque(self) -> Float[np.ndarray, "T n"]:
        """The torque of the known values (the payload's mass and first moments)."""
        return self.A[..., self.fixed] @ self.known

    @property
    def free(self) -> np.ndarray:
        """The model's columns the equations estimate."""
        return np.setdiff1d(np.arange(self.A.shape[-1]), self.fixed)

    @property
    def n_gains(self) -> int:
        return self.current.shape[-1]

    @property
    def rows(self) -> tuple[Float[np.ndarray, "T n u"], Float[np.ndarray, "T n"]]:
        """``(X, b)``: the unknowns' columns ``[Y_free, -C]`` and the right-hand side, the
        known columns' torque, negated."""
        X = np.concatenate([self.A[..., self.free], -self.C], -1)
        return X, -self.known_torque

    def split(self, theta: Float[np.ndarray, " u"]) -> tuple[np.ndarray, np.ndarray]:
        """``(the model's values, the gains)`` of the unknowns ``theta``, the known values
        put back."""
        values = np.zeros(self.A.shape[-1])
        values[self.free] = theta[:self.free.size]
        values[self.fixed] = self.known
        return values, np.asarray(theta[self.free.size:], dtype=float)

    def lift(self) -> np.ndarray:
        """``L`` with ``values[free] = L theta``: the rows of the free values."""
        return np.eye(self.free.size + self.n_gains)[:self.free.size]


def payload_columns(model: TorqueModel) -> np.ndarray:
    """The indices of the payload's 10 columns in ``model.names``."""
    names = [f"payload_{p}" for p in PAYLOAD_PARAMETERS]
    return np.array([model.names.index(n) for n in names])


def with_payload(model: TorqueModel, term: PayloadInertia) -> TorqueModel:
    """``model`` with the payload's term."""
    return TorqueModel.of(model.robot, (*model.terms, term), transmission=model.transmission,
                          base=model.base, recordings=model.recordings, search=model.search)


def equations(model: TorqueModel, signals: tuple, motors: np.ndarray, mass: float,
              com: np.ndarray | None) -> GainEquations:
    """The equations of ``model`` (with the payload's term) at the stacked recordings
    ``signals = (q, qd, qdd, currents, recording index)``; ``motors`` the transmission
    ``K`` (the identity for joint-side currents)."""
    q, qd, qdd, current, index = signals
    A = np.asarray(model.regressor(q, qd, qdd, index), dtype=float)
    columns = payload_columns(model)
    names = list(PAYLOAD_PARAMETERS)
    fixed = [columns[names.index(MASS)]]
    known = [float(mass)]
    if com is not None:
        fixed += [columns[names.index(f)] for f in FIRST_MOMENTS]
        known += [float(mass) * float(r) for r in com]
    return GainEquations(model, A, np.asarray(current, dtype=float),
                         np.asarray(motors, dtype=float), np.array(fixed), np.array(known))
