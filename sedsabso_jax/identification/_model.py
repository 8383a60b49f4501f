"""The torque model an identification fits: the base regressor plus terms (:mod:`._terms`)::

    tau = Yb(q, qd, qdd) beta        base regressor: rigid body, viscous + Coulomb friction
          + each term's columns      offset, qd|qd| friction, armature, coupled motors

A :class:`TorqueModel` is built once (:meth:`TorqueModel.of`) and travels whole through
:func:`~._identify.identify`, the validations and the reports; :func:`candidate_models`
builds the candidates the default chooses among. ``recordings = R > 1`` (several
recordings fitted together) gives the :class:`~._terms.Offset` one column per joint and
recording, ``OFF1.1 .. OFF1.R, OFF2.1 ..``: a torque sensor's zero that moved between them.

``transmission`` is ``K`` (motor angles ``theta = K q``, a
:class:`~sedsabso_jax.Transmission` or its matrix) for the armature and coupled-motor
terms, or None (``K = 1``). The extra columns come after the base columns, in the order of
:data:`~._terms.FRICTION_TERMS`: ``OFF1..``, ``FQ1..``, ``IA1..``, ``FVM6, FCM6`` (motor
numbers from 1).

An extra column that the base regressor already spans (e.g. the armature of a first joint
about a fixed vertical axis, which regroups with ``ZZ1``) is dropped: it cannot be
identified apart. :attr:`TorqueModel.regrouped` names them.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Iterable

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float, Int

from ..dynamics._base_parameters import (
    RANK_TOLERANCE,
    BaseParameters,
    base_parameters,
    random_states,
)
from ..dynamics._robot import Robot
from ..measurements._transmission import Transmission, TransmissionLike, coupled_motors
from ._options import as_floats
from ._term_base import AbstractTerm, Shapes, Signals
from ._terms import (
    Armature,
    CoupledMotorFriction,
    LoadFriction,
    Offset,
    SmoothCoulomb,
    canonical_order,
    friction_text,
)

#: The candidate torque models of :func:`~._validation.select_model` (terms beyond the
#: base regressor's viscous and Coulomb friction), simplest first. After 0.5.0 each has
#: Coulomb friction without the jump at rest (:class:`~._terms.SmoothCoulomb`: with
#: velocities derived from noisy positions, ``sign(qd)`` flips at random on a joint that
#: stands still, which doubled the error on point-to-point motions with rests in the
#: simulation study, docs/results/extrapolation.md), Coulomb friction growing with the
#: load is a candidate, alone and with armature, and ``qd|qd|`` is not (it grows without
#: bound with the speed: the validation chose it where it made 2.2-2.6 times the best
#: candidate's error at twice the fitted speed).
FRICTION_CANDIDATES: tuple[tuple[AbstractTerm, ...], ...] = (
    (SmoothCoulomb(),), (Offset(), SmoothCoulomb()), (Offset(), Armature(), SmoothCoulomb()),
    (Offset(), SmoothCoulomb(), LoadFriction()),
    (Offset(), Armature(), SmoothCoulomb(), LoadFriction()))


def _matrix(transmission: object) -> object:
    """A :class:`~sedsabso_jax.Transmission` as its matrix ``K``, a matrix as floats."""
    if isinstance(transmission, Transmission):
        return transmission.matrix
    try:
        return None if transmission is None else np.asarray(transmission, dtype=float)
    except (TypeError, ValueError):
        return transmission  # for the check to name


class TorqueModel(eqx.Module):
    """A linear torque model: the base regressor of a robot plus extra ``terms`` (module
    docstring); ``transmission`` is ``K`` (``n x n``) or None; ``recordings`` the
    recordings with one torque offset each (1: one offset for all).

    ``regressor(q, qd, qdd)`` is ``(..., n, d)`` with ``d`` = :attr:`dim`;
    ``predict(values, q, qd, qdd)`` is ``regressor @ values``. :meth:`of` builds one from
    a robot.
    """

    base: BaseParameters
    terms: tuple[AbstractTerm, ...] = eqx.field(default=(), converter=canonical_order)
    transmission: np.ndarray | None = eqx.field(default=None, converter=_matrix)
    recordings: int = 1
    load_point: tuple[float, ...] | None = eqx.field(default=None, converter=as_floats)

    def __check_init__(self):
        if not isinstance(self.terms, tuple) or not all(isinstance(t, AbstractTerm)
                                                        for t in self.terms):
            raise TypeError(f"terms must be a tuple of terms (Offset(), Quadratic(), ...; "
                            f"parse_friction('viscous-coulomb+offset') reads the command "
                            f"line's text), got {self.terms!r}")
        kinds = [t.name for t in self.terms]
        if len(set(kinds)) < len(kinds):
            raise ValueError(f"one term of each kind, got {self.friction!r}")
        if not isinstance(self.recordings, (int, np.integer)) or isinstance(
                self.recordings, bool) or self.recordings < 1:
            raise ValueError(f"recordings must be an integer >= 1, got {self.recordings!r}")
        if self.recordings > 1 and Offset() not in self.terms:
            raise ValueError("one torque offset per recording needs the Offset() term in the "
                             "torque model")
        if self.transmission is not None:
            n = self.robot.n_joints
            K = self.transmission
            if not isinstance(K, np.ndarray) or K.shape != (n, n) or not np.all(np.isfinite(K)):
                raise ValueError(f"transmission must be a finite ({n}, {n}) matrix for robot "
                                 f"{self.robot.name!r}, got {K!r}")
        if self.load_point is not None and (
                not isinstance(self.load_point, tuple) or len(self.load_point) != self.base.rank
                or not np.all(np.isfinite(self.load_point))):
            raise ValueError(f"load_point must be {self.base.rank} finite base-parameter "
                             f"values, got {self.load_point!r}")
        self._extra_names()  # each term checks that it applies

    @classmethod
    def of(cls, robot: Robot, terms: Iterable[AbstractTerm] = (), *,
           transmission: TransmissionLike = None, base: BaseParameters | None = None,
           recordings: int = 1) -> TorqueModel:
        """The model of ``robot`` with ``terms`` (:mod:`._terms`, in any order; none: the
        base regressor's viscous and Coulomb friction only), ``transmission`` (a
        :class:`~sedsabso_jax.Transmission` or its matrix ``K``) for the armature and
        coupled-motor terms, ``base`` a precomputed ``base_parameters(robot)`` (computed
        when None), and ``recordings``: one torque offset per joint and recording."""
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
        if isinstance(terms, str):
            raise TypeError(f"terms must be terms (Offset(), ...), not the text {terms!r}: "
                            f"parse_friction({terms!r}) reads it")
        if base is None:
            base = base_parameters(robot)
        elif not isinstance(base, BaseParameters) or base.robot.n_params != robot.n_params:
            raise ValueError("base must be base_parameters(robot) of this robot")
        return cls(base, tuple(terms), transmission, recordings)  # type: ignore[arg-type]

    @property
    def robot(self) -> Robot:
        return self.base.robot

    @property
    def friction(self) -> str:
        """The terms as the command line writes them: ``viscous-coulomb+offset+...``."""
        return friction_text(self.terms)

    def settings(self) -> dict:
        """What the reports write about the model besides its friction terms."""
        out: dict = {}
        if self.transmission is not None:
            out["transmission"] = self.transmission
        if self.regrouped:
            out["regrouped"] = list(self.regrouped)
        for term in self.terms:
            out.update(term.settings())
        if self.recordings > 1:
            out["offset_per_recording"] = self.recordings
        return out

    @property
    def motor_matrix(self) -> np.ndarray:
        """The transmission's ``K``, the identity without one."""
        n = self.robot.n_joints
        return np.eye(n) if self.transmission is None else self.transmission

    @property
    def coupled_motors(self) -> tuple[int, ...]:
        """The motors (0-based) that turn with several joints."""
        return coupled_motors(self.motor_matrix)

    def _extra_names(self) -> list[str]:
        return [name for term in self.terms for name in term.names(self)]

    @functools.cached_property
    def _kept(self) -> np.ndarray:
        """Indices of the extra columns that the base regressor does not span, found as
        the base parameters are: at random states, scaled columns, ordered QR."""
        if not self._extra_names():
            return np.zeros(0, dtype=int)
        robot = self.robot
        # the sample count base_parameters uses: the regressor is compiled for it already
        q, qd, qdd = random_states(robot, max(50, -(-4 * robot.n_params // robot.n_joints)),
                                   seed=1)
        recording = np.random.default_rng(1).integers(0, self.recordings, q.shape[0])
        # a random load: which load columns the base spans must not depend on the load
        # point (a fit's own parameters would otherwise change the model's columns)
        load = np.random.default_rng(2).standard_normal(q.shape) if self.needs_load else None
        Y = self._full_regressor(q, qd, qdd, recording if self.recordings > 1 else None,
                                 load=load)
        W = Y.reshape(-1, Y.shape[-1])
        W = W / np.where(np.linalg.norm(W, axis=0) > 0, np.linalg.norm(W, axis=0), 1.0)
        d = np.abs(np.diag(np.linalg.qr(W, mode="r")))
        independent = d > RANK_TOLERANCE * d.max()
        return np.flatnonzero(independent[self.base.rank:])

    @property
    def regrouped(self) -> tuple[str, ...]:
        """Extra columns dropped because the base regressor spans them."""
        names = self._extra_names()
        return tuple(n for i, n in enumerate(names) if i not in set(self._kept.tolist()))

    @property
    def names(self) -> tuple[str, ...]:
        extra = self._extra_names()
        return tuple(self.base.names) + tuple(extra[i] for i in self._kept)

    @property
    def nonnegative(self) -> np.ndarray:
        """Per column (:attr:`names`): whether a physical value is >= 0 (the terms that
        say so; the base columns are constrained through the full parameters)."""
        extra = [term.nonnegative for term in self.terms for _ in term.names(self)]
        return np.array([False] * self.base.rank + [extra[i] for i in self._kept], dtype=bool)

    @property
    def dim(self) -> int:
        return len(self.names)

    def _full_regressor(self, q, qd, qdd, recording=None, base_rows=None, load=None
                        ) -> np.ndarray:
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        Y = np.asarray(self.base.regressor(q, qd, qdd) if base_rows is None else base_rows)
        n = self.robot.n_joints
        batch = Y.shape[:-2]
        q, qd, qdd = (np.broadcast_to(a, batch + (n,)) for a in (q, qd, qdd))
        coulomb = np.sign(qd)
        for term in self.terms:
            shape = term.coulomb(qd)
            if shape is not None:
                coulomb = shape
                Y = Y.copy()
                Y[..., np.arange(n), np.array(self.base.joint_columns("FC"))] = shape
        if load is None and self.needs_load:  # the rigid-body torque at the load point
            rigid = self.rigid_columns
            load = Y[..., rigid] @ np.asarray(self.load_values)[rigid]
        signals = Signals(q, qd, qdd, recording, coulomb, load)
        extra = [term.columns(self, signals) for term in self.terms]
        return np.concatenate([Y, *extra], -1)

    @property
    def needs_load(self) -> bool:
        """Whether a term's columns read the model's rigid-body torque
        (:class:`~._terms.LoadFriction`)."""
        return any(term.needs_load for term in self.terms)

    @property
    def stateful(self) -> bool:
        """Whether a term's columns integrate a state along the samples
        (:class:`~._terms.Presliding`): the rows need each recording whole, in time
        order."""
        return any(term.stateful for term in self.terms)

    @property
    def load_fixed_point(self) -> bool:
        """Whether the load-dependent friction's fit goes on to a fixed point
        (:class:`~._terms.LoadFriction`'s ``fixed_point``)."""
        return any(term.settles_load for term in self.terms)

    @property
    def rigid_columns(self) -> np.ndarray:
        """The base columns of the rigid body: all but each joint's viscous and Coulomb
        friction (which never regroup)."""
        friction = {c for p in ("FV", "FC") for c in self.base.joint_columns(p)
                    if c is not None}
        return np.array([c for c in range(self.base.rank) if c not in friction], dtype=int)

    @property
    def load_values(self) -> tuple[float, ...]:
        """The base-parameter values whose rigid-body torque loads the joints:
        :attr:`load_point`, or the robot's own (a-priori) parameters projected on the
        base."""
        if self.load_point is not None:
            return self.load_point
        return tuple(float(v) for v in np.asarray(self.base.values))

    def linearized_at(self, values: Float[ArrayLike, " d"]) -> TorqueModel:
        """The model whose load point is ``values``' base part (the load-dependent
        friction then reads the torque of these parameters); the model itself when no
        term reads the load."""
        if not self.needs_load:
            return self
        base = np.asarray(values, dtype=float)[:self.base.rank]
        return dataclasses.replace(self, load_point=tuple(float(v) for v in base))

    def at_load_of(self, values: Float[ArrayLike, " d"]) -> TorqueModel:
        """The model whose load-dependent friction reads the load a prediction with
        ``values`` uses: the model's own load point where it has one (a fitted model: the
        load its fit used), else the rigid-body torque of ``values`` themselves."""
        return self if self.load_point is not None else self.linearized_at(values)

    def shapes(self) -> list[tuple[int, Shapes]]:
        """The velocity scales a fit searches: ``(term index, Shapes)`` of each term with
        fitted scales."""
        out = []
        for i, term in enumerate(self.terms):
            found = term.shapes(self)
            if found is not None:
                out.append((i, found))
        return out

    def with_shapes(self, values: Float[ArrayLike, " k"]) -> TorqueModel:
        """The model with the searched velocity scales set to ``values`` (those of
        :meth:`shapes`, concatenated)."""
        values = np.asarray(values, dtype=float)
        terms, k = list(self.terms), 0
        for i, found in self.shapes():
            m = len(found.values)
            terms[i] = terms[i].with_shapes(values[k:k + m])
            k += m
        if k != values.size:
            raise ValueError(f"expected {k} velocity scales, got {values.size}")
        return dataclasses.replace(self, terms=tuple(terms))

    @property
    def nonlinear(self) -> bool:
        """Whether fitting the model takes more than one linear fit: a term reads the
        model's own torque, or has velocity scales to search."""
        return self.needs_load or bool(self.shapes())

    def regressor(self, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                  qdd: Float[ArrayLike, "*batch n"],
                  recording: Int[ArrayLike, "*batch"] | None = None, *,
                  base_rows: Float[ArrayLike, "*batch n b"] | None = None,
                  every_column: bool = False) -> Float[np.ndarray, "*batch n d"]:
        """``(..., n, dim)``: the base columns, then the identifiable extra columns;
        ``recording``: the recording of each sample, for one offset per recording (None:
        new motions, the offsets' mean); ``base_rows``: the base regressor at these
        samples when already computed (a fit that tries many velocity scales);
        ``every_column``: also the extra columns the base regressor spans (which ones
        those are may change with a term's velocity scale)."""
        Y = self._full_regressor(q, qd, qdd, recording, base_rows)
        if every_column:
            return Y
        keep = np.r_[np.arange(self.base.rank), self.base.rank + self._kept]
        return Y[..., keep] if len(keep) < Y.shape[-1] else Y

    def predict(self, values: Float[ArrayLike, " d"], q: Float[ArrayLike, "*batch n"],
                qd: Float[ArrayLike, "*batch n"], qdd: Float[ArrayLike, "*batch n"],
                recording: Int[ArrayLike, "*batch"] | None = None
                ) -> Float[np.ndarray, "*batch n"]:
        """Torques ``regressor(q, qd, qdd, recording) @ values``, ``(..., n)``; a model
        with load-dependent friction reads the load at its load point (a fitted model's:
        the one its fit used) or, without one, the rigid-body torque of ``values``
        (:meth:`at_load_of`)."""
        values = np.asarray(values, dtype=float)
        if values.shape != (self.dim,):
            raise ValueError(f"values must have shape ({self.dim},), got {values.shape}")
        return self.at_load_of(values).regressor(q, qd, qdd, recording) @ values


def regrouped_message(model: TorqueModel) -> str:
    """The warning that extra columns of ``model`` were left out."""
    return (f"identify: {', '.join(model.regrouped)} cannot be identified apart from the base "
            f"parameters (their columns are in the base regressor's span); left out of the "
            f"model")


def candidate_models(robot: Robot,
                     frictions: Iterable[Iterable[AbstractTerm]] = FRICTION_CANDIDATES, *,
                     transmission: TransmissionLike = None, recordings: int = 1,
                     base: BaseParameters | None = None) -> tuple[TorqueModel, ...]:
    """The torque models of ``robot`` with each set of terms of ``frictions`` (default
    :data:`FRICTION_CANDIDATES`), simplest first: with the
    :class:`~._terms.CoupledMotorFriction` where ``transmission`` couples a motor, with
    one :class:`~._terms.Offset` per recording for ``recordings > 1``, the base
    parameters computed once (``base``: given), and each model once (``()`` and
    ``(Offset(),)`` are one model with offsets per recording). Where the smooth Coulomb
    term does not apply (a joint's Coulomb column regroups with other base columns),
    the default candidates keep the jump."""
    if base is None:
        base = base_parameters(robot)
    K = _matrix(transmission)
    coupled = K is not None and bool(coupled_motors(K))  # type: ignore[arg-type]
    models: list[TorqueModel] = []
    for terms in frictions:
        terms = tuple(terms)
        added = ((CoupledMotorFriction(),) if coupled else ()) + (
            (Offset(),) if recordings > 1 else ())
        terms += tuple(t for t in added if t not in terms)
        if frictions is FRICTION_CANDIDATES and None in base.joint_columns("FC"):
            terms = tuple(t for t in terms if not isinstance(t, SmoothCoulomb))
        model = TorqueModel.of(robot, terms, transmission=transmission, base=base,
                               recordings=recordings)
        if all(m.friction != model.friction for m in models):
            models.append(model)
    return tuple(models)
