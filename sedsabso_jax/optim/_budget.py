"""Equal budgets in fitness evaluations: how many iterations (generations) a solver gets
for a number of evaluations. The swarms spend different numbers per iteration (LDWPSO one
per particle, BSO three per beetle, SEDSABSO three per beetle of a shrinking population
plus ``q`` annealing candidates, Eq. 14-16), so a fair comparison fixes evaluations, not
iterations."""

from __future__ import annotations

import numpy as np

from ._solver import AbstractSolver


def evaluation_counts(solver: AbstractSolver, iterations: int, dim: int) -> np.ndarray:
    """Cumulative fitness evaluations after each iteration of ``solver`` in dimension
    ``dim`` (what ``minimise(...).n_evaluations`` reports after the last)."""
    return np.asarray(solver.evaluation_counts(int(iterations), int(dim)), dtype=np.int64)


def iterations_for_budget(solver: AbstractSolver, budget: int, dim: int) -> int:
    """The most iterations whose evaluations (initial population included) fit in
    ``budget``. Raises ValueError when not even one iteration fits."""
    if isinstance(budget, bool) or not isinstance(budget, (int, np.integer)) or budget < 1:
        raise ValueError(f"budget must be an integer >= 1 (fitness evaluations), got "
                         f"{budget!r}")

    def total(k: int) -> int:
        return int(evaluation_counts(solver, k, dim)[-1])

    one = total(1)
    if one > budget:
        raise ValueError(f"budget {budget} evaluations is below one generation of "
                         f"{solver.label} in {dim} dimensions ({one} evaluations, initial "
                         f"population included)")
    lo, hi = 1, 2  # total(lo) <= budget; grow hi until it does not fit
    while total(hi) <= budget:
        lo, hi = hi, hi * 2
    while hi - lo > 1:  # the total grows with k (up to rounding of N(t): checked below)
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if total(mid) <= budget else (lo, mid)
    while lo > 1 and total(lo) > budget:  # pragma: no cover - rounding safety
        lo -= 1
    return lo
