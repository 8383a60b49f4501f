"""The package's layering, read from the source: every import (also those inside functions)
points down the layers, no two modules import each other (directly or around a cycle),
nothing inside imports the package root, and no module takes another's private names."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "sedsabso_jax"
PACKAGE = "sedsabso_jax"

#: Layer of each top-level part (README, "Layout"): a module may import only from lower
#: layers or from its own part. Parts in one layer are independent of each other.
LAYERS = {
    "paper": 0, "_output": 0, "_deprecation": 0, "_version": 0, "_x64": 0,
    "dynamics": 1, "optim": 1,
    "measurements": 2, "excitation": 2,
    "identification": 3,
    "reproduce": 4,
    "compare": 5,
    "cli": 6, "__main__": 7,
    "": 8,  # the package root: re-exports the public names
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _imports(name: str):
    """(imported module, imported names, line) for every import in ``name``'s source."""
    tree = ast.parse(MODULES[name].read_text(), filename=str(MODULES[name]))
    here = name if _is_package(name) else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == PACKAGE:
                    yield alias.name, (), node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here.split(".")[: len(here.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != PACKAGE:
                continue
            names = [a.name for a in node.names]
            submodules = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
            for sub in submodules:  # from package import module
                yield sub, (), node.lineno
            rest = [n for n in names if f"{target}.{n}" not in MODULES]
            if rest:
                yield target, tuple(rest), node.lineno


def _part(name: str) -> str:
    return name.split(".")[1] if "." in name else ""


EDGES = [(src, dst, names, line) for src in MODULES for dst, names, line in _imports(src)]


def test_every_part_has_a_layer():
    assert {_part(m) for m in MODULES} <= set(LAYERS), "a new part needs a layer"


@pytest.mark.parametrize("src", sorted(MODULES))
def test_imports_point_down(src):
    bad = []
    for s, dst, _, line in EDGES:
        if s != src:
            continue
        if dst == PACKAGE:
            bad.append(f"line {line}: imports the package root")
            continue
        if _is_package(dst) and s.startswith(dst + "."):
            bad.append(f"line {line}: imports names from its own package's __init__ ({dst})")
            continue
        a, b = _part(s), _part(dst)
        if a != b and not LAYERS[b] < LAYERS[a]:
            bad.append(f"line {line}: {dst} (layer {LAYERS[b]}) from layer {LAYERS[a]}")
    assert not bad, f"{src}: " + "; ".join(bad)


def test_no_private_names_across_modules():
    bad = [f"{src}:{line} takes {n} from {dst}" for src, dst, names, line in EDGES
           for n in names if n.startswith("_") and not n.startswith("__") and dst != src]
    assert not bad, bad


def test_no_import_cycle():
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for src, dst, _, _ in EDGES:
        if dst in graph and not _is_package(dst):  # a package's __init__ only re-exports
            graph[src].add(dst)
    state: dict[str, int] = {}

    def visit(node, path):
        state[node] = 1
        for nxt in graph[node]:
            if state.get(nxt) == 1:
                raise AssertionError("import cycle: " + " -> ".join(path + [node, nxt]))
            if nxt not in state:
                visit(nxt, path + [node])
        state[node] = 2

    for m in graph:
        if m not in state:
            visit(m, [])


def test_the_checks_see_the_imports():
    """The graph is not empty by accident: known edges are found."""
    pairs = {(s, d) for s, d, _, _ in EDGES}
    assert ("sedsabso_jax.identification.identify", "sedsabso_jax.optim.linear") in pairs
    assert ("sedsabso_jax.dynamics.robots", "sedsabso_jax.paper") in pairs
    assert ("sedsabso_jax.cli", "sedsabso_jax.reproduce.experiment") in pairs  # in a function
