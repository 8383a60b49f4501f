"""The one conic solve of the physically consistent fits (:mod:`._physical`, the payload's
:func:`~.._payload._least_squares.consistent`, the drive gains'
:func:`~.._gains._solvers.physical`): a cvxpy problem solved by Clarabel, its status
checked and its report made alike."""

from __future__ import annotations

import time
import warnings
from typing import Any

from ..._deprecation import caller_stacklevel

#: The report of a fit whose least-squares solution already meets the constraints.
NOT_SOLVED = "none (the least-squares solution is consistent)"


def solve(problem: Any, what: str, none_found: str, *, started: float | None = None) -> dict:
    """Solve the cvxpy ``problem`` with Clarabel.

    Arguments:
        problem: a ``cvxpy.Problem`` (its variables hold the solution after).
        what: the fit, as errors and warnings name it (``"payload"``).
        none_found: what a solve that ends neither optimal nor inaccurate did not find.
        started: ``time.perf_counter()`` when the fit began (None: now).

    Returns ``{"solver", "status", "iterations", "seconds"}``. Raises RuntimeError when
    the solver fails or ends not optimal; warns when it stops at its iteration limit or
    stalls (status ``optimal_inaccurate``: feasible, maybe off the optimum)."""
    import cvxpy as cp

    t0 = time.perf_counter() if started is None else started
    try:
        problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError as err:
        raise RuntimeError(f"{what}: the conic solver failed: {err}") from None
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise RuntimeError(f"{what}: Clarabel ended with status {problem.status!r}; "
                           f"{none_found}")
    if problem.status == cp.OPTIMAL_INACCURATE:
        warnings.warn(f"{what}: Clarabel reached its iteration limit or stalled (status "
                      f"'optimal_inaccurate'); the parameters are feasible but may be off "
                      f"the optimum", stacklevel=caller_stacklevel())
    return {"solver": "Clarabel (cvxpy)", "status": str(problem.status),
            "iterations": int(problem.solver_stats.num_iters or 0),
            "seconds": time.perf_counter() - t0}
