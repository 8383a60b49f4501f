"""What a torque-model term is (:mod:`._terms` has them all): the interface
(:class:`AbstractTerm`), what its columns read (:class:`Signals`), the velocity scales a
fit may search (:class:`Shapes`), and the registry of terms by name, in column order."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import abc
import dataclasses
from typing import Protocol

import equinox as eqx
import numpy as np

from ..dynamics._base_parameters import BaseParameters
from ..dynamics._robot import Robot

#: Term name -> final class, in column order (each class registers itself when defined).
TERMS: dict[str, type["AbstractTerm"]] = {}


@dataclasses.dataclass(frozen=True, eq=False)
class Signals:
    """What a term's columns read, each ``(..., n)``: positions, velocities and
    accelerations; ``recording`` each sample's recording (``(...)``) or None; ``coulomb``
    the model's Coulomb shape ``c(qd)``; ``load`` the model's own rigid-body torque at its
    load point (None unless a term asks for it)."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    recording: np.ndarray | None
    coulomb: np.ndarray
    load: np.ndarray | None = None


@dataclasses.dataclass(frozen=True, eq=False)
class Shapes:
    """A term's velocity scales that a fit searches: their names, values and bounds
    (each ``(k,)``, > 0; searched in log scale)."""

    names: tuple[str, ...]
    values: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


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
            TERMS[cls.name] = cls

    @abc.abstractmethod
    def names(self, model: TorqueModelView) -> tuple[str, ...]:
        """The names of this term's columns in ``model`` (a ValueError where the term does
        not apply to the model)."""

    @abc.abstractmethod
    def columns(self, model: TorqueModelView, s: Signals) -> np.ndarray:
        """The columns ``(..., n, len(names))`` at the samples of ``s``."""

    @abc.abstractmethod
    def coulomb(self, qd: np.ndarray) -> np.ndarray | None:
        """The Coulomb columns' values in place of ``sign(qd)``, or None to keep them."""

    @property
    def needs_load(self) -> bool:
        """Whether the columns read the model's rigid-body torque (:attr:`Signals.load`)."""
        return False

    @property
    def stateful(self) -> bool:
        """Whether the columns integrate a state along the samples (each recording's
        samples in time order, whole: a subset's columns are the whole's, taken)."""
        return False

    @property
    def settles_load(self) -> bool:
        """Whether a fit iterates the load to a fixed point (:mod:`._shapes`)."""
        return False

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

    def shapes(self, model: TorqueModelView) -> Shapes | None:
        """The velocity scales a fit searches, or None (none, or fixed)."""
        return None

    def with_shapes(self, values: np.ndarray) -> "AbstractTerm":
        """The term with its searched velocity scales set to ``values``."""
        raise ValueError(f"friction term {self.name!r} has no velocity scales to fit")

    def settings(self) -> dict:
        """The term's options for the report, ``{name_option: value}``."""
        return {f"{self.name}_{f.name}": getattr(self, f.name)
                for f in dataclasses.fields(self)}


class AbstractColumns(AbstractTerm):
    """A term that adds columns and leaves the Coulomb columns as they are."""

    def coulomb(self, qd: np.ndarray) -> None:
        return None


def diagonal(values: np.ndarray | float, batch: tuple[int, ...], n: int) -> np.ndarray:
    """``(..., n, n)`` columns with ``values`` on joint ``j``'s own column ``j``."""
    E = np.zeros(batch + (n, n))
    E[..., np.arange(n), np.arange(n)] = values
    return E


def through_motors(K: np.ndarray, motors: list[int], v: np.ndarray, sign: bool = False
                    ) -> np.ndarray:
    """Columns ``K[m, j] u_m`` for joint ``j``, motor ``m`` of ``motors``, with ``u_m =
    K_m . v`` (or its sign): a motor-side coefficient seen at the joints."""
    u = v @ K[motors].T  # (..., motors)
    if sign:
        u = np.sign(u)
    return K[motors].T * u[..., None, :]
