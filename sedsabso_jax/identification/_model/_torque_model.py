"""The torque model an identification fits: the base regressor plus terms::

    tau = Yb(q, qd, qdd) beta        base regressor: rigid body, viscous + Coulomb friction
          + each term's columns      offset, friction beyond Coulomb's, actuators, ...

A :class:`TorqueModel` is built once (:meth:`TorqueModel.of`) and travels whole through
:func:`~sedsabso_jax.identify`, the validations and the reports. ``recordings = R > 1``
(several recordings fitted together) gives the :class:`~._offset.Offset` one column per
joint and recording, ``OFF1.1 .. OFF1.R, OFF2.1 ..``: a torque sensor's zero that moved
between them. ``transmission`` is ``K`` (motor angles ``theta = K q``) for the armature
and coupled-motor terms, or None (``K = 1``). The extra columns come after the base
columns, term by term in :data:`~._order.TERMS`' order.

An extra column that the base regressor already spans (e.g. the armature of a first joint
about a fixed vertical axis, which regroups with ``ZZ1``) is dropped: it cannot be
identified apart. :attr:`TorqueModel.regrouped` names them.

The model reads every term's answers (:mod:`._term`) and branches on none of their
kinds: the parameters its terms search (:meth:`TorqueModel.nonlinear`,
:meth:`TorqueModel.with_nonlinear`, as leaves :meth:`TorqueModel.partition`) and how
(:attr:`TorqueModel.search`), what they read of a fit (:meth:`TorqueModel.reading`),
the constraints of a physical body (:attr:`TorqueModel.nonnegative`,
:attr:`TorqueModel.bodies`).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Iterable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Bool, Float, Int

from ...dynamics._base_parameters import BaseParameters, base_parameters
from ...dynamics._robot import Robot
from ...measurements._transmission import Transmission, TransmissionLike, coupled_motors
from .._search._methods import AbstractSearch, CoordinateSearch
from ._leaves import partition, tree_key, with_nonlinear
from ._order import canonical_order, friction_text
from ._regrouping import kept_columns
from ._term import AbstractTerm, Nonlinear, Signals

#: How a model's nonlinear parameters are searched unless it says otherwise.
DEFAULT_SEARCH = CoordinateSearch()


def _matrix(transmission: object) -> object:
    """A :class:`~sedsabso_jax.Transmission` as its matrix ``K``, a matrix as floats."""
    if isinstance(transmission, Transmission):
        return transmission.matrix
    try:
        return None if transmission is None else np.asarray(transmission, dtype=float)
    except (TypeError, ValueError):
        return transmission  # for the check to name


class TorqueModel(eqx.Module):
    """A torque model: the base regressor of a robot plus extra ``terms`` (module
    docstring); ``transmission`` is ``K`` (``n x n``) or None; ``recordings`` the
    recordings with one torque offset each (1: one offset for all); ``search`` how a fit
    searches the terms' nonlinear parameters (None: :data:`DEFAULT_SEARCH`).

    ``regressor(q, qd, qdd)`` is ``(..., n, d)`` with ``d`` = :attr:`dim`;
    ``predict(values, q, qd, qdd)`` is ``regressor @ values``. :meth:`of` builds one from
    a robot.
    """

    base: BaseParameters
    terms: tuple[AbstractTerm, ...] = eqx.field(default=(), converter=canonical_order)
    transmission: np.ndarray | None = eqx.field(default=None, converter=_matrix)
    recordings: int = 1
    search: AbstractSearch | None = None

    def __check_init__(self):
        if not isinstance(self.terms, tuple) or not all(isinstance(t, AbstractTerm)
                                                        for t in self.terms):
            raise TypeError(f"terms must be terms (Offset(), Quadratic(), ...; "
                            f"parse_friction('viscous-coulomb+offset') reads the command "
                            f"line's text), got {self.terms!r}")
        kinds = [type(t) for t in self.terms]
        if len(set(kinds)) < len(kinds):
            raise ValueError(f"one term of each kind, got {self.friction!r}")
        if not isinstance(self.recordings, (int, np.integer)) or isinstance(
                self.recordings, bool) or self.recordings < 1:
            raise ValueError(f"recordings must be an integer >= 1, got {self.recordings!r}")
        if self.recordings > 1 and (self._extra_names()
                                    == dataclasses.replace(self, recordings=1)._extra_names()):
            # no term has columns per recording: the model asks no term which kind it is
            raise ValueError("one torque offset per recording needs the Offset() term in the "
                             "torque model")
        if self.transmission is not None:
            n, K = self.robot.n_joints, self.transmission
            if not isinstance(K, np.ndarray) or K.shape != (n, n) or not np.all(np.isfinite(K)):
                raise ValueError(f"transmission must be a finite ({n}, {n}) matrix for robot "
                                 f"{self.robot.name!r}, got {K!r}")
        if self.search is not None and not isinstance(self.search, AbstractSearch):
            raise TypeError(f"search must be a search method (CoordinateSearch(), "
                            f"PopulationSearch(solver), LeastSquaresSearch()), got "
                            f"{self.search!r}")
        self._extra_names()  # each term checks that it applies

    @classmethod
    def of(cls, robot: Robot, terms: AbstractTerm | Iterable[AbstractTerm] = (), *,
           transmission: TransmissionLike = None, base: BaseParameters | None = None,
           recordings: int = 1, search: AbstractSearch | None = None) -> TorqueModel:
        """The model of ``robot`` with ``terms`` (one term or several, in any order; none:
        the base regressor's viscous and Coulomb friction only), ``transmission`` (a
        :class:`~sedsabso_jax.Transmission` or its matrix ``K``) for the armature and
        coupled-motor terms, ``base`` a precomputed ``base_parameters(robot)`` (computed
        when None), ``recordings``: one torque offset per joint and recording, and
        ``search``: how a fit searches the terms' nonlinear parameters."""
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a sedsabso_jax.Robot, got {type(robot).__name__}")
        if isinstance(terms, str):
            raise TypeError(f"terms must be terms (Offset(), ...), not the text {terms!r}: "
                            f"parse_friction({terms!r}) reads it")
        if base is None:
            base = base_parameters(robot)
        elif not isinstance(base, BaseParameters) or base.robot.n_params != robot.n_params:
            raise ValueError("base must be base_parameters(robot) of this robot")
        found = (terms,) if isinstance(terms, AbstractTerm) else terms
        try:
            found = tuple(found)
        except TypeError:
            raise TypeError(f"terms must be a term or several (Offset(), [Offset(), "
                            f"SmoothCoulomb()]), got {terms!r}") from None
        return cls(base, found, transmission, recordings, search)  # type: ignore[arg-type]

    @property
    def robot(self) -> Robot:
        return self.base.robot

    @property
    def friction(self) -> str:
        """The terms as the command line writes them: ``viscous-coulomb+offset+...``."""
        return friction_text(self.terms)

    @property
    def searched_by(self) -> AbstractSearch:
        """The search method of :attr:`search`, or the default."""
        return DEFAULT_SEARCH if self.search is None else self.search

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

    def check_recordings(self, count: int) -> None:
        """That a model with one torque offset per recording has ``count`` of them."""
        if self.recordings > 1 and self.recordings != count:
            raise ValueError(f"the torque model has one offset per recording for "
                             f"{self.recordings} recordings; the data hold {count}")

    def _extra_names(self) -> list[str]:
        return [name for term in self.terms for name in term.names(self)]

    # what a model works out about itself once lives on it (functools.cached_property)
    @functools.cached_property
    def structure(self) -> tuple:
        """What sets the model's columns: its base, terms, transmission and recordings,
        by their tree structure and values (:func:`tree_key`; the search method sets
        none)."""
        return tree_key((self.base, self.terms, self.transmission, self.recordings))

    @functools.cached_property
    def kept(self) -> np.ndarray:
        """Which of its every columns (:meth:`regressor`'s ``every_column``) the model
        fits (booleans): the base columns, the extra ones the base does not span."""
        out = np.zeros(self.base.rank + len(self._extra_names()), dtype=bool)
        out[:self.base.rank] = True
        out[self.base.rank + kept_columns(self)] = True
        return out

    @property
    def regrouped(self) -> tuple[str, ...]:
        """Extra columns dropped because the base regressor spans them."""
        extra = self._extra_names()
        return tuple(n for n, k in zip(extra, self.kept[self.base.rank:]) if not k)

    @functools.cached_property
    def names(self) -> tuple[str, ...]:
        kept = self.kept[self.base.rank:]
        return tuple(self.base.names) + tuple(n for n, k in zip(self._extra_names(), kept) if k)

    def _per_column(self, answer) -> np.ndarray:
        extra = [answer(term) for term in self.terms for _ in term.names(self)]
        kept = self.kept[self.base.rank:]
        return np.array([False] * self.base.rank + [e for e, k in zip(extra, kept) if k], bool)

    @functools.cached_property
    def nonnegative(self) -> np.ndarray:
        """Per column (:attr:`names`): whether a physical value is >= 0 (the terms that
        say so; the base columns are constrained through the full parameters)."""
        return self._per_column(lambda t: t.nonnegative)

    @functools.cached_property
    def bodies(self) -> np.ndarray:
        """Per column (:attr:`names`): whether it is a rigid body's inertial parameter
        (10 a body, :attr:`~._term.AbstractTerm.body`), constrained as the links are."""
        return self._per_column(lambda t: t.body)

    @property
    def dim(self) -> int:
        return len(self.names)

    @functools.cached_property
    def rigid_columns(self) -> np.ndarray:
        """The base columns of the rigid body: all but each joint's viscous and Coulomb
        friction (which never regroup)."""
        friction = {c for p in ("FV", "FC") for c in self.base.joint_columns(p)
                    if c is not None}
        return np.array([c for c in range(self.base.rank) if c not in friction], dtype=int)

    @functools.cached_property
    def shaping(self) -> tuple[AbstractTerm, ...]:
        """The terms that reshape the Coulomb columns (:meth:`AbstractTerm.coulomb`)."""
        still = np.zeros((1, self.robot.n_joints))
        return tuple(t for t in self.terms if t.coulomb(still) is not None)

    def coulomb(self, qd: Any) -> tuple[Any, bool]:
        """The model's Coulomb shape at ``qd`` (the last shaping term's, else
        ``sign(qd)``) and whether a term reshaped it."""
        return (self.shaping[-1].coulomb(qd), True) if self.shaping else (jnp.sign(qd), False)

    @property
    def prior_values(self) -> np.ndarray:
        """The robot's own (a-priori) parameters as the model's values: projected on the
        base, the extra columns 0."""
        return np.r_[np.asarray(self.base.values, dtype=float), np.zeros(self.dim - self.base.rank)]

    def rigid_values(self, values: np.ndarray) -> np.ndarray:
        """The values (of :attr:`names`) of the rigid-body columns: the base columns but
        friction (:attr:`rigid_columns`), then every column of the terms that are bodies
        (0 for one that regroups), in :meth:`signals`' ``rigid`` order."""
        values = np.asarray(values, dtype=float)
        out = [values[self.rigid_columns]]
        extra = np.flatnonzero(self.kept[self.base.rank:])
        position = {int(e): self.base.rank + i for i, e in enumerate(extra)}
        start = 0
        for term in self.terms:
            size = len(term.names(self))
            if term.body:
                out.append(np.array([values[position[e]] if e in position else 0.0
                                     for e in range(start, start + size)]))
            start += size
        return np.concatenate(out)

    def signals(self, q, qd, qdd, recording=None, base_rows=None) -> Signals:
        """What the terms' columns read at these samples (:class:`~._term.Signals`):
        the model's Coulomb shape; ``base_rows`` the base regressor
        (the rigid-body rows are its columns but friction, then the columns of the terms
        that are bodies)."""
        coulomb, _ = self.coulomb(qd)
        s = Signals(q, qd, qdd, recording, coulomb)
        if base_rows is None:
            return s
        take = np.take if isinstance(base_rows, np.ndarray) else jnp.take  # np: no copy
        rigid: Any = take(base_rows, self.rigid_columns, axis=-1)  # faster than indexing
        bodies = [term.columns(self, s) for term in self.terms if term.body]
        if bodies:
            rigid = jnp.concatenate([rigid, *bodies], -1)
        return dataclasses.replace(s, rigid=rigid)

    def _full_regressor(self, q, qd, qdd, recording=None, base_rows=None,
                        rows=None) -> np.ndarray:
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        Y = self.base.regressor(q, qd, qdd) if base_rows is None else base_rows
        # traced (searched values, :meth:`partition`, or inside jax.jit): the columns
        # assembled in jax.numpy; else in NumPy, the measured rows not copied into JAX
        xp: Any = jnp if any(isinstance(x, jax.core.Tracer)
                             for x in jax.tree_util.tree_leaves((self.terms, Y))) else np
        Y = xp.asarray(Y)
        n = self.robot.n_joints
        batch = Y.shape[:-2]
        q, qd, qdd = (np.broadcast_to(a, batch + (n,)) for a in (q, qd, qdd))
        s = self.signals(q, qd, qdd, recording, Y)
        mask = None if rows is None else np.asarray(rows)
        if mask is not None and (mask.dtype != bool or mask.shape != batch[:1]):
            raise ValueError(f"rows must be {batch[:1]} booleans, got {mask.dtype} {mask.shape}")
        keep: Any = slice(None) if mask is None else mask
        Y = Y[keep].copy() if self.shaping and xp is np else Y[keep]
        if self.shaping:  # a term reshapes the Coulomb columns
            fc = (..., np.arange(n), np.array(self.base.joint_columns("FC")))
            if xp is np:
                Y[fc] = np.asarray(s.coulomb)[keep]
            else:
                Y = Y.at[fc].set(s.coulomb[keep])
        extra = [xp.asarray(term.columns(self, s))[keep] for term in self.terms]
        return xp.concatenate([Y, *extra], -1)

    def regressor(self, q: Float[ArrayLike, "*batch n"], qd: Float[ArrayLike, "*batch n"],
                  qdd: Float[ArrayLike, "*batch n"],
                  recording: Int[ArrayLike, "*batch"] | None = None, *,
                  base_rows: Float[ArrayLike, "*batch n b"] | None = None,
                  every_column: bool = False, rows: Bool[ArrayLike, " T"] | None = None
                  ) -> Float[np.ndarray, "*batch n d"]:
        """``(..., n, dim)``: the base columns, then the identifiable extra columns;
        ``recording``: the recording of each sample (one offset per recording; the
        recordings a state restarts at); None: one recording, or a new motion (the
        offsets' mean); ``base_rows``: the base regressor at these samples when already
        computed; ``every_column``: also the extra columns the base regressor spans;
        ``rows``: only the rows of the samples (``(T,)`` mask) this selects. A term with a
        state integrates it along all the samples (in time order within each
        recording)."""
        Y = self._full_regressor(q, qd, qdd, recording, base_rows, rows=rows)
        if every_column:
            return Y
        return Y if self.kept.all() else Y[..., self.kept]

    def predict(self, values: Float[ArrayLike, " d"], q: Float[ArrayLike, "*batch n"],
                qd: Float[ArrayLike, "*batch n"], qdd: Float[ArrayLike, "*batch n"],
                recording: Int[ArrayLike, "*batch"] | None = None
                ) -> Float[np.ndarray, "*batch n"]:
        """Torques ``regressor(q, qd, qdd, recording) @ values``, ``(..., n)``; terms
        still waiting for fitted values (:attr:`waiting`) read ``values``."""
        values = np.asarray(values, dtype=float)
        if values.shape != (self.dim,):
            raise ValueError(f"values must have shape ({self.dim},), got {values.shape}")
        model = self.reading(values, only=lambda term: term.waiting)
        return model.regressor(q, qd, qdd, recording) @ values

    def nonlinear(self) -> list[tuple[int, Nonlinear]]:
        """The parameters a fit searches: ``(term index, Nonlinear)`` of each term that
        has some."""
        found = ((i, term.nonlinear(self)) for i, term in enumerate(self.terms))
        return [(i, f) for i, f in found if f is not None]

    def partition(self) -> tuple[TorqueModel, TorqueModel]:
        """``(searched, rest)``: the searched parameters as leaves, as ``equinox.partition``
        gives them; ``equinox.combine(searched, rest)`` is the model with their values
        (:func:`~._leaves.partition`)."""
        return partition(self)

    def with_nonlinear(self, values: Any) -> TorqueModel:
        """The model with the searched parameters at ``values`` (those of
        :meth:`nonlinear`, concatenated; traced values inside a compiled search, as array
        leaves: :func:`~._leaves.with_nonlinear`)."""
        return with_nonlinear(self, values)

    @property
    def waiting(self) -> bool:
        """Whether a term waits for the model's fitted values before its columns exist."""
        return any(term.waiting for term in self.terms)

    @property
    def iterates(self) -> bool:
        """Whether a term reads every fit's values until they settle (a fixed point)."""
        return any(term.iterates for term in self.terms)

    def without_waiting(self) -> TorqueModel:
        """The model without the terms that wait for fitted values (what gives them
        their first values)."""
        return dataclasses.replace(self, terms=tuple(t for t in self.terms if not t.waiting))

    def reading(self, values: Float[ArrayLike, " d"], *,
                only: Callable[[AbstractTerm], bool] = lambda term: True) -> TorqueModel:
        """The model whose terms (those ``only`` selects) read the fitted ``values`` (the
        base values first); the model itself where none reads them."""
        terms = tuple(t.reading(self, values) if only(t) else t for t in self.terms)
        if all(a is b for a, b in zip(terms, self.terms)):
            return self
        read = dataclasses.replace(self, terms=terms)
        read.__dict__["kept"] = self.kept  # the same (kept_columns reads no value read)
        return read
