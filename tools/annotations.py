"""Share of annotated parameters (and returns) in a package, from the source: every
function and method whose name does not start with ``_`` (``__init__`` included), self
and cls not counted. ``python tools/annotations.py [PATH ...]`` (default: sedsabso_jax);
``--list`` prints the unannotated ones."""

from __future__ import annotations

import ast
import sys
from pathlib import Path


def functions(tree):
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node


def count(path: Path, missing: list[str]) -> tuple[int, int, int, int]:
    params = annotated = returns = returns_annotated = 0
    for file in sorted(path.rglob("*.py")) if path.is_dir() else [path]:
        for fn in functions(ast.parse(file.read_text())):
            if fn.name.startswith("_") and fn.name != "__init__":
                continue
            args = fn.args.posonlyargs + fn.args.args + fn.args.kwonlyargs
            args += [a for a in (fn.args.vararg, fn.args.kwarg) if a is not None]
            for a in args:
                if a.arg in ("self", "cls"):
                    continue
                params += 1
                if a.annotation is not None:
                    annotated += 1
                else:
                    missing.append(f"{file}:{fn.lineno} {fn.name}({a.arg})")
            if fn.name != "__init__":
                returns += 1
                returns_annotated += fn.returns is not None
    return params, annotated, returns, returns_annotated


def main(argv: list[str]) -> None:
    show = "--list" in argv
    paths = [Path(a) for a in argv if a != "--list"] or [Path("sedsabso_jax")]
    for path in paths:
        missing: list[str] = []
        p, a, r, ra = count(path, missing)
        print(f"{path}: {a}/{p} parameters annotated ({100 * a / max(p, 1):.0f} %), "
              f"{ra}/{r} returns ({100 * ra / max(r, 1):.0f} %)")
        if show:
            print("\n".join(missing))


if __name__ == "__main__":
    main(sys.argv[1:])
