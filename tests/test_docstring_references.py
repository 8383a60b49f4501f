"""Every cross-reference in the package's docstrings (``:class:`~._model.TorqueModel```,
``:func:``, ``:meth:``, ``:attr:``, ``:data:``, ``:mod:``) names an object that exists:
a module moved or a name renamed leaves no stale reference behind (the documentation
site renders an unresolved one as plain code, silently)."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "sedsabso_jax"
ROLE = re.compile(r":(class|func|meth|attr|data|mod|obj|exc):`~?([^`]+)`")


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _docstrings(tree: ast.Module):
    """(docstring, enclosing class name or None) of the module, its classes and
    functions (a method's and a nested function's with their class)."""
    doc = ast.get_docstring(tree, clean=False)
    if doc:
        yield doc, None

    def visit(node: ast.AST, cls: str | None):
        for item in ast.iter_child_nodes(node):
            if isinstance(item, ast.ClassDef):
                doc = ast.get_docstring(item, clean=False)
                if doc:
                    yield doc, item.name
                yield from visit(item, item.name)
            elif isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                doc = ast.get_docstring(item, clean=False)
                if doc:
                    yield doc, cls
                yield from visit(item, cls)

    yield from visit(tree, None)


def _member(obj: object, attr: str) -> object:
    """``obj.attr``, or for a class a field it declares (a dataclass's or equinox's)."""
    if hasattr(obj, attr):
        return getattr(obj, attr)
    if isinstance(obj, type) and (attr in getattr(obj, "__dataclass_fields__", {})
                                  or any(attr in getattr(c, "__annotations__", {})
                                         for c in obj.__mro__)):
        return object()
    raise AttributeError(attr)


def _resolve(target: str, module: str, is_package: bool, cls: str | None) -> bool:
    """Whether ``target`` names an object, read as Sphinx reads it from ``module``."""
    target = re.sub(r"\s+", "", target).rstrip("()")
    if target.startswith("."):
        dots = len(target) - len(target.lstrip("."))
        base = module.split(".") if is_package else module.split(".")[:-1]
        base = base[:len(base) - dots + 1]
        target = ".".join(base) + "." + target.lstrip(".")
    candidates = [target] if "." in target and target.startswith("sedsabso_jax") else [
        f"{module}.{target}", *([f"{module}.{cls}.{target}"] if cls else []), target]
    for name in candidates:
        parts = name.split(".")
        for i in range(len(parts), 0, -1):
            try:
                obj = importlib.import_module(".".join(parts[:i]))
            except ImportError:
                continue
            try:
                for attr in parts[i:]:
                    obj = _member(obj, attr)
            except AttributeError:
                break
            return True
    return False


MODULES = sorted(ROOT.rglob("*.py"))


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_docstring_references_resolve(path):
    module = _module_name(path)
    tree = ast.parse(path.read_text(encoding="utf-8"))
    stale = sorted({m.group(0) for doc, cls in _docstrings(tree)
                    for m in ROLE.finditer(doc)
                    if not _resolve(m.group(2), module, path.name == "__init__.py", cls)})
    assert not stale, f"{module}: references to nothing: {stale}"
