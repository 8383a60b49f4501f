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
    Stribeck(v_s)        + FS_j exp(-(qd_j / v_s)^2) c_j(qd)   friction above Coulomb's
                                                        near rest (Stribeck's curve)
    LoadFriction()       + FL_j |tau_load_j| c_j(qd)    Coulomb friction growing with the
                                                        torque the joint transmits
    Presliding(q_c)      + FP_j z_j(q; q_c)             friction held at rest: Dahl's state
                                                        along the recorded positions

``K`` is the model's transmission (motor angles ``theta = K q``; ``K = 1`` without one);
``c_j(qd)`` the model's Coulomb shape (``sign(qd_j)``, or ``tanh(qd_j / v)`` with the
smooth term); ``tau_load`` the model's own rigid-body torque (the base columns but
friction, at the model's load point, :attr:`~._model.TorqueModel.load_point`).

A term's velocity scale (smooth Coulomb's ``v``, Stribeck's ``v_s``) is fixed, or, with
``fitted=True``, one per joint searched by the fit (:mod:`._shapes`), and so is the
presliding state's displacement ``q_c``; the command line writes ``smooth:fit``,
``stribeck:fit``, ``smooth:0.05``, ``load:viscous``, ``presliding:fit`` or
``presliding:0.001``. The presliding state (:mod:`._friction_state`) is the one term
whose columns read the samples in time order (:attr:`AbstractTerm.stateful`).
A term is an immutable value that knows its columns, their names and whether a physical
body has its coefficients ``>= 0``; adding one is one final class here (its ``name`` is
its word in the command's ``--friction a+b`` text, its place in :data:`FRICTION_TERMS`
the order of its columns). :func:`parse_friction` reads that text, once, at the edge.
"""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import abc
from typing import ClassVar

import equinox as eqx
import numpy as np

from ._scales import AbstractVelocityScale, as_scale
from ._term_base import (
    TERMS,
    AbstractColumns,
    AbstractTerm,
    Signals,
    TorqueModelView,
    diagonal,
    through_motors,
)

#: The rigid-body model's own friction, always in the model (the base regressor's columns).
BASE_FRICTION = "viscous-coulomb"
#: Velocity scale (rad/s or m/s) of :class:`SmoothCoulomb` unless told.
SMOOTH_VELOCITY = 0.02
#: Stribeck velocity (rad/s or m/s) of :class:`Stribeck` unless told.
STRIBECK_VELOCITY = 0.1

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

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        n, R = model.robot.n_joints, model.recordings
        batch, recording = s.qd.shape[:-1], s.recording
        if R == 1:
            return diagonal(1.0, batch, n)
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
    def torque(self, s: Signals) -> np.ndarray:
        """Each joint's column value at the samples of ``s``, ``(..., n)``."""

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        return tuple(f"{self.prefix}{j + 1}" for j in range(model.robot.n_joints))

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        return diagonal(self.torque(s), s.qd.shape[:-1], model.robot.n_joints)


class Quadratic(AbstractJointFriction):
    """``FQ_j qd_j |qd_j|``: friction growing with the velocity squared (a lubricant's
    drag at speed), ``>= 0`` for a physical body."""

    name: ClassVar[str] = "quadratic"
    prefix: ClassVar[str] = "FQ"
    nonnegative: ClassVar[bool] = True

    def torque(self, s: Signals) -> np.ndarray:
        return s.qd * np.abs(s.qd)


class SmoothCoulomb(AbstractVelocityScale):
    """Coulomb friction without the jump at rest: ``tanh(qd_j / velocity)`` in place of
    ``sign(qd_j)`` in each joint's Coulomb column (``velocity`` in rad/s or m/s, > 0:
    one, one per joint, or with ``fitted=True`` one per joint searched by the fit); no
    columns of its own."""

    velocity: float | tuple[float, ...] = eqx.field(default=SMOOTH_VELOCITY,
                                                    converter=as_scale)
    fitted: bool = False
    name: ClassVar[str] = "smooth"
    nonnegative: ClassVar[bool] = False
    symbol: ClassVar[str] = "v_smooth"
    default_scale: ClassVar[float] = SMOOTH_VELOCITY

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        if None in model.base.joint_columns("FC"):
            raise ValueError("the smooth Coulomb term needs every joint's Coulomb column in "
                             "the base set")
        self.per_joint(model.robot.n_joints)
        return ()

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        return np.zeros(s.qd.shape[:-1] + (model.robot.n_joints, 0))

    def coulomb(self, qd: np.ndarray) -> np.ndarray:
        return np.tanh(qd / self.per_joint(qd.shape[-1]))


class Armature(AbstractColumns):
    """``K_m^T IA_m (K_m . qdd)``: the rotor inertia ``IA_m`` of motor ``m`` (kg m^2,
    motor side), ``>= 0``. Without a transmission ``K = 1``: joint ``j``'s column is
    ``qdd_j``; with a diagonal ``K`` its effect at the joint is ``N_j^2 IA_j``."""

    name: ClassVar[str] = "armature"
    nonnegative: ClassVar[bool] = True

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        return tuple(f"IA{m + 1}" for m in range(model.robot.n_joints))

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        return through_motors(model.motor_matrix, list(range(model.robot.n_joints)), s.qdd)


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

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        K, motors = model.motor_matrix, list(model.coupled_motors)
        return np.concatenate([through_motors(K, motors, s.qd),
                               through_motors(K, motors, s.qd, sign=True)], -1)


class Stribeck(AbstractVelocityScale):
    """``FS_j exp(-(qd_j / velocity)^2) c_j(qd)``: the friction above Coulomb's that
    a joint shows near rest and loses as it speeds up (Stribeck's curve; ``FS_j >= 0``,
    the static friction's excess), ``velocity`` the Stribeck velocity (rad/s or m/s,
    > 0: one, one per joint, or fitted). Its columns are ``FS1..``."""

    velocity: float | tuple[float, ...] = eqx.field(default=STRIBECK_VELOCITY,
                                                    converter=as_scale)
    fitted: bool = False
    name: ClassVar[str] = "stribeck"
    nonnegative: ClassVar[bool] = True
    symbol: ClassVar[str] = "v_stribeck"
    default_scale: ClassVar[float] = STRIBECK_VELOCITY

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        n = model.robot.n_joints
        self.per_joint(n)
        return tuple(f"FS{j + 1}" for j in range(n))

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        v = self.per_joint(s.qd.shape[-1])
        return diagonal(np.exp(-(s.qd / v) ** 2) * s.coulomb, s.qd.shape[:-1],
                         model.robot.n_joints)

    def coulomb(self, qd: np.ndarray) -> None:
        return None


class LoadFriction(AbstractColumns):
    """``FL_j |tau_load_j| c_j(qd)``: Coulomb friction that grows with the torque the
    joint transmits (a harmonic drive's or gearbox's teeth and bearings, loaded by it),
    ``tau_load`` the model's own rigid-body torque (module docstring); ``FL_j >= 0``,
    dimensionless (N m of friction per N m transmitted). With ``viscous=True`` also
    ``FLV_j |tau_load_j| qd_j`` (s/rad). The coefficients are bilinear with the
    rigid-body parameters; the fit (:func:`~._shapes.fit`) takes the load from a least-
    squares fit of the model without this term, then fits the model with that load (two
    linear fits); ``fixed_point=True`` goes on, fitting with the load of the last fit's
    parameters until it settles (``load:fixed-point``; measured no better and 6-30 times
    slower, :mod:`._shapes`)."""

    viscous: bool = False
    fixed_point: bool = False
    name: ClassVar[str] = "load"
    nonnegative: ClassVar[bool] = True
    #: The command line's options, ``load:viscous,fixed-point``.
    options: ClassVar[tuple[str, ...]] = ("viscous", "fixed-point")

    def __check_init__(self):
        for field in ("viscous", "fixed_point"):
            if not isinstance(getattr(self, field), bool):
                raise ValueError(f"LoadFriction's {field} must be True or False, got "
                                 f"{getattr(self, field)!r}")

    @property
    def needs_load(self) -> bool:
        return True

    @property
    def settles_load(self) -> bool:
        return self.fixed_point

    @property
    def text(self) -> str:
        chosen = [o for o, on in zip(self.options, (self.viscous, self.fixed_point)) if on]
        return "load" + (":" + ",".join(chosen) if chosen else "")

    @classmethod
    def parse(cls, option: str | None) -> AbstractTerm:
        words = [] if option is None else option.split(",")
        if any(w not in cls.options for w in words) or len(set(words)) < len(words):
            raise ValueError(f"friction term 'load': expected load, load:viscous, "
                             f"load:fixed-point or load:viscous,fixed-point, got "
                             f"load:{option}")
        return cls(viscous="viscous" in words, fixed_point="fixed-point" in words)

    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        n = model.robot.n_joints
        kinds = ("FL", "FLV") if self.viscous else ("FL",)
        return tuple(f"{k}{j + 1}" for k in kinds for j in range(n))

    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        if s.load is None:
            raise ValueError("LoadFriction's columns need the model's rigid-body torque")
        n, batch = model.robot.n_joints, s.qd.shape[:-1]
        load = np.abs(s.load)
        out = [diagonal(load * s.coulomb, batch, n)]
        if self.viscous:
            out.append(diagonal(load * s.qd, batch, n))
        return np.concatenate(out, -1)

    def settings(self) -> dict:
        return {"load_viscous": self.viscous, "load_fixed_point": self.fixed_point}


# After LoadFriction: a term's place in the registry is the order of its columns.
from ._presliding import PRESLIDING_DISPLACEMENT, Presliding  # noqa: E402, F401

#: The words of ``--friction``'s ``a+b`` text, in column order.
FRICTION_TERMS = (BASE_FRICTION, *TERMS)


def canonical_order(terms: object) -> object:
    """``terms`` as a tuple in column order (:data:`FRICTION_TERMS`); anything but terms
    is left for the model's check to name."""
    found = tuple(terms) if isinstance(terms, (tuple, list)) else terms
    if not isinstance(found, tuple) or not all(isinstance(t, AbstractTerm) for t in found):
        return found
    return tuple(sorted(found, key=lambda t: list(TERMS).index(t.name)))


def friction_text(terms: tuple[AbstractTerm, ...]) -> str:
    """The ``a+b`` text of ``terms`` (in column order): ``viscous-coulomb+offset+...``."""
    return "+".join((BASE_FRICTION, *(t.text for t in terms)))


def parse_friction(text: str) -> tuple[AbstractTerm, ...]:
    """The terms of the command line's ``--friction`` text: words of
    :data:`FRICTION_TERMS` joined by ``+`` (``"viscous-coulomb+offset+quadratic"``; the
    base regressor's ``viscous-coulomb`` is always in the model, so ``"offset"`` is the
    same), each ``word`` or ``word:option`` (``smooth:fit``, ``smooth:0.05``,
    ``stribeck:fit``, ``load:viscous``), in column order."""
    if not isinstance(text, str) or not text:
        raise ValueError(f"friction must be a string of terms joined by '+' from "
                         f"{FRICTION_TERMS}, got {text!r}")
    given: dict[str, str | None] = {}
    for part in (p.strip() for p in text.split("+")):
        word, _, option = part.partition(":")
        given[word.strip()] = option.strip() or None
    unknown = set(given) - set(FRICTION_TERMS)
    if unknown:
        raise ValueError(f"unknown friction term(s) {sorted(unknown)}; known: {FRICTION_TERMS} "
                         f"(joined by '+', e.g. 'viscous-coulomb+offset')")
    if given.get(BASE_FRICTION) is not None:
        raise ValueError(f"{BASE_FRICTION} takes no option, got "
                         f"{BASE_FRICTION}:{given[BASE_FRICTION]}")
    return tuple(cls.parse(given[name]) for name, cls in TERMS.items() if name in given)
