"""Deprecated names: each keeps working until the release it names, with a
DeprecationWarning that points at the caller's line and names the replacement ("... will
be removed after sedsabso-jax X.Y; use ..."); and the caller's line for other warnings."""

from __future__ import annotations

import functools
import sys
import warnings
from types import FrameType
from typing import Any, TypeVar

_INTERNAL = ("sedsabso_jax", "equinox")

_T = TypeVar("_T")


def caller_stacklevel() -> int:
    """The ``stacklevel`` (for a ``warnings.warn`` in the calling function) of the first
    frame outside this package and equinox (whose module metaclass stands between a
    constructor call and ``__init__``): the user's line."""
    frame: FrameType | None = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith(_INTERNAL):
        frame, level = frame.f_back, level + 1
    return level


def warn(old: str, new: str, *, removed_after: str) -> None:
    """Warn that ``old`` is deprecated in favour of ``new`` and goes after release
    ``removed_after`` (e.g. ``"0.5"``)."""
    warnings.warn(f"{old} is deprecated and will be removed after sedsabso-jax "
                  f"{removed_after}; use {new}", DeprecationWarning,
                  stacklevel=caller_stacklevel())


def renamed(cls: type[_T], names: dict[str, str], *, removed_after: str) -> type[_T]:
    """Let the old name stand for the new one, for each ``old: new`` of ``names``, with a
    warning that the old name goes after release ``removed_after``: ``cls(old=...)`` for
    ``cls(new=...)`` (passing both is a TypeError) and ``obj.old`` for ``obj.new``."""
    init = cls.__init__

    @functools.wraps(init)
    def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
        for old, new in names.items():
            if old in kwargs:
                if new in kwargs:
                    raise TypeError(f"{cls.__name__}() got both {old}= (deprecated) and {new}=")
                warn(f"{cls.__name__}({old}=...)", f"{new}=...", removed_after=removed_after)
                kwargs[new] = kwargs.pop(old)
        init(self, *args, **kwargs)

    def alias(old: str, new: str) -> property:
        def get(self: Any) -> Any:
            warn(f"{cls.__name__}.{old}", f"{cls.__name__}.{new}", removed_after=removed_after)
            return getattr(self, new)

        return property(get, doc=f"Deprecated: :attr:`{new}`.")

    cls.__init__ = __init__  # type: ignore[method-assign]
    for old, new in names.items():
        setattr(cls, old, alias(old, new))
    return cls
