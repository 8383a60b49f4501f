"""Names of a package imported when first used (PEP 562), so that ``import sedsabso_jax``
imports neither JAX nor SciPy and the command's ``--help`` answers at once.

The package's ``__init__`` states what it re-exports as ordinary imports under
``if TYPE_CHECKING:``, which type checkers and the documentation (griffe) read as any
import, and :func:`attach` reads the same lines (not run at run time) into the module's
``__getattr__`` and ``__dir__``: a name's module is imported on its first use, as SPEC 1's
``lazy_loader.attach_stub`` does from a stub file. ``sj.NAME``, ``from sedsabso_jax
import NAME`` and ``dir(sj)`` work as with the imports run."""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable
from typing import Any


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports(source: str) -> dict[str, tuple[str, str | None]]:
    """``{name: (module, attribute)}`` of the imports under the top-level ``if
    TYPE_CHECKING:`` of ``source`` (a module's text): ``from .a import B as B`` is
    ``"B": (".a", "B")``, ``from . import a as a`` is ``"a": (".a", None)``."""
    found: dict[str, tuple[str, str | None]] = {}
    for node in ast.parse(source).body:
        if not (isinstance(node, ast.If) and _is_type_checking(node.test)):
            continue
        for line in node.body:
            if not isinstance(line, ast.ImportFrom):
                raise ImportError(f"line {line.lineno}: only 'from ... import ...' lines go "
                                  f"under 'if TYPE_CHECKING:' of a lazy namespace")
            where = "." * line.level + (line.module or "")
            for alias in line.names:
                name = alias.asname or alias.name
                found[name] = ((where + alias.name, None) if line.module is None
                               else (where, alias.name))
    return found


def attach(package: str) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of the module named ``package``, from the
    imports under its ``if TYPE_CHECKING:`` (:func:`imports`); every name of its
    ``__all__`` must be there or defined in it."""
    module = sys.modules[package]
    loader: Any = module.__spec__.loader if module.__spec__ is not None else None
    source = loader.get_source(package) if loader is not None else None
    if source is None:
        raise ImportError(f"{package}: its source is needed to import its names lazily")
    table = imports(source)

    def __getattr__(name: str) -> Any:
        try:
            where, attribute = table[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = importlib.import_module(where, package)
        if attribute is not None:
            value = getattr(value, attribute)
        setattr(module, name, value)  # the next use finds it without this function
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(module)) | set(table))

    return __getattr__, __dir__
