"""Terms with a scale per joint that a fit may search (:class:`AbstractScale`, its field
declared with :func:`scale`): of a velocity (:class:`~._friction.SmoothCoulomb`,
:class:`~._friction.Stribeck`) or a displacement (:class:`~._presliding.Presliding`);
the converter and check of a scale given as one number or one per joint."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import dataclasses
import functools
from typing import Any, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._options import as_float, as_floats, check_number
from ._term import AbstractTerm, ModelView, Nonlinear


def as_scale(value: object) -> object:
    """A scale (a velocity, a displacement): one number for every joint (a float) or one
    per joint (a tuple of floats); anything else as given, for the check to name."""
    if isinstance(value, (list, tuple, np.ndarray)):
        converted = as_floats(value)
        return converted if isinstance(converted, tuple) else value
    return as_float(value)


def check_scale(name: str, value: object) -> None:
    """A scale is a number > 0, or one per joint."""
    for v in value if isinstance(value, tuple) else (value,):
        check_number(name, v, strict=True)


@dataclasses.dataclass(frozen=True)
class Declared:
    """What a term declares of its scale (:func:`scale`): the field's ``name`` and
    ``default``, the box a fit searches it in (``bounds``), its ``unit`` and the searched
    values' names in reports (``{symbol}{joint}``)."""

    name: str
    default: float
    bounds: tuple[float, float]
    unit: str
    symbol: str


def scale(default: float, *, bounds: tuple[float, float], unit: str, symbol: str) -> Any:
    """The field of an :class:`AbstractScale` that holds its scale: ``default`` (one number
    for every joint), ``bounds`` (the box a fit searches it in), ``unit`` and ``symbol``
    (the searched values' names in reports, ``{symbol}{joint}``)::

        velocity: float | tuple[float, ...] = scale(0.02, bounds=(1e-4, 1.0),
                                                    unit="rad/s", symbol="v_smooth")
    """
    return eqx.field(default=default, converter=as_scale,
                     metadata={"scale": (tuple(float(b) for b in bounds), unit, symbol)})


class AbstractScale(AbstractTerm):
    """A term with a scale per joint (a velocity, a displacement), the one field it
    declares with :func:`scale`: fixed (one for every joint, or one per joint), or with
    ``fitted=True`` one per joint searched by the fit from the value given, within its
    bounds (:meth:`declared`)."""

    fitted: eqx.AbstractVar[bool]
    #: A field that narrows the box a fit searches (None until given, then a number, only
    #: with ``fitted=True``) and the end it sets, 0 the lower, 1 the upper: the command
    #: line's ``name:fit:VALUE``; None: the declared box only.
    narrowed_by: ClassVar[tuple[str, int] | None] = None
    #: A narrowing value the command line's messages give as an example.
    narrowed_example: ClassVar[float] = 0.0

    @classmethod
    @functools.cache
    def declared(cls) -> Declared:
        """The scale field's declaration (:func:`scale`), read once per class."""
        found = [Declared(f.name, float(f.default), *f.metadata["scale"])  # type: ignore[arg-type]
                 for f in dataclasses.fields(cls) if "scale" in f.metadata]
        if len(found) != 1:
            raise TypeError(f"{cls.__name__} must declare one scale field with scale(...), "
                            f"found {len(found)}")
        return found[0]

    @property
    def scale(self) -> Any:
        """The scale as given: one number, or one per joint (traced values inside a
        compiled search)."""
        return getattr(self, self.declared().name)

    def __check_init__(self):
        check_scale(f"{type(self).__name__}'s {self.declared().name}", self.scale)
        if not isinstance(self.fitted, bool):
            raise ValueError(f"{type(self).__name__}'s fitted must be True or False, got "
                             f"{self.fitted!r}")
        value = self.narrowing
        if value is not None and not (self.fitted and isinstance(value, float)
                                      and self._inside(value)):
            raise ValueError(f"{type(self).__name__}'s {self.narrowed_by[0]} must be a "  # type: ignore[index]
                             f"number in {self.interval()} with fitted=True, got {value!r} "
                             f"(fitted={self.fitted!r})")

    @property
    def narrowing(self) -> float | None:
        """The value of the field that narrows the searched box (:attr:`narrowed_by`)."""
        return None if self.narrowed_by is None else getattr(self, self.narrowed_by[0])

    @classmethod
    def interval(cls) -> str:
        """Where a narrowing value may lie: inside the declared box, at most its upper end
        for an upper bound, at least its lower end for a lower one."""
        lo, hi = cls.declared().bounds
        upper = cls.narrowed_by is not None and cls.narrowed_by[1] == 1
        return f"({lo:g}, {hi:g}]" if upper else f"[{lo:g}, {hi:g})"

    @classmethod
    def _inside(cls, value: float) -> bool:
        lo, hi = cls.declared().bounds
        upper = cls.narrowed_by is not None and cls.narrowed_by[1] == 1
        return lo < value <= hi if upper else lo <= value < hi  # NaN: False

    def check_joints(self, n: int) -> None:
        """A ValueError unless the scale is one number or one per joint of ``n``."""
        shape = np.shape(self.scale)
        if shape and shape != (n,):
            raise ValueError(f"{self.name}'s {self.declared().name} must be one number or one "
                             f"per joint ({n}), got {shape[0]}")

    def per_joint(self, n: int) -> Any:
        """The scale of each of ``n`` joints."""
        self.check_joints(n)
        return jnp.broadcast_to(jnp.asarray(self.scale, dtype=float), (n,))

    def fixed(self) -> "AbstractScale":
        """The term with its scale fixed where it is (not searched)."""
        narrowing = {} if self.narrowed_by is None else {self.narrowed_by[0]: None}
        return dataclasses.replace(self, fitted=False, **narrowing)

    def search_bounds(self) -> tuple[float, float]:
        """The box the fit searches the scales in: the declared bounds, one end narrowed
        where :attr:`narrowed_by`'s field is given."""
        box = list(self.declared().bounds)
        if self.narrowing is not None:
            box[self.narrowed_by[1]] = self.narrowing  # type: ignore[index]
        return box[0], box[1]

    @property
    def text(self) -> str:
        v = self.scale
        if self.fitted:
            return f"{self.name}:fit" + ("" if self.narrowing is None
                                         else f":{self.narrowing:g}")
        if v != self.declared().default:
            return f"{self.name}:" + (f"{v:g}" if isinstance(v, float)
                                      else ",".join(f"{x:g}" for x in v))
        return self.name

    @classmethod
    def parse(cls, option: str | None) -> AbstractTerm:
        if option is None or option == "fit":
            return cls(fitted=option == "fit")  # type: ignore[call-arg]
        field = cls.declared()
        if cls.narrowed_by is not None and option.startswith("fit:"):
            return cls._parse_narrowed(option)
        expected = (f"friction term {cls.name!r}: expected {cls.name}:fit or "
                    f"{cls.name}:{field.name.upper()} ({field.unit}, one or one per "
                    f"joint, comma-separated")
        try:
            values = [float(v) for v in option.split(",")]
        except ValueError:
            raise ValueError(f"{expected}), got {cls.name}:{option}") from None
        if not all(0 < v < float("inf") for v in values):  # NaN too
            raise ValueError(f"{expected}, each > 0), got {cls.name}:{option}")
        return cls(**{field.name: values[0] if len(values) == 1  # type: ignore[arg-type]
                      else tuple(values)})

    @classmethod
    def _parse_narrowed(cls, option: str) -> AbstractTerm:
        """The term of ``name:fit:VALUE``: searched with one end of its box at VALUE
        (:attr:`narrowed_by`), checked to lie within the declared box."""
        name, end = cls.narrowed_by  # type: ignore[misc]
        field = cls.declared()
        try:
            value = float(option[4:])
        except ValueError:
            value = float("nan")
        if not cls._inside(value):
            word = name.upper()
            where = f"up to {word}" if end else f"from {word} up"
            raise ValueError(f"friction term {cls.name!r}: {cls.name}:fit:{word} searches "
                             f"each joint's {field.name} {where} ({field.unit}), a number in "
                             f"{cls.interval()}, got {cls.name}:{option} (e.g. "
                             f"{cls.name}:fit:{cls.narrowed_example:g})")
        return cls(fitted=True, **{name: value})  # type: ignore[call-arg]

    def nonlinear(self, model: ModelView) -> Nonlinear | None:
        if not self.fitted:
            return None
        n = model.robot.n_joints
        lo, hi = self.search_bounds()
        field = self.declared()
        return Nonlinear(tuple(f"{field.symbol}{j + 1}" for j in range(n)),
                         np.clip(np.broadcast_to(np.asarray(self.scale, float), (n,)), lo, hi),
                         np.full(n, lo),
                         np.full(n, hi), field.unit, field.name)

    def settings(self) -> dict:
        v = self.scale
        out: dict = {f"{self.name}_{self.declared().name}": list(v) if isinstance(v, tuple)
                     else v}
        if self.fitted:
            out[f"{self.name}_fitted"] = True
        if self.narrowing is not None:
            out[f"{self.name}_{self.narrowed_by[0]}"] = self.narrowing  # type: ignore[index]
        return out
