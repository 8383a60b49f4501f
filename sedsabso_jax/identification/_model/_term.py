"""What a torque-model term is: the interface (:class:`AbstractTerm`), what its columns
read (:class:`Signals`) and the parameters it has that a fit searches
(:class:`Nonlinear`).

A term is an immutable value. It owns everything about itself:

- its columns (:meth:`~AbstractTerm.columns`, named by :meth:`~AbstractTerm.names`),
  computed with ``jax.numpy`` (the same code gives a fit's columns and, traced, the
  compiled search's), or a new shape of the Coulomb columns
  (:meth:`~AbstractTerm.coulomb`);
- the constraint a physical body puts on its coefficients (:attr:`~AbstractTerm.nonnegative`,
  :attr:`~AbstractTerm.body`), for the physically consistent fit;
- the parameters that enter its columns nonlinearly (:meth:`~AbstractTerm.nonlinear`),
  their bounds and how the term reads a trial of them (:meth:`~AbstractTerm.with_nonlinear`);
- a state along the samples, if it has one: the :class:`Signals` give each recording's
  increments from its start (:meth:`Signals.increments`); the signals are always the
  whole recordings' (a validation split takes its rows of the columns);
- what it reads of the model's own fitted values, if anything (:attr:`~AbstractTerm.waiting`,
  :meth:`~AbstractTerm.reading`): the fit gives it a first fit's values, and again each
  later fit's while it :attr:`~AbstractTerm.iterates`;
- its word in the command line's ``--friction`` text (:attr:`~AbstractTerm.name`,
  :meth:`~AbstractTerm.parse`, :attr:`~AbstractTerm.text`) and its settings in reports.

Nothing outside a term asks which kind it is: the model, the fit and the validation read
these answers.
"""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import abc
import dataclasses
from typing import Any, ClassVar, Protocol

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..._deprecation import warn
from ...dynamics._base_parameters import BaseParameters
from ...dynamics._robot import Robot
from ._dahl import increments


@dataclasses.dataclass(frozen=True, eq=False)
class Nonlinear:
    """A term's parameters that enter its columns nonlinearly and that a fit searches
    (each ``(k,)``: ``values`` to start from, ``lower`` and ``upper`` bounds, all > 0,
    searched in log scale), their ``names`` in reports and their ``unit``; ``field``:
    the term's field that holds them, a leaf of the model
    (:meth:`~._torque_model.TorqueModel.partition`: an array ``(k,)`` in a trial, floats
    once found), or None where the term places them itself
    (:meth:`~AbstractTerm.with_nonlinear`)."""

    names: tuple[str, ...]
    values: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    unit: str
    field: str | None = None


@dataclasses.dataclass(frozen=True, eq=False)
class Signals:
    """What a term's columns read, each ``(..., n)``: positions, velocities,
    accelerations; ``recording`` each sample's recording (``(...)``) or None (one
    recording, or a new motion); ``coulomb`` the model's Coulomb shape ``c(qd)``.

    ``rigid``: the rows of the model's rigid-body columns (the base columns but each
    joint's viscous and Coulomb friction, then the columns of terms that are bodies),
    ``(..., n, r)``, where a term reads the model's own torque.

    The samples are whole recordings in time order (a validation split takes its rows of
    the columns), so a term's state integrates along them (:meth:`increments`)."""

    q: Any
    qd: Any
    qdd: Any
    recording: Any
    coulomb: Any
    rigid: Any = None

    @property
    def batch(self) -> tuple[int, ...]:
        return tuple(self.qd.shape[:-1])

    @property
    def xp(self) -> Any:
        """Deprecated: terms compute with ``jax.numpy`` (this is it)."""
        warn("Signals.xp", "jax.numpy", removed_after="0.6")
        return jnp

    def rigid_torque(self, values: np.ndarray) -> np.ndarray:
        """The model's rigid-body torque ``(..., n)`` with the rigid-body columns'
        ``values`` (:meth:`~._torque_model.TorqueModel.rigid_values`)."""
        if self.rigid is None:
            raise ValueError("these signals carry no rigid-body rows")
        if isinstance(self.rigid, np.ndarray):  # measured rows: no copy into JAX
            rows = self.rigid.reshape(-1, self.rigid.shape[-1])  # one matrix-vector product
            return (rows @ np.asarray(values, dtype=float)).reshape(self.rigid.shape[:-1])
        return self.rigid @ jnp.asarray(values)

    def increments(self) -> tuple[Any, Any]:
        """Each sample's position increment from the previous one in its recording
        (``(T, n)``, 0 at a recording's start) and where each recording starts
        (``(T,)``), over the whole recordings (time order): :func:`~._dahl.increments`."""
        return increments(self.q, self.recording)


@dataclasses.dataclass(frozen=True, eq=False)
class InSimulator:
    """What a rigid-body simulator (MuJoCo) holds of a term, per joint (``(n,)`` each,
    None: nothing of that kind): the rotor inertia seen at the joint (``armature``), a
    torque the actuators subtract from the measured one (``offset``), dry friction added
    to the joint's Coulomb friction (``frictionloss``); ``lost``: what of the term it
    cannot hold, in words (empty: nothing)."""

    armature: np.ndarray | None = None
    offset: np.ndarray | None = None
    frictionloss: np.ndarray | None = None
    lost: str = ""


class ModelView(Protocol):
    """What a term reads of its torque model (:class:`~._torque_model.TorqueModel`)."""

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

    def rigid_values(self, values: np.ndarray) -> np.ndarray: ...

    @property
    def prior_values(self) -> np.ndarray: ...


class AbstractTerm(eqx.Module):
    """A term of the torque model beyond the rigid-body base regressor (module
    docstring). A final class sets ``name`` (its word in ``--friction``) and
    ``nonnegative`` (whether a physical body has its coefficients ``>= 0``), and
    implements :meth:`names` and :meth:`columns`; the rest has defaults: no Coulomb
    shape, no searched parameters, no state, reads nothing of the fit."""

    name: eqx.AbstractClassVar[str]
    nonnegative: eqx.AbstractClassVar[bool]
    #: The fields holding values read of a fit, the model's rigid-body values
    #: (:meth:`~._torque_model.TorqueModel.rigid_values`), None until read (the term
    #: :attr:`waiting`; :meth:`reading` fills them): a search takes them as its compiled
    #: call's arguments, so that one compilation serves the fits of every split
    #: (:class:`~.._fit._projection.Projection`).
    read_fields: ClassVar[tuple[str, ...]] = ()

    @abc.abstractmethod
    def names(self, model: ModelView) -> tuple[str, ...]:
        """The names of this term's columns in ``model`` (a ValueError where the term does
        not apply to the model)."""

    @abc.abstractmethod
    def columns(self, model: ModelView, s: Signals) -> Any:
        """The columns ``(..., n, len(names))`` at the samples of ``s``, computed with
        ``jax.numpy``."""

    def coulomb(self, qd: Any) -> Any:
        """The Coulomb columns' values in place of ``sign(qd)``, or None to keep them."""
        return None

    @property
    def unit(self) -> str:
        """The unit of the term's coefficients in reports, with their names (``"N m for a
        torque offset OFF"``); empty where the term has no columns of its own."""
        return ""

    @property
    def body(self) -> bool:
        """Whether the columns are rigid bodies' inertial parameters, 10 a body in the
        robot's order (``XX YY ZZ XY XZ YZ M MX MY MZ``): a physical body has a positive
        semidefinite pseudo-inertia."""
        return False

    def nonlinear(self, model: ModelView) -> Nonlinear | None:
        """The parameters a fit searches, or None (none, or fixed); their
        :attr:`Nonlinear.field` names the field that holds them."""
        return None

    def with_nonlinear(self, values: Any) -> "AbstractTerm":
        """The term with its searched parameters at ``values`` (floats; or traced values
        inside a compiled search, taken as they are), for a term whose
        :meth:`nonlinear` names no :attr:`Nonlinear.field` (the model places them in that
        field otherwise)."""
        raise ValueError(f"term {self.name!r} has no parameters to search")

    def held(self, model: ModelView, values: np.ndarray) -> InSimulator | None:
        """What a rigid-body simulator holds of this term with its coefficients ``values``
        (one per name), or None where it holds none of it (the term is then left out of
        a simulator's model, :meth:`~.._fit._identify.Identification.mjcf`)."""
        return None

    @property
    def held_in_full(self) -> bool:
        """Whether :meth:`held` keeps the whole term (at most a transmission's coupling
        lost): a model made to be written for a simulator has only such terms."""
        return False

    @property
    def waiting(self) -> bool:
        """Whether the columns read the model's own fitted values and have none yet (a
        :attr:`read_fields` None): the fit first fits the model without the waiting terms
        and gives them its values."""
        return any(getattr(self, field) is None for field in self.read_fields)

    @property
    def iterates(self) -> bool:
        """Whether the term reads every fit's values until its columns settle (a fixed
        point), not only the first fit's."""
        return False

    def reading(self, model: ModelView, values: Any) -> "AbstractTerm":
        """The term reading the model's fitted ``values`` (the base values first): its
        :attr:`read_fields` at their rigid-body values; itself for a term that reads none."""
        if not self.read_fields:
            return self
        rigid = tuple(float(v) for v in model.rigid_values(np.asarray(values, dtype=float)))
        return dataclasses.replace(self, **dict.fromkeys(self.read_fields, rigid))

    def read_line(self, step: dict) -> str:
        """A report's line on what the term read of the fit (``step``: the fit's record
        of it, ``iterations`` and, for a fixed point, ``settled``); empty for a term that
        reads none."""
        return ""

    @property
    def text(self) -> str:
        """The term in the command line's ``--friction`` text (``name[:option]``)."""
        return self.name

    @classmethod
    def parse(cls, option: str | None) -> "AbstractTerm":
        """The term of the command line's ``name:option`` text (no option: defaults)."""
        if option is not None:
            raise ValueError(f"friction term {cls.name!r} takes no option, got "
                             f"{cls.name}:{option}")
        return cls()

    def settings(self) -> dict:
        """The term's options for the report, ``{name_option: value}``."""
        return {f"{self.name}_{f.name}": getattr(self, f.name)
                for f in dataclasses.fields(self)}


def diagonal(values: Any, n: int) -> Any:
    """``(..., n, n)`` columns with ``values (..., n)`` on joint ``j``'s own column ``j``
    (exact zeros elsewhere)."""
    return jnp.where(np.eye(n, dtype=bool), jnp.asarray(values)[..., None, :], 0.0)


def through_motors(K: np.ndarray, motors: list[int], v: Any, sign: bool = False) -> Any:
    """Columns ``K[m, j] u_m`` for joint ``j``, motor ``m`` of ``motors``, with ``u_m =
    K_m . v`` (or its sign): a motor-side coefficient seen at the joints."""
    Km = jnp.asarray(K)[np.asarray(motors, dtype=int)]
    u = jnp.asarray(v) @ Km.T  # (..., motors)
    if sign:
        u = jnp.sign(u)
    return Km.T * u[..., None, :]
