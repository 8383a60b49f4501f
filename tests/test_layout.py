"""The package's layering and its public API, read from the source: every import (also
those inside functions) points down the layers, no two modules import each other (directly
or around a cycle), nothing inside imports the package root, and no module takes another's
private names. Public and private apart: every implementation module is private
(``_name.py``), the public names are the ``__all__`` of the root and of the public
namespaces, each name in one place, and the benchmarks and notebooks use nothing else."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "sedsabso_jax"
PACKAGE = "sedsabso_jax"

#: Layer of each top-level part (docs/explanation/conventions.md, "Layout"): a module may
#: import only from lower layers or from its own part. Parts in one layer are independent
#: of each other.
LAYERS = {
    "paper": 0, "_output": 0, "_deprecation": 0, "_version": 0, "_x64": 0, "_lazy": 0,
    "_terms": 0,
    "dynamics": 1, "optim": 1,
    "measurements": 2, "excitation": 2, "robots": 2, "baselines": 2,
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
    assert ("sedsabso_jax.identification._fit._identify", "sedsabso_jax.optim._linear") in pairs
    assert ("sedsabso_jax.dynamics._robots", "sedsabso_jax.paper") in pairs
    # an import inside a function
    assert ("sedsabso_jax.cli._main", "sedsabso_jax.reproduce._experiment") in pairs


# ------------------------------------------------------------------------ public API
import importlib  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402

#: The public namespaces (each with ``__all__``); the package root first.
NAMESPACES = ("sedsabso_jax", "sedsabso_jax.robots", "sedsabso_jax.baselines",
              "sedsabso_jax.paper", "sedsabso_jax.dynamics", "sedsabso_jax.optim",
              "sedsabso_jax.measurements", "sedsabso_jax.excitation",
              "sedsabso_jax.identification", "sedsabso_jax.compare", "sedsabso_jax.reproduce",
              "sedsabso_jax.cli")
#: 0.2's documented module paths, kept as deprecation shims through 0.3.x.
SHIMS = {"sedsabso_jax.identification.validation", "sedsabso_jax.measurements.transmission",
         "sedsabso_jax.reproduce.experiment", "sedsabso_jax.dynamics.robots"}


def test_implementation_modules_are_private():
    public = {m for m in MODULES if not _is_package(m)
              and not m.rpartition(".")[2].startswith("_")} - SHIMS
    assert public == {f"sedsabso_jax.{n.rpartition('.')[2]}" for n in NAMESPACES[1:4]}, public


@pytest.mark.parametrize("name", NAMESPACES)
def test_namespace_exports_exactly_its_all(name):
    module = importlib.import_module(name)
    names = module.__all__
    assert len(names) == len(set(names)), f"{name}: a name twice in __all__"
    for n in names:
        assert hasattr(module, n), f"{name}.{n} in __all__ but missing"
    submodules = {m.rpartition(".")[2] for m in MODULES if m.startswith(name + ".")}
    extra = {n for n in vars(module) if not n.startswith("_") and n != "annotations"
             and n not in names and n not in submodules}
    assert not extra, f"{name}: public attributes outside __all__: {sorted(extra)}"


def test_one_import_path_per_public_name():
    """No function, class or module is exported by two namespaces (two namespaces may
    each have their own ``Settings``, but not the same one)."""
    import inspect

    namespaces = set(NAMESPACES)
    seen: dict[int, str] = {}
    for name in NAMESPACES:
        module = importlib.import_module(name)
        for n in module.__all__:
            obj = getattr(module, n)
            if f"{name}.{n}" in namespaces or n.startswith("__") or not (
                    inspect.isclass(obj) or inspect.isroutine(obj)):
                continue
            assert id(obj) not in seen, f"{n} is public as {seen[id(obj)]} and {name}.{n}"
            seen[id(obj)] = f"{name}.{n}"
    assert {"sedsabso_jax.minimise", "sedsabso_jax.identify", "sedsabso_jax.SEDSABSO",
            "sedsabso_jax.robots.rs010n"} <= set(seen.values())


REPO = ROOT.parent


def _private_uses(source: str) -> list[str]:
    """``sedsabso_jax`` imports or attribute paths through a private name."""
    found = re.findall(r"(?:sedsabso_jax|\bsj)(?:\.\w+)*\._(?!_)\w+", source)
    for m in re.finditer(r"from (sedsabso_jax[\w.]*) import \(?([^)\n]*)", source):
        found += [f"{m.group(1)}.{n.split()[0]}" for n in m.group(2).split(",")
                  if n.strip().startswith("_")]
    return found


@pytest.mark.parametrize("path", sorted((REPO / "benchmarks").glob("*.py"))
                         + sorted((REPO / "notebooks").glob("*.ipynb")), ids=lambda p: p.name)
def test_benchmarks_and_notebooks_use_the_public_api(path):
    text = path.read_text()
    if path.suffix == ".ipynb":
        text = "\n".join("".join(c["source"]) for c in json.loads(text)["cells"]
                         if c["cell_type"] == "code")
    assert not _private_uses(text), _private_uses(text)


# ------------------------------------------------------------------- sizes of the parts
#: The largest module (lines) and the most parameters a function takes; the command
#: line's parser functions (``add_parser``) are exempt, their flags being their job.
MAX_LINES, MAX_PARAMETERS = 400, 10


def _parameters(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    a = node.args
    count = (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None)
             + (a.kwarg is not None))
    return count - bool(a.args and a.args[0].arg in ("self", "cls"))


def test_modules_and_functions_stay_small():
    long, wide = [], []
    for path in sorted(ROOT.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if len(text.splitlines()) > MAX_LINES:
            long.append(f"{path.relative_to(ROOT)}: {len(text.splitlines())} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) \
                    and node.name != "add_parser" and _parameters(node) > MAX_PARAMETERS:
                wide.append(f"{path.relative_to(ROOT)}: {node.name}({_parameters(node)})")
    assert not long, f"modules over {MAX_LINES} lines: {long}"
    assert not wide, f"functions over {MAX_PARAMETERS} parameters: {wide}"


def test_every_planted_bug_still_applies():
    """Each of tools/planted_bugs.py's bugs names text that occurs exactly once in its
    module and test files that exist: a refactor that moves the text would otherwise turn
    the bug into a silent ``NOT APPLIED`` (two had, after issue 42's merges)."""
    import importlib.util

    path = ROOT.parent / "tools" / "planted_bugs.py"
    spec = importlib.util.spec_from_file_location("planted_bugs", path)
    planted = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(planted)
    stale = [(number, module, source.count(text))
             for number, (module, text, *_, tests, _) in enumerate(planted.BUGS, 1)
             if (source := (ROOT / module).read_text(encoding="utf-8")).count(text) != 1]
    assert not stale, f"(bug, module, times its text occurs): {stale}"
    tests = {t for *_, files, _ in planted.BUGS for t in files}
    assert all((ROOT.parent / t).is_file() for t in tests), tests
