"""Deprecated names and call forms: each keeps working until the release it names, with a
DeprecationWarning that points at the caller's line and names the replacement ("... will
be removed after sedsabso-jax X.Y; use ..."); and the caller's line for other warnings."""

from __future__ import annotations

import functools
import importlib
import sys
import warnings
from collections.abc import Callable
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


#: The release after which the deprecations of 0.3 (the last ones left, in
#: :mod:`sedsabso_jax.optim`) go: the default of ``removed_after`` until they are gone.
REMOVED_AFTER_03 = "0.3"


def warn(old: str, new: str, *, removed_after: str = REMOVED_AFTER_03) -> None:
    """Warn that ``old`` is deprecated in favour of ``new`` and goes after release
    ``removed_after`` (e.g. ``"0.5"``)."""
    warnings.warn(f"{old} is deprecated and will be removed after sedsabso-jax "
                  f"{removed_after}; use {new}", DeprecationWarning,
                  stacklevel=caller_stacklevel())


def renamed_arguments(cls: type[_T], renamed: dict[str, str], *,
                      removed_after: str = REMOVED_AFTER_03) -> type[_T]:
    """Let ``cls(old=...)`` stand for ``cls(new=...)`` for each ``old: new``, with a
    warning that the old name goes after release ``removed_after``. Passing both is a
    TypeError."""
    init = cls.__init__

    @functools.wraps(init)
    def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
        for old, new in renamed.items():
            if old in kwargs:
                if new in kwargs:
                    raise TypeError(f"{cls.__name__}() got both {old}= (deprecated) and {new}=")
                warn(f"{cls.__name__}({old}=...)", f"{new}=...",
                     removed_after=removed_after)
                kwargs[new] = kwargs.pop(old)
        init(self, *args, **kwargs)

    cls.__init__ = __init__  # type: ignore[method-assign]
    return cls


def resolve(path: str) -> Any:
    """The object at the dotted ``path`` (``"sedsabso_jax.robots.rs010n"``): the longest
    importable module prefix, then attributes."""
    parts = path.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(path)


def moved(module_name: str, names: dict[str, str | tuple[str, str]],
          module: str | None = None) -> Callable[[str], Any]:
    """A module ``__getattr__`` for names that moved: each ``old: "new.dotted.path"`` is
    served from its new place with a warning naming it (``old: (path, advice)``: the
    warning gives the advice instead). With ``module`` (a deprecated module path kept as
    a shim), any other name is looked up there, with a warning. (Used by
    :mod:`sedsabso_jax.optim` for its 0.3 names only.)"""
    def __getattr__(name: str) -> Any:
        if name in names:
            where = names[name]
            path, advice = (where, where) if isinstance(where, str) else where
            warn(f"{module_name}.{name}", advice)
            return resolve(path)
        if module is not None and not name.startswith("__"):
            target = importlib.import_module(module)
            if hasattr(target, name):
                warn(f"the module path {module_name}", f"the public names of sedsabso_jax "
                     f"(the documentation's API pages); {name} is {module}.{name} now")
                return getattr(target, name)
        raise AttributeError(f"module {module_name!r} has no attribute {name!r}")

    return __getattr__
