"""The terms a torque model adds to the base regressor (:mod:`._model`), one class each.

The base regressor already holds each joint's viscous and Coulomb friction
``FV_j qd_j + FC_j sign(qd_j)`` (the paper's Eq. 1); a term adds columns or reshapes them::

    Offset()             + OFF_j                        a constant torque (a sensor's zero)
    Quadratic()          + FQ_j qd_j |qd_j|             velocity-squared friction
    SmoothCoulomb(v)     sign(qd_j) -> tanh(qd_j / v)   Coulomb friction without the jump
    Armature()           + K_m^T IA_m (K_m . qdd)       rotor inertia of motor m
    CoupledMotorFriction() + K_m^T (FVM_m u_m + FCM_m sign(u_m)), u_m = K_m . qd:
                                                        friction of a motor m that turns
                                                        with several joints

``K`` is the model's transmission (motor angles ``theta = K q``; ``K = 1`` without one).
A term is an immutable value that knows its columns, their names and whether a physical
body has its coefficients ``>= 0``; adding one is one final class here (its ``name`` is
its word in the command's ``--friction a+b`` text, its place in :data:`FRICTION_TERMS`
the order of its columns). :func:`parse_friction` reads that text, once, at the edge.
"""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import abc
import dataclasses
from typing import ClassVar, Protocol

import equinox as eqx
import numpy as np

from ..dynamics._base_parameters import BaseParameters
from ..dynamics._robot import Robot
from ._options import as_float, check_number

#: The rigid-body model's own friction, always in the model (the base regressor's columns).
BASE_FRICTION = "viscous-coulomb"
#: Velocity scale (rad/s or m/s) of :class:`SmoothCoulomb` unless told.
SMOOTH_VELOCITY = 0.02
#: Term name -> final class, in column order (each class registers itself when defined).
_TERMS: dict[str, type["AbstractTerm"]] = {}


class TorqueModelView(Protocol):
    """What a term reads of its torque model (:class:`~._model.TorqueModel`)."""

    @property
    def robot(self) -> Robot: ...

    @property
    def base(self) -> BaseParameters: ...

    @property
    def recordings(self) -> int: ...

    @property
    def motor_matrix(self) -> np.ndarray: ...

    @property
    def coupled_motors(self) -> tuple[int, ...]: ...


class AbstractTerm(eqx.Module):
    """A term of the torque model beyond the rigid-body base regressor (module
    docstring): its columns (:meth:`columns`, named by :meth:`names`), or a new shape of
    the Coulomb columns (:meth:`coulomb`). Final subclasses set ``name`` (the word in
    ``--friction``) and ``nonnegative`` (whether a physical body has its coefficients
    ``>= 0``, a constraint of the physically consistent fit)."""

    name: eqx.AbstractClassVar[str]
    nonnegative: eqx.AbstractClassVar[bool]

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "name" in cls.__dict__:  # a final class: known by its name, in definition order
            _TERMS[cls.name] = cls

    @abc.abstractmethod
    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        """The names of this term's columns in ``model`` (a ValueError where the term does
        not apply to the model)."""

    @abc.abstractmethod
    def columns(self, model: TorqueModelView, qd: np.ndarray, qdd: np.ndarray,
                recording: np.ndarray | None) -> np.ndarray:
        """The columns ``(..., n, len(names))`` at velocities and accelerations ``(..., n)``
        (``recording``: each sample's recording, or None)."""

    @abc.abstractmethod
    def coulomb(self, qd: np.ndarray) -> np.ndarray | None:
        """The Coulomb columns' values in place of ``sign(qd)``, or None to keep them."""

    def settings(self) -> dict:
        """The term's options for the report, ``{name_option: value}``."""
        return {f"{self.name}_{f.name}": getattr(self, f.name)
                for f in dataclasses.fields(self)}


class AbstractColumns(AbstractTerm):
    """A term that adds columns and leaves the Coulomb columns as they are."""

    def coulomb(self, qd: np.ndarray) -> None:
        return None


def _diagonal(values: np.ndarray | float, batch: tuple[int, ...], n: int) -> np.ndarray:
    """``(..., n, n)`` columns with ``values`` on joint ``j``'s own column ``j``."""
    E = np.zeros(batch + (n, n))
    E[..., np.arange(n), np.arange(n)] = values
    return E


def _through_motors(K: np.ndarray, motors: list[int], v: np.ndarray, sign: bool = False
                    ) -> np.ndarray:
    """Columns ``K[m, j] u_m`` for joint ``j``, motor ``m`` of ``motors``, with ``u_m =
    K_m . v`` (or its sign): a motor-side coefficient seen at the joints."""
    u = v @ K[motors].T  # (..., motors)
    if sign:
        u = np.sign(u)
    return K[motors].T * u[..., None, :]


class Offset(AbstractColumns):
    """``OFF_j``: a constant torque per joint (a torque sensor's zero). With a model of
    ``R > 1`` recordings, one per joint and recording, ``OFFj.r``: rows of recording ``r``
    carry 1 in column ``OFFj.r``, rows of no recording (new motions) ``1/R`` in each,
    the offsets' mean."""

    name: ClassVar[str] = "offset"
    nonnegative: ClassVar[bool] = False

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        n, R = model.robot.n_joints, model.recordings
        if R > 1:
            return tuple(f"OFF{j + 1}.{r + 1}" for j in range(n) for r in range(R))
        return tuple(f"OFF{j + 1}" for j in range(n))

    def columns(self, model: TorqueModelView, qd: np.ndarray, qdd: np.ndarray,
                recording: np.ndarray | None) -> np.ndarray:
        n, R = model.robot.n_joints, model.recordings
        batch = qd.shape[:-1]
        if R == 1:
            return _diagonal(1.0, batch, n)
        if recording is None:
            share = np.full(batch + (R,), 1.0 / R)
        else:
            index = np.asarray(recording)
            if index.shape != batch or index.dtype.kind not in "iu" or (
                    index.size and (index.min() < 0 or index.max() >= R)):
                raise ValueError(f"recording must hold one integer in [0, {R}) per sample "
                                 f"{batch}, got shape {index.shape}")
            share = (index[..., None] == np.arange(R)).astype(float)
        E = np.zeros(batch + (n, n, R))  # joint j's row: its recording's indicator
        E[..., np.arange(n), np.arange(n), :] = share[..., None, :]
        return E.reshape(batch + (n, n * R))


class AbstractJointFriction(AbstractColumns):
    """A friction term of each joint's own velocity: one column per joint, ``PREFIXj``,
    with :meth:`torque` on the joint's own row."""

    prefix: eqx.AbstractClassVar[str]

    @abc.abstractmethod
    def torque(self, qd: np.ndarray) -> np.ndarray:
        """Each joint's column value at velocities ``qd (..., n)``."""

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        return tuple(f"{self.prefix}{j + 1}" for j in range(model.robot.n_joints))

    def columns(self, model: TorqueModelView, qd: np.ndarray, qdd: np.ndarray,
                recording: np.ndarray | None) -> np.ndarray:
        return _diagonal(self.torque(qd), qd.shape[:-1], model.robot.n_joints)


class Quadratic(AbstractJointFriction):
    """``FQ_j qd_j |qd_j|``: friction growing with the velocity squared (a lubricant's
    drag at speed), ``>= 0`` for a physical body."""

    name: ClassVar[str] = "quadratic"
    prefix: ClassVar[str] = "FQ"
    nonnegative: ClassVar[bool] = True

    def torque(self, qd: np.ndarray) -> np.ndarray:
        return qd * np.abs(qd)


class SmoothCoulomb(AbstractTerm):
    """Coulomb friction without the jump at rest: ``tanh(qd_j / velocity)`` in place of
    ``sign(qd_j)`` in each joint's Coulomb column (``velocity`` in rad/s or m/s, > 0);
    no columns of its own."""

    velocity: float = eqx.field(default=SMOOTH_VELOCITY, converter=as_float)
    name: ClassVar[str] = "smooth"
    nonnegative: ClassVar[bool] = False

    def __check_init__(self):
        check_number("SmoothCoulomb's velocity", self.velocity, strict=True)

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        if None in model.base.joint_columns("FC"):
            raise ValueError("the smooth Coulomb term needs every joint's Coulomb column in "
                             "the base set")
        return ()

    def columns(self, model: TorqueModelView, qd: np.ndarray, qdd: np.ndarray,
                recording: np.ndarray | None) -> np.ndarray:
        return np.zeros(qd.shape[:-1] + (model.robot.n_joints, 0))

    def coulomb(self, qd: np.ndarray) -> np.ndarray:
        return np.tanh(qd / self.velocity)


class Armature(AbstractColumns):
    """``K_m^T IA_m (K_m . qdd)``: the rotor inertia ``IA_m`` of motor ``m`` (kg m^2,
    motor side), ``>= 0``. Without a transmission ``K = 1``: joint ``j``'s column is
    ``qdd_j``; with a diagonal ``K`` its effect at the joint is ``N_j^2 IA_j``."""

    name: ClassVar[str] = "armature"
    nonnegative: ClassVar[bool] = True

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        return tuple(f"IA{m + 1}" for m in range(model.robot.n_joints))

    def columns(self, model: TorqueModelView, qd: np.ndarray, qdd: np.ndarray,
                recording: np.ndarray | None) -> np.ndarray:
        return _through_motors(model.motor_matrix, list(range(model.robot.n_joints)), qdd)


class CoupledMotorFriction(AbstractColumns):
    """``K_m^T (FVM_m u_m + FCM_m sign(u_m))`` with ``u_m = K_m . qd``: the viscous and
    Coulomb friction (motor side, ``>= 0``) of each motor ``m`` that turns with several
    joints (a coupled wrist), which no single joint's friction describes. Columns
    ``FVM..`` then ``FCM..``, motors numbered from 1; the model's transmission must
    couple a motor."""

    name: ClassVar[str] = "coupling"
    nonnegative: ClassVar[bool] = True

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        motors = model.coupled_motors
        if not motors:
            raise ValueError("friction term 'coupling' needs a transmission with a motor that "
                             "turns several joints (a coupling)")
        return tuple(f"{k}{m + 1}" for k in ("FVM", "FCM") for m in motors)

    def columns(self, model: TorqueModelView, qd: np.ndarray, qdd: np.ndarray,
                recording: np.ndarray | None) -> np.ndarray:
        K, motors = model.motor_matrix, list(model.coupled_motors)
        return np.concatenate([_through_motors(K, motors, qd),
                               _through_motors(K, motors, qd, sign=True)], -1)


#: The words of ``--friction``'s ``a+b`` text, in column order.
FRICTION_TERMS = (BASE_FRICTION, *_TERMS)


def canonical_order(terms: object) -> object:
    """``terms`` as a tuple in column order (:data:`FRICTION_TERMS`); anything but terms
    is left for the model's check to name."""
    found = tuple(terms) if isinstance(terms, (tuple, list)) else terms
    if not isinstance(found, tuple) or not all(isinstance(t, AbstractTerm) for t in found):
        return found
    return tuple(sorted(found, key=lambda t: list(_TERMS).index(t.name)))


def friction_text(terms: tuple[AbstractTerm, ...]) -> str:
    """The ``a+b`` text of ``terms`` (in column order): ``viscous-coulomb+offset+...``."""
    return "+".join((BASE_FRICTION, *(t.name for t in terms)))


def parse_friction(text: str) -> tuple[AbstractTerm, ...]:
    """The terms of the command line's ``--friction`` text: words of
    :data:`FRICTION_TERMS` joined by ``+`` (``"viscous-coulomb+offset+quadratic"``; the
    base regressor's ``viscous-coulomb`` is always in the model, so ``"offset"`` is the
    same), each term with its default options, in column order."""
    if not isinstance(text, str) or not text:
        raise ValueError(f"friction must be a string of terms joined by '+' from "
                         f"{FRICTION_TERMS}, got {text!r}")
    words = {w.strip() for w in text.split("+")}
    unknown = words - set(FRICTION_TERMS)
    if unknown:
        raise ValueError(f"unknown friction term(s) {sorted(unknown)}; known: {FRICTION_TERMS} "
                         f"(joined by '+', e.g. 'viscous-coulomb+offset')")
    return tuple(cls() for name, cls in _TERMS.items() if name in words)
