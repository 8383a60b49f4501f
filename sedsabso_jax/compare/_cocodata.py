"""COCO's data format: the files COCO's ``bbob`` observer writes (coco-experiment 2.8.2,
``code-experiments/src/logger_bbob.c`` and ``coco_observer.c``, data format
``bbob-new2``), written from what a run records, so that ``python -m cocopp`` reads them.

The observer sees every evaluation; a run of :func:`sedsabso_jax.minimise` records its
best value after each iteration (generation) and the cumulative evaluation counts are
known (:func:`sedsabso_jax.evaluation_counts`). The lines follow the observer's rules
with the iteration as the unit of time:

- ``.dat`` (targets): a line at evaluation 1, then whenever the best ``f - f_opt``
  improves past a new target ``10**(k/20)`` (``number_target_triggers`` 20,
  ``log_target_precision`` 1e-8: below it every value counts as 1e-8, and 0 as 1e-9) or
  a new multiple of 1e5 (``lin_target_precision``; below 1e-12 it counts as 0), and at
  the last evaluation;
- ``.tdat`` (budgets): a line at evaluation 1, then whenever the evaluations pass
  ``floor(10**(k/20))`` or ``dim * {1, 2, 5} * 10**k``, and at the last evaluation.

What an iteration-level record cannot give, and how it is written (also in each
``.info`` comment):

- a target reached inside an iteration is placed at the END of that iteration, its
  cumulative evaluation count: conservative by less than one population;
- the value of evaluation 1 is not kept: it is logged as 3e21, COCO's value for an
  infinite ``f`` (so no target is hit before the first iteration ends);
- ``measured fitness`` is the best value (the observer writes the evaluated point's
  value there; cocopp reads neither it nor ``x``), and the ``x`` columns are left out (as
  the observer does from 22 variables on).

Files of one algorithm (``FOLDER``): ``bbobexp_f{F}.info`` with one three-line entry per
dimension, and ``data_f{F}/bbobexp_f{F}_DIM{D}.dat`` / ``.tdat`` with one block per run.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from .._output import PathLike, write_text

#: COCO's logged value for an infinite (and here: unknown) f
LOGGED_INFINITY = 3e21
#: the version of COCO whose bbob observer the files follow
COCO_VERSION = "2.8.2"
TARGET_TRIGGERS = 20  # per decade
TARGET_PRECISION = 1e-8
LINEAR_PRECISION = 1e5
EVALUATION_TRIGGERS = 20  # per decade
BASE_EVALUATIONS = (1, 2, 5)
HEADER = ("% f evaluations | g evaluations | best noise-free fitness - Fopt ({:13.12e}) + "
          "sum g_i+ | measured fitness | best measured fitness or single-digit g-values | "
          "x1 | x2...\n")
#: the .info comment's account of the conversion (after the algorithm's description)
CONVERSION = ("written by sedsabso-jax from per-iteration best values: a target hit is "
              "placed at the end of the iteration (generation) that reaches it, "
              "conservative by less than one population; evaluation 1 is logged as 3e21 "
              "(its value is not kept); measured fitness = best fitness; no x columns")


def _round_up(number: float, precision: float) -> float:
    """``coco_double_round_up_with_precision``."""
    rounded_up = math.ceil(number / precision) * precision
    rounded = math.floor(number / precision + 0.5) * precision
    if abs(rounded - rounded_up) < precision or abs(number - rounded) >= 1e-12:
        return rounded_up
    return rounded


class _TargetTrigger:
    """``coco_observer_targets_trigger`` (logarithmic or linear targets) for values >= 0."""

    def __init__(self) -> None:
        self.exponent, self.linear = math.inf, math.inf

    def __call__(self, value: float) -> bool:
        verified = (TARGET_PRECISION / 10.0 if value == 0 else
                    TARGET_PRECISION if value < TARGET_PRECISION else value)
        exponent = math.ceil(math.log10(verified) * TARGET_TRIGGERS)
        log = exponent < self.exponent
        if log:
            self.exponent = exponent
        linear = _round_up(value, LINEAR_PRECISION)
        lin = linear < self.linear
        if lin:
            self.linear = linear
        return log or lin


class _EvaluationTrigger:
    """``coco_observer_evaluations_trigger``, advanced over a range of evaluations."""

    def __init__(self, dim: int) -> None:
        self.dim = dim
        self.value1, self.exponent1 = 1, 0
        self.value2, self.exponent2, self.index = dim * BASE_EVALUATIONS[0], 0, 0

    def _next1(self) -> None:
        while math.floor(10.0 ** (self.exponent1 / EVALUATION_TRIGGERS)) <= self.value1:
            self.exponent1 += 1
        self.value1 = math.floor(10.0 ** (self.exponent1 / EVALUATION_TRIGGERS))

    def _next2(self) -> None:
        if self.index < len(BASE_EVALUATIONS) - 1:
            self.index += 1
        else:
            self.index, self.exponent2 = 0, self.exponent2 + 1
        self.value2 = int(10.0 ** self.exponent2 * self.dim * BASE_EVALUATIONS[self.index])

    def up_to(self, evaluations: int) -> bool:
        """Whether an evaluation up to ``evaluations`` triggers (consuming them all)."""
        fired = False
        while self.value1 <= evaluations:
            self._next1()
            fired = True
        while self.value2 <= evaluations:
            self._next2()
            fired = True
        return fired


def logged(f: float, f_opt: float) -> float:
    """A best value as the observer keeps it: non-finite as 3e21, never below ``f_opt``."""
    return max(f if math.isfinite(f) else LOGGED_INFINITY, f_opt)


def run_lines(evaluations: Sequence[int] | np.ndarray, best: Sequence[float] | np.ndarray,
              f_opt: float, dim: int
              ) -> tuple[list[tuple[int, float]], list[tuple[int, float]]]:
    """``(dat, tdat)``: the ``(evaluations, best f)`` lines of one run's ``.dat`` and
    ``.tdat`` blocks, from its cumulative evaluation counts and best value after each
    iteration (see the module's docstring)."""
    if len(evaluations) != len(best) or not len(evaluations):
        raise ValueError(f"a run needs as many evaluation counts as best values (at least "
                         f"one), got {len(evaluations)} and {len(best)}")
    current = logged(LOGGED_INFINITY, f_opt)
    dat, tdat = [(1, current)], [(1, current)]
    targets, budgets = _TargetTrigger(), _EvaluationTrigger(dim)
    budgets.up_to(1)
    last = 1
    for n, f in zip(evaluations, best):
        n, f = int(n), logged(float(f), f_opt)
        if n <= last:
            raise ValueError(f"evaluation counts must increase from 2 on, got {n} after "
                             f"{last}")
        if f < current:
            current = f
            if targets(current - f_opt):
                dat.append((n, current))
        if budgets.up_to(n):
            tdat.append((n, current))
        last = n
    for lines in (dat, tdat):
        if lines[-1][0] != last:
            lines.append((last, current))
    return dat, tdat


def _line(evaluations: int, f: float, f_opt: float) -> str:
    return f"{evaluations} 0 {f - f_opt:+10.9e} {f:+10.9e} {f:+10.9e}\n"


def block(lines: Iterable[Sequence[float]], f_opt: float) -> str:
    """One run's block of a ``.dat`` or ``.tdat`` file: the header, then its lines."""
    return HEADER.format(f_opt) + "".join(_line(int(n), float(f), f_opt) for n, f in lines)


def printed_precision(f: float, f_opt: float) -> float:
    """``f - f_opt`` as a ``.dat`` line states it (10 significant digits): the number
    cocopp reads."""
    return float(f"{f - f_opt:+10.9e}")


@dataclass(frozen=True)
class Entry:
    """The runs of one algorithm on one (function, dimension): what one ``.info`` entry
    and its ``.dat`` / ``.tdat`` files hold."""

    function: int
    dim: int
    comment: str  # the algorithm and its settings, one line
    instances: tuple[int, ...]  # COCO's instance number of each run
    f_opt: tuple[float, ...]  # per run
    dat: tuple  # per run: ((evaluations, best f), ...)
    tdat: tuple

    @property
    def stem(self) -> str:
        return f"data_f{self.function}/bbobexp_f{self.function}_DIM{self.dim}"

    def info(self, algorithm: str) -> str:
        """The entry's three lines of ``bbobexp_f{F}.info`` (no final newline)."""
        runs = ", ".join(f"{i}:{int(dat[-1][0])}|{dat[-1][1] - f:.1e}"
                         for i, f, dat in zip(self.instances, self.f_opt, self.dat))
        return (f"suite = 'bbob', funcId = {self.function}, DIM = {self.dim}, Precision = "
                f"{TARGET_PRECISION:.3e}, algId = '{algorithm}', coco_version = "
                f"'{COCO_VERSION}', logger = 'bbob', data_format = 'bbob-new2'\n"
                f"% {self.comment}; {CONVERSION}\n{self.stem}.dat, {runs}")

    def data(self, which: str) -> str:
        """The text of the ``.dat`` (``which="dat"``) or ``.tdat`` file."""
        return "".join(block(lines, f) for lines, f in zip(getattr(self, which), self.f_opt))


def folder_files(algorithm: str, entries: Iterable[Entry]) -> dict[str, str]:
    """Relative path -> text of every file of one algorithm's folder."""
    if not algorithm or any(c in algorithm for c in " '\",=/\\%"):
        raise ValueError(f"COCO's algId must be one word without quotes, commas or "
                         f"slashes, got {algorithm!r}")
    files: dict[str, str] = {}
    by_function: dict[int, list[Entry]] = {}
    for e in sorted(entries, key=lambda e: (e.function, e.dim)):
        by_function.setdefault(e.function, []).append(e)
        for which in ("dat", "tdat"):
            files[f"{e.stem}.{which}"] = e.data(which)
    for function, es in by_function.items():
        files[f"bbobexp_f{function}.info"] = "\n".join(e.info(algorithm) for e in es)
    return files


def write_folder(path: PathLike, algorithm: str, entries: Iterable[Entry]) -> list[str]:
    """Write one algorithm's COCO folder at ``path``, replacing what was there: the files
    go to a new folder beside it, which then takes its place (a reader sees the old
    folder or the new one, never a mix). Returns the files' paths."""
    files = folder_files(algorithm, entries)
    path = os.path.abspath(path)
    parent = os.path.dirname(path)
    os.makedirs(parent, exist_ok=True)
    new = tempfile.mkdtemp(dir=parent, prefix=f".{os.path.basename(path)}.")
    try:
        for name, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(new, name)), exist_ok=True)
            write_text(os.path.join(new, name), text)
        os.chmod(new, 0o755)
        old = None
        if os.path.exists(path):
            old = tempfile.mkdtemp(dir=parent, prefix=f".{os.path.basename(path)}.old.")
            os.replace(path, os.path.join(old, "x"))
        os.replace(new, path)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(new, ignore_errors=True)
        raise
    return sorted(os.path.join(path, name) for name in files)

