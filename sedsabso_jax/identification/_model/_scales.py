"""Terms with a scale per joint that a fit may search (:class:`AbstractScale`): of a
velocity (:class:`AbstractVelocityScale`: :class:`~._friction.SmoothCoulomb`,
:class:`~._friction.Stribeck`) or a displacement (:class:`~._presliding.Presliding`);
the converter and check of a scale given as one number or one per joint."""

# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import dataclasses
from typing import Any, ClassVar

import equinox as eqx
import jax
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


class AbstractScale(AbstractTerm):
    """A term with a scale per joint (a velocity, a displacement): fixed (one for every
    joint, or one per joint), or with ``fitted=True`` one per joint searched by the fit
    from the value given, within :attr:`bounds`. A final class names its scale's field
    (``scale_name``), its unit (``scale_unit``), its default (``default_scale``) and the
    scales' names in reports (``{symbol}{joint}``)."""

    fitted: eqx.AbstractVar[bool]
    bounds: eqx.AbstractClassVar[tuple[float, float]]
    scale_name: eqx.AbstractClassVar[str]
    scale_unit: eqx.AbstractClassVar[str]
    default_scale: eqx.AbstractClassVar[float]
    symbol: eqx.AbstractClassVar[str]

    @property
    def scale(self) -> Any:
        """The scale as given: one number, or one per joint (traced values inside a
        compiled search)."""
        return getattr(self, self.scale_name)

    def __check_init__(self):
        check_scale(f"{type(self).__name__}'s {self.scale_name}", self.scale)
        if not isinstance(self.fitted, bool):
            raise ValueError(f"{type(self).__name__}'s fitted must be True or False, got "
                             f"{self.fitted!r}")

    def per_joint(self, n: int) -> Any:
        """The scale of each of ``n`` joints."""
        v = jnp.asarray(self.scale, dtype=float)
        if v.ndim and v.shape != (n,):
            raise ValueError(f"{self.name}'s {self.scale_name} must be one number or one "
                             f"per joint ({n}), got {len(v)}")
        return jnp.broadcast_to(v, (n,))

    def search_bounds(self) -> tuple[float, float]:
        """The box the fit searches the scales in (:attr:`bounds` unless a term narrows
        it)."""
        return self.bounds

    @property
    def text(self) -> str:
        v = self.scale
        if self.fitted:
            return f"{self.name}:fit"
        if v != self.default_scale:
            return f"{self.name}:" + (f"{v:g}" if isinstance(v, float)
                                      else ",".join(f"{x:g}" for x in v))
        return self.name

    @classmethod
    def parse(cls, option: str | None) -> AbstractTerm:
        if option is None or option == "fit":
            return cls(fitted=option == "fit")  # type: ignore[call-arg]
        expected = (f"friction term {cls.name!r}: expected {cls.name}:fit or "
                    f"{cls.name}:{cls.scale_name.upper()} ({cls.scale_unit}, one or one per "
                    f"joint, comma-separated")
        try:
            values = [float(v) for v in option.split(",")]
        except ValueError:
            raise ValueError(f"{expected}), got {cls.name}:{option}") from None
        if not all(0 < v < float("inf") for v in values):  # NaN too
            raise ValueError(f"{expected}, each > 0), got {cls.name}:{option}")
        return cls(**{cls.scale_name: values[0] if len(values) == 1  # type: ignore[arg-type]
                      else tuple(values)})

    def nonlinear(self, model: ModelView) -> Nonlinear | None:
        if not self.fitted:
            return None
        n = model.robot.n_joints
        lo, hi = self.search_bounds()
        return Nonlinear(tuple(f"{self.symbol}{j + 1}" for j in range(n)),
                         np.clip(np.broadcast_to(np.asarray(self.scale, float), (n,)), lo, hi),
                         np.full(n, lo),
                         np.full(n, hi), self.scale_unit)

    def with_nonlinear(self, values: Any) -> AbstractTerm:
        if isinstance(values, jax.core.Tracer):  # a trial inside a compiled search
            name = self.scale_name
            return eqx.tree_at(lambda t: getattr(t, name), self, values)
        scale = {self.scale_name: tuple(float(v) for v in np.asarray(values))}
        return dataclasses.replace(self, **scale)  # type: ignore[arg-type]

    def settings(self) -> dict:
        v = self.scale
        out: dict = {f"{self.name}_{self.scale_name}": list(v) if isinstance(v, tuple) else v}
        if self.fitted:
            out[f"{self.name}_fitted"] = True
        return out


class AbstractVelocityScale(AbstractScale):
    """A term with a velocity scale (rad/s or m/s): :class:`AbstractScale` of the field
    ``velocity``."""

    velocity: eqx.AbstractVar[float | tuple[float, ...]]
    #: The scales' search box (rad/s or m/s).
    bounds: ClassVar[tuple[float, float]] = (1e-4, 1.0)
    scale_name: ClassVar[str] = "velocity"
    scale_unit: ClassVar[str] = "rad/s"
