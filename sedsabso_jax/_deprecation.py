"""Deprecated names and call forms: each keeps working through 0.3.x with a
DeprecationWarning that points at the caller's line and names the replacement."""

from __future__ import annotations

import functools
import importlib
import sys
import warnings

_INTERNAL = ("sedsabso_jax", "equinox")


def caller_stacklevel() -> int:
    """The ``stacklevel`` (for a ``warnings.warn`` in the calling function) of the first
    frame outside this package and equinox (whose module metaclass stands between a
    constructor call and ``__init__``): the user's line."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith(_INTERNAL):
        frame, level = frame.f_back, level + 1
    return level


def warn(old: str, new: str) -> None:
    """Warn that ``old`` is deprecated in favour of ``new``."""
    warnings.warn(f"{old} is deprecated and will be removed after sedsabso-jax 0.3; use {new}",
                  DeprecationWarning, stacklevel=caller_stacklevel())


def renamed_arguments(cls, renamed: dict[str, str]):
    """Let ``cls(old=...)`` stand for ``cls(new=...)`` for each ``old: new``, with a
    warning. Passing both is a TypeError."""
    init = cls.__init__

    @functools.wraps(init)
    def __init__(self, *args, **kwargs):
        for old, new in renamed.items():
            if old in kwargs:
                if new in kwargs:
                    raise TypeError(f"{cls.__name__}() got both {old}= (deprecated) and {new}=")
                warn(f"{cls.__name__}({old}=...)", f"{new}=...")
                kwargs[new] = kwargs.pop(old)
        init(self, *args, **kwargs)

    cls.__init__ = __init__
    return cls


def module_getattr(module_name: str, moved: dict[str, tuple[str, str]]):
    """A module ``__getattr__`` that serves each deprecated ``name: (module, new_name)``
    from its new place, with a warning."""
    def __getattr__(name: str):
        if name not in moved:
            raise AttributeError(f"module {module_name!r} has no attribute {name!r}")
        where, new = moved[name]
        warn(f"{module_name}.{name}", f"{where}.{new}")
        return getattr(importlib.import_module(where), new)

    return __getattr__
