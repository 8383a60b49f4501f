"""COCO's ``bbob`` suite as ``sedsabso-jax compare`` runs it: the 24 noiseless functions,
COCO's dimensions, and COCO's numbered instances.

Instances: by default COCO's current ones, ``1-5,101-110`` (``cocoex.Suite("bbob",
"year: 2025", "")``, the BBOB workshops' set since 2023); cocopp knows each year's set
(``cocopp.genericsettings.instancesOfInterest``) and warns on others, so the default data
go beside archived algorithms without a warning. cocoex without a year gives the 2018 set,
``1-5,71-80``, which cocopp also accepts. One run per instance, as COCO does since 2010;
an instance named k times gets k runs (``1-5,1-5,1-5``: the 2009 set).

Dimensions: COCO's, 2, 3, 5, 10, 20 and 40 (cocopp's figures and tables show these).

The functions are COCO's in JAX (:mod:`._coco`: cocoex's values to rounding, COCO's
``f_opt`` exactly).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

import jax
import numpy as np

from ._coco import MAX_INSTANCE, CocoArgs, coco_args, coco_optimum, coco_value

#: COCO's names of f1-f24 (cocopp's ``bbob-benchmarkshortinfos.txt``), short forms
FUNCTIONS = ("sphere", "ellipsoid", "rastrigin", "bueche-rastrigin", "linear-slope",
             "attractive-sector", "step-ellipsoid", "rosenbrock", "rosenbrock-rotated",
             "ellipsoid-rotated", "discus", "bent-cigar", "sharp-ridge", "different-powers",
             "rastrigin-rotated", "weierstrass", "schaffer-f7", "schaffer-f7-cond-1000",
             "griewank-rosenbrock", "schwefel", "gallagher-101", "gallagher-21", "katsuura",
             "lunacek")
DIMENSIONS = (2, 3, 5, 10, 20, 40)
DEFAULT_INSTANCES = (1, 2, 3, 4, 5, *range(101, 111))
BOX = 5.0


def parse_numbers(text: str | Iterable[int], what: str) -> tuple[int, ...]:
    """``"1-5,101-110"`` (or integers) -> the numbers, in order, ranges expanded."""
    if not isinstance(text, str):
        return tuple(int(v) for v in text)
    out: list[int] = []
    for part in text.split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", part)
        if not m or (m.group(2) and int(m.group(2)) < int(m.group(1))):
            raise ValueError(f"--{what}: expected comma-separated numbers and ranges, e.g. "
                             f"1-5,101-110, got {text!r}")
        out += range(int(m.group(1)), int(m.group(2) or m.group(1)) + 1)
    return tuple(out)


def ranges(numbers: Iterable[int], sep: str = ",") -> str:
    """Numbers as ranges, :func:`parse_numbers`' input: ``(1, 2, 3, 101)`` -> ``"1-3,101"``."""
    numbers, parts, k = list(numbers), [], 0
    while k < len(numbers):
        j = k
        while j + 1 < len(numbers) and numbers[j + 1] == numbers[j] + 1:
            j += 1
        parts.append(f"{numbers[k]}" if j == k else f"{numbers[k]}-{numbers[j]}")
        k = j + 1
    return sep.join(parts)


def check(functions: Iterable[int], dimensions: Iterable[int],
          instances: Iterable[int]) -> None:
    """ValueError naming what is unknown and what was expected."""
    def bad(v, ok) -> bool:
        return isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not ok(v)

    functions, instances = tuple(functions), tuple(instances)
    for f in functions:
        if bad(f, lambda v: 1 <= v <= len(FUNCTIONS)):
            raise ValueError(f"unknown BBOB function {f!r}; expected 1 to {len(FUNCTIONS)}")
    for d in dimensions:
        if bad(d, lambda v: v in DIMENSIONS):
            raise ValueError(f"unknown BBOB dimension {d!r}; expected one of COCO's "
                             f"{', '.join(map(str, DIMENSIONS))}")
    for i in instances:
        if bad(i, lambda v: 1 <= v <= MAX_INSTANCE):
            raise ValueError(f"unknown BBOB instance {i!r}; expected COCO's instance "
                             f"numbers, 1 to {MAX_INSTANCE}")
    if not functions or not instances:
        raise ValueError("BBOB needs at least one function and one instance")
    counts = {i: instances.count(i) for i in instances}
    if len(set(counts.values())) > 1:
        raise ValueError(f"every BBOB instance must be named equally often (cocopp expects "
                         f"the same number of runs on each), got {instances}")


def problem_name(function: int, dim: int) -> str:
    return f"bbob-f{function:02d}-{FUNCTIONS[function - 1]}-d{dim:02d}"


def parse_name(name: str) -> tuple[int, int] | None:
    """``(function, dimension)`` of a BBOB problem's name, None for another name."""
    m = re.fullmatch(r"bbob-f(\d\d)-[a-z0-9-]+-d(\d\d)", name)
    return (int(m.group(1)), int(m.group(2))) if m else None


def value(x: jax.Array, args: CocoArgs) -> jax.Array:
    """BBOB's fitness at one point: :func:`._coco.coco_value` (the function and instance
    in ``args``, :func:`instance_args`)."""
    return coco_value(x, args)


def instance_args(function: int, instance: int, dim: int) -> CocoArgs:
    """The runtime arguments of :func:`value` for one instance (the same shapes for every
    function and instance of a dimension: one compiled fitness serves them all)."""
    return coco_args(function, instance, dim)


def f_opt(function: int, instance: int, dim: int) -> float:
    """COCO's optimal value of an instance."""
    return coco_optimum(function, instance, dim)[0]
