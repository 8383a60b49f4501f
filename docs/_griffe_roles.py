"""Griffe extension for the documentation site (mkdocs.yml, mkdocstrings' python handler):
the package's docstrings are Google-style with reStructuredText roles, which mkdocstrings
does not read. Each ``:class:`~x.Y``` (also ``:func:``, ``:meth:``, ``:attr:``,
``:data:``, ``:mod:``) becomes

- a link, ``[`Y`][sedsabso_jax.Y]``, when the target is a public object (an entry of the
  ``__all__`` of ``sedsabso_jax`` or of one of its namespaces, or a member of a public
  class), the public path found by its name (``~._model.TorqueModel`` links to
  ``sedsabso_jax.TorqueModel``);
- inline code otherwise (private helpers, names that are public in two namespaces).

As in Sphinx, ``~`` shows the last component only and functions and methods get ``()``.
An attribute documented by ``#:`` comment lines right above it (Sphinx's convention) gets
them as its docstring. Only the rendered site changes; the package's source is left as it
is.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(class|func|meth|attr|data|mod|obj|exc):`(~?)([^`]+)`")
PACKAGE = "sedsabso_jax"


class SphinxRoles(griffe.Extension):
    """Rewrite the roles of every docstring in the package once it is loaded."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        if pkg.name != PACKAGE:
            return
        public = _public_paths(pkg)
        for obj in _walk(pkg):
            if obj.is_attribute and obj.docstring is None:
                _comment_docstring(obj)
            if obj.docstring is not None:
                obj.docstring.value = ROLE.sub(
                    lambda m: _render(m, obj, pkg, public), obj.docstring.value)


def _comment_docstring(obj: griffe.Object) -> None:
    """Sphinx's ``#:`` comments right above an attribute become its docstring."""
    try:
        lines = obj.lines_collection[obj.filepath]  # type: ignore[index]
    except (KeyError, TypeError, AttributeError):
        return
    i = (obj.lineno or 0) - 2  # the line above, 0-based
    comment: list[str] = []
    while i >= 0 and lines[i].lstrip().startswith("#:"):
        comment.insert(0, lines[i].lstrip()[2:].removeprefix(" "))
        i -= 1
    if comment:
        obj.docstring = griffe.Docstring("\n".join(comment), lineno=i + 2, parent=obj)


def _walk(obj: griffe.Object):
    yield obj
    for member in obj.members.values():
        if not member.is_alias:
            yield from _walk(member)  # type: ignore[arg-type]


def _public_paths(pkg: griffe.Module) -> dict[str, list[str]]:
    """name -> the public paths it has (``sedsabso_jax.X`` or ``sedsabso_jax.ns.X``)."""
    names: dict[str, list[str]] = {}
    modules = [pkg] + [m for m in pkg.modules.values() if not m.name.startswith("_")]
    for module in modules:
        for name in module.exports or ():
            names.setdefault(str(name), []).append(f"{module.path}.{name}")
    for name, paths in names.items():  # a submodule re-exported by the root: one place
        names[name] = sorted(set(paths), key=len)
    return names


def _target(pkg: griffe.Module, path: str):
    try:
        obj = pkg[path.removeprefix(PACKAGE + ".")] if path != PACKAGE else pkg
        return obj.final_target if obj.is_alias else obj
    except Exception:  # noqa: BLE001  (unresolvable: rendered as code)
        return None


def _is_module(pkg: griffe.Module, path: str) -> bool:
    target = _target(pkg, path)
    return target is not None and target.is_module


def _link(parts: list[str], obj: griffe.Object, pkg: griffe.Module,
          public: dict[str, list[str]]) -> str | None:
    """The public path the role's target renders at, or None."""
    full = ".".join(parts)
    everything = {p for paths in public.values() for p in paths}
    if full in everything or full == PACKAGE:
        return full
    # the first public name in the target (past namespaces), then at most one member
    # of a public class
    for i, part in enumerate(parts):
        paths = public.get(part)
        if paths is None:
            continue
        if i + 1 < len(parts) and all(_is_module(pkg, p) for p in paths):
            continue  # a namespace on the way: sedsabso_jax.measurements._transmission.X
        if len(paths) != 1 and not (i > 0 and ".".join(parts[:i + 1]) in paths):
            return None  # public in two namespaces (Settings): ambiguous
        base = ".".join(parts[:i + 1]) if ".".join(parts[:i + 1]) in paths else paths[0]
        rest = parts[i + 1:]
        if not rest:
            return base
        if len(rest) == 1 and not rest[0].startswith("_"):
            target = _target(pkg, base)
            if target is not None and target.is_class and rest[0] in target.members:
                return f"{base}.{rest[0]}"
        return None
    # a method or attribute of the class the docstring belongs to: ``:meth:`step```
    if len(parts) == 1 and not parts[0].startswith("_"):
        owner = obj if obj.is_class else obj.parent
        if owner is not None and owner.is_class and parts[0] in owner.members:
            for paths in public.values():
                for p in paths:
                    target = _target(pkg, p)
                    if target is not None and target.path == owner.path:
                        return f"{p}.{parts[0]}"
    return None


def _render(match: re.Match, obj: griffe.Object, pkg: griffe.Module,
            public: dict[str, list[str]]) -> str:
    role, tilde, target = match.groups()
    target = target.strip()
    parts = [p for p in target.lstrip(".").split(".") if p]
    shown = parts[-1] if tilde else target.lstrip(".")
    if role in ("func", "meth"):
        shown += "()"
    path = _link(parts, obj, pkg, public)
    return f"[`{shown}`][{path}]" if path else f"`{shown}`"
