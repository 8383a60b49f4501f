"""Terms with a scale a fit may search (:mod:`._shapes`): a velocity scale
(:class:`AbstractVelocityScale`, of :class:`~._terms.SmoothCoulomb` and
:class:`~._terms.Stribeck`), and the converter and check of a scale given as one number
or one per joint (also :class:`~._terms.Presliding`'s displacement)."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import dataclasses
from typing import ClassVar

import equinox as eqx
import numpy as np

from ._options import as_float, as_floats, check_number
from ._term_base import AbstractTerm, Shapes, TorqueModelView


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


def per_joint(name: str, value: float | tuple[float, ...], n: int) -> np.ndarray:
    """A scale of each of ``n`` joints: ``value`` for all, or its ``n`` values."""
    v = np.asarray(value, dtype=float)
    if v.ndim and v.shape != (n,):
        raise ValueError(f"{name} must be one number or one per joint ({n}), got {len(v)}")
    return np.broadcast_to(v, (n,))


class AbstractVelocityScale(AbstractTerm):
    """A term with a velocity scale (rad/s or m/s): fixed (one for every joint, or one
    per joint), or with ``fitted=True`` one per joint searched by the fit from the value
    given (:mod:`._shapes`) within :attr:`bounds`."""

    velocity: eqx.AbstractVar[float | tuple[float, ...]]
    fitted: eqx.AbstractVar[bool]
    #: The scales' search box (rad/s or m/s).
    bounds: ClassVar[tuple[float, float]] = (1e-4, 1.0)
    #: The scales' names in reports: ``{symbol}{joint}``.
    symbol: eqx.AbstractClassVar[str]
    default_velocity: eqx.AbstractClassVar[float]

    def __check_init__(self):
        check_scale(f"{type(self).__name__}'s velocity", self.velocity)

    def per_joint(self, n: int) -> np.ndarray:
        """The velocity scale of each of ``n`` joints."""
        return per_joint(f"{self.name}'s velocity", self.velocity, n)

    @property
    def text(self) -> str:
        if self.fitted:
            return f"{self.name}:fit"
        if self.velocity != self.default_velocity:
            return f"{self.name}:{self.velocity:g}" if isinstance(self.velocity, float) \
                else f"{self.name}:" + ",".join(f"{v:g}" for v in self.velocity)
        return self.name

    @classmethod
    def parse(cls, option: str | None) -> AbstractTerm:
        if option is None:
            return cls()  # type: ignore[call-arg]
        if option == "fit":
            return cls(fitted=True)  # type: ignore[call-arg]
        try:
            values = [float(v) for v in option.split(",")]
        except ValueError:
            raise ValueError(f"friction term {cls.name!r}: expected {cls.name}:fit or "
                             f"{cls.name}:VELOCITY (rad/s, one or one per joint, "
                             f"comma-separated), got {cls.name}:{option}") from None
        return cls(velocity=values[0] if len(values) == 1 else tuple(values))  # type: ignore[call-arg]

    def shapes(self, model: TorqueModelView) -> Shapes | None:
        if not self.fitted:
            return None
        return searched(self.symbol, self.per_joint(model.robot.n_joints), self.bounds)

    def with_shapes(self, values: np.ndarray) -> AbstractTerm:
        return dataclasses.replace(self, velocity=tuple(float(v) for v in values))

    def settings(self) -> dict:
        v = self.velocity
        out: dict = {f"{self.name}_velocity": list(v) if isinstance(v, tuple) else v}
        if self.fitted:
            out[f"{self.name}_fitted"] = True
        return out


def searched(symbol: str, values: np.ndarray, bounds: tuple[float, float]) -> Shapes:
    """The :class:`Shapes` of one scale per joint, ``{symbol}{joint}``, searched from
    ``values`` (clipped to ``bounds``) within ``bounds``."""
    n, (lo, hi) = len(values), bounds
    return Shapes(tuple(f"{symbol}{j + 1}" for j in range(n)), np.clip(values, lo, hi),
                  np.full(n, lo), np.full(n, hi))
