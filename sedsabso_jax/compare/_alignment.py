"""Run lengths read off COCO ``.dat`` lines the way cocopp reads them, so that the
package's average runtimes and runtime ECDFs are cocopp's on the same data.

cocopp (2.9.1, ``readalign.align_data`` with ``HMultiReader``, then
``DataSet._cut_data`` and ``DataSet.detEvals``) does not look up each target in each run
on its own: it aligns the runs of one (function, dimension) on the grid ``10**(i/5)``,
going down from the worst first value, and keeps a row ``(value, evaluations of each
run)`` per step; a target gets the row with the largest value at or below it. The
alignment counts a value within 1e-9 (relative) above a grid value as reaching it
(``is_close``) and lowers the worst value of a row by 1e-12 (absolute) before it picks
the next grid value; so a run whose ``f - f_opt`` lies within 1e-12 above a target may
count as reaching it, depending on the other runs. This module repeats those steps on the
lines as written (:func:`._cocodata.printed_precision`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: values per decade of cocopp's alignment grid (``testbed.number_of_points``)
POINTS = 5
#: cocopp's final target (``DataSet.precision``, the .info files' ``Precision``)
PRECISION = 1e-8


def _close(a: float, b: float) -> bool:
    """cocopp's ``readalign.is_close``."""
    return abs(a - b) <= 1e-09 * max(abs(a), abs(b))


class _Run:
    """One run's lines ``(evaluations, f - f_opt)``, read as ``SingleReader`` reads."""

    def __init__(self, lines: np.ndarray):
        self.lines, self.k = lines, 0  # k: index of the next line
        self.current: np.ndarray | None = None
        self.nearly = self.finished = False

    @property
    def next_value(self) -> float:
        return float(self.lines[min(self.k, len(self.lines) - 1), 1])

    def advance(self) -> None:
        if self.finished:
            return
        if not self.nearly:
            self.current = self.lines[self.k].copy()
            self.k += 1
            self.nearly = self.k >= len(self.lines)
        else:
            self.finished = True
            assert self.current is not None
            self.current[0] = np.nan


class _Aligner:
    """``HMultiReader`` over the runs of one (function, dimension)."""

    def __init__(self, runs: list[_Run]):
        self.runs = runs
        self.index, self.old, self.negative = math.inf, 0.0, False

    def value(self) -> float:
        return (-1.0 if self.negative else 1.0) * float(np.power(10, self.index / POINTS))

    def initial(self) -> float:
        for r in self.runs:
            r.advance()
        worst = max(float(r.current[1]) for r in self.runs)  # type: ignore[index]
        self.index = float(np.ceil(np.log10(worst if worst > 0 else 1e-19) * POINTS))
        return self.value()

    def done(self) -> bool:
        value = self.value()
        for r in self.runs:
            while r.next_value > value and not r.finished:
                r.advance()
        return not any(r.next_value <= value for r in self.runs)

    def step(self) -> float:
        if self.index == -math.inf:
            self.index, self.negative = self.old, True
        elif self.negative:
            self.index += 1
        else:
            self.index -= 1
        return self.value()

    def align(self, value: float) -> list[float]:
        reached = []
        for r in self.runs:
            while not r.finished:
                f = float(r.current[1])  # type: ignore[index]
                if f <= value or _close(f, value):
                    break
                r.advance()
            f = float(r.current[1])  # type: ignore[index]
            if f <= value or _close(f, value):
                reached.append(f)
        if not reached:
            raise ValueError(f"value {value:g} is not reached")
        worst = max(reached)
        if worst <= 0.0:
            if value > 0.0:
                self.old, self.index, value = self.index, -math.inf, 0.0
            else:
                self.index = max(self.index, float(np.floor(np.log10(-worst + 1e-12) * POINTS)))
                value = self.value()
        else:
            worst = worst - 1e-12 if worst >= 2e-12 else worst / 2
            self.index = min(self.index, float(np.ceil(np.log10(worst) * POINTS)))
            value = self.value()
        return [value, *(float(r.current[0]) for r in self.runs)]  # type: ignore[index]


def aligned_rows(runs: Sequence[np.ndarray]) -> np.ndarray:
    """cocopp's ``DataSet.evals`` of these runs: rows ``(value, evaluations of each
    run)``, cut below the final target as ``DataSet._cut_data`` cuts them. ``runs``: per
    run an array of lines ``(evaluations, f - f_opt as printed)``."""
    aligner = _Aligner([_Run(np.asarray(r, dtype=float)) for r in runs])
    rows = []
    value = aligner.initial()
    if aligner.done():
        rows.append(aligner.align(value))
    while not aligner.done():
        rows.append(aligner.align(value))
        value = aligner.step()
    out = np.array(rows)
    i = len(out)
    while i > 1 and out[i - 1, 0] <= PRECISION:
        i -= 1
    out = out[:i + 1]
    if out[-1, 0] < PRECISION:
        out[-1, 0] = max(PRECISION / 1.001, out[-1, 0])
    return out


def run_lengths(runs: Sequence[np.ndarray], targets: Sequence[float] | np.ndarray
                ) -> np.ndarray:
    """``(runs, targets)``: the evaluations at which each run reaches each target as
    cocopp's ``DataSet.detEvals`` gives them (``inf`` where never)."""
    rows = aligned_rows(runs)
    out = np.full((len(runs), len(targets)), np.inf)
    for j, target in enumerate(targets):
        at = np.nonzero(rows[:, 0] <= target)[0]
        if at.size:
            evaluations = rows[at[0], 1:]
            out[:, j] = np.where(np.isnan(evaluations), np.inf, evaluations)
    return out
