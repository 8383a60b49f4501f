"""Converting and checking the options of estimators and torque-model terms, as their
``eqx.field(converter=...)`` and ``__check_init__`` do: a converter turns what it can
into the kept type and leaves anything else for the check, which names the option."""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np


def as_int(value: object) -> object:
    """An integer (not a bool) as ``int``; anything else as given."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return int(value)
    return value


def as_float(value: object) -> object:
    """A real number (not a bool) as ``float``; anything else as given."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    return value


def as_floats(value: object) -> object:
    """A 1-D array of numbers as a tuple of floats (None stays None); anything else as
    given."""
    if value is None or isinstance(value, str):
        return value
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return value
    return tuple(float(x) for x in v) if v.ndim == 1 else value


def check_count(name: str, value: object, minimum: int) -> None:
    """That ``value`` is an integer >= ``minimum``."""
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")


def check_number(name: str, value: object, strict: bool = False) -> None:
    """That ``value`` is a finite number >= 0 (> 0 if ``strict``)."""
    if not isinstance(value, float) or not (np.isfinite(value)
                                            and (value > 0 if strict else value >= 0)):
        raise ValueError(f"{name} must be a number {'>' if strict else '>='} 0, got {value!r}")


def one_or_more(value: Any, kind: type) -> tuple[Any, ...]:
    """``value`` as a tuple: one ``kind`` as a tuple of it, a sequence of them as a
    tuple."""
    return (value,) if isinstance(value, kind) else tuple(value)
