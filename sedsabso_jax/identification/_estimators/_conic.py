"""The one conic solve of the physically consistent fits (:mod:`._physical`, the payload's
:func:`~.._payload._least_squares.consistent`, the drive gains'
:func:`~.._gains._solvers.physical`): Clarabel, its status checked and its report made
alike. A cvxpy problem is solved through cvxpy (:func:`solve`); the links' fit, hundreds of
solves in one default identification, gives Clarabel cvxpy's data of its programme
directly (:func:`solve_data`)."""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np

from ..._deprecation import caller_stacklevel

#: The report of a fit whose least-squares solution already meets the constraints.
NOT_SOLVED = "none (the least-squares solution is consistent)"
#: Clarabel's statuses in cvxpy's words (its ``CLARABEL.STATUS_MAP``; any other one is
#: ``"solver_error"``), so that both ways of solving report alike without importing cvxpy.
STATUS = {"Solved": "optimal", "AlmostSolved": "optimal_inaccurate",
          "PrimalInfeasible": "infeasible", "DualInfeasible": "unbounded",
          "AlmostPrimalInfeasible": "infeasible_inaccurate",
          "AlmostDualInfeasible": "unbounded_inaccurate", "MaxIterations": "user_limit",
          "MaxTime": "user_limit"}


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
    return _checked(str(problem.status), int(problem.solver_stats.num_iters or 0),
                    "Clarabel (cvxpy)", what, none_found, t0)


def solve_data(solver: Any, data: dict, what: str, none_found: str, *,
               started: float | None = None) -> tuple[np.ndarray, dict]:
    """Solve a programme given to Clarabel as data, as cvxpy solves a problem it has solved
    before (its warm start): ``solver`` (a ``clarabel.DefaultSolver`` set up once on the
    programme's shape) takes the new data by ``update`` and keeps the equilibration of
    the data it was set up with.

    Arguments:
        solver: the ``clarabel.DefaultSolver``.
        data: ``{"P", "q", "A", "b"}``, of the shapes it was set up with.
        what, none_found, started: as :func:`solve`'s.

    Returns ``(x, report)``: Clarabel's primal solution and the report of :func:`solve`."""
    t0 = time.perf_counter() if started is None else started
    settings = solver.get_settings()
    settings.verbose = False
    try:
        solver.update(**data, settings=settings)
        solution = solver.solve()
    except Exception as err:  # Clarabel's errors (bad data, a panic) have no common class
        raise RuntimeError(f"{what}: the conic solver failed: {err}") from None
    status = STATUS.get(str(solution.status), "solver_error")
    return (np.array(solution.x, dtype=float),
            _checked(status, int(solution.iterations), "Clarabel", what, none_found, t0))


def _checked(status: str, iterations: int, solver: str, what: str, none_found: str,
             started: float) -> dict:
    """The report of a solve that ended with ``status`` (cvxpy's words); raises where it
    is neither optimal nor inaccurate, warns where it is inaccurate."""
    if status not in ("optimal", "optimal_inaccurate"):
        raise RuntimeError(f"{what}: Clarabel ended with status {status!r}; {none_found}")
    if status == "optimal_inaccurate":
        warnings.warn(f"{what}: Clarabel reached its iteration limit or stalled (status "
                      f"'optimal_inaccurate'); the parameters are feasible but may be off "
                      f"the optimum", stacklevel=caller_stacklevel())
    return {"solver": solver, "status": status, "iterations": iterations,
            "seconds": time.perf_counter() - started}
