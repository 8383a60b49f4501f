"""The conic solves of the physically consistent fits, by Clarabel, their status checked
and their reports alike:

- :func:`least_squares`: least squares over parameters bodies can have, built for
  Clarabel directly (the fits of :mod:`._physical`, hundreds in one default
  identification);
- :func:`solve`: a cvxpy problem (the payload's
  :func:`~.._payload._least_squares.consistent` and the drive gains'
  :func:`~.._gains._solvers.physical`, one solve each).
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np
import scipy.sparse as sp
from jaxtyping import ArrayLike, Float

from ..._deprecation import caller_stacklevel
from ...dynamics._inertia import pseudo_inertia

#: The report of a fit whose least-squares solution already meets the constraints.
NOT_SOLVED = "none (the least-squares solution is consistent)"
#: Smallest eigenvalue of each body's pseudo-inertia in a consistent fit (kg m^2, kg).
PSD_MARGIN = 1e-6


def _svec_rows() -> tuple[np.ndarray, np.ndarray]:
    """``(S, e)``: ``S p`` is Clarabel's vector of a pseudo-inertia ``J(p)`` (its upper
    triangle column by column, the off-diagonal entries times sqrt(2), so that the
    vectors' dot product is the matrices'), ``S`` a (10, 10) matrix as ``J`` is linear in
    the link's 10 parameters; ``e`` the identity's vector."""
    J = pseudo_inertia(np.eye(10))  # J[k] of the k-th unit parameter vector
    pairs = [(i, j) for j in range(4) for i in range(j + 1)]
    weight = np.array([1.0 if i == j else np.sqrt(2) for i, j in pairs])
    S = np.stack([J[:, i, j] for i, j in pairs]) * weight[:, None]
    return S, np.array([1.0 if i == j else 0.0 for i, j in pairs])


def least_squares(M: Float[ArrayLike, "m n"], c: Float[ArrayLike, " m"],
                  ridge: Float[ArrayLike, " n"], centre: Float[ArrayLike, " n"], *,
                  bodies: tuple[int, ...] = (), nonneg: tuple[int, ...] = (),
                  what: str, none_found: str, started: float | None = None
                  ) -> tuple[np.ndarray, dict]:
    """Least squares over parameters bodies can have, to Clarabel's optimum::

        min ||M x - c||^2 + sum_i ridge_i (x_i - centre_i)^2
        subject to  pseudo_inertia(x[k:k + 10]) - PSD_MARGIN 1 >= 0  for k in bodies,
                    x[nonneg] >= 0.

    A convex programme, given to Clarabel as it is stated: the square root of the
    objective, a norm, under a second-order cone (``M`` enters as it is, not squared, and
    the solver's tolerance applies to the residual's norm, not to its square: a fit to
    exact data is exact), in units of ``||c||``; a body's constraint as Clarabel's
    positive semidefinite cone of its pseudo-inertia. Built anew each call (no
    canonicalisation: ``python -m benchmarks.physical_fit``).

    Arguments:
        M, c: the data term (a factor of the normal equations and its right-hand side).
        ridge, centre: each parameter's pull (``>= 0``) and where it pulls to.
        bodies: where each body's 10 inertial parameters start in ``x``.
        nonneg: the parameters that are ``>= 0``.
        what, none_found, started: as :func:`solve`'s.

    Returns ``(x, report)``, the report as :func:`solve`'s."""
    import clarabel

    t0 = time.perf_counter() if started is None else started
    M, c = np.asarray(M, dtype=float), np.asarray(c, dtype=float)
    m, n = M.shape
    scale = max(float(np.linalg.norm(c)), 1e-300)
    root = np.sqrt(np.asarray(ridge, dtype=float)) / scale
    pulled = np.flatnonzero(root)
    S, e = _svec_rows()
    # rows of A (variables x, then t) and b, each cone's slack s = b - A [x; t]:
    # (t, M x - c, root (x - centre)) in the second-order cone, in units of ||c||
    k = 1 + m + pulled.size
    A = np.zeros((k + 10 * len(bodies) + len(nonneg), n + 1))
    A[0, n] = -1.0
    A[1:1 + m, :n] = -M / scale
    A[1 + m + np.arange(pulled.size), pulled] = -root[pulled]
    for i, start in enumerate(bodies):  # svec(J(x[start:start + 10]) - margin 1)
        A[k + 10 * i:k + 10 * i + 10, start:start + 10] = -S
    A[k + 10 * len(bodies) + np.arange(len(nonneg)), list(nonneg)] = -1.0
    b = np.concatenate([[0.0], -c / scale, -(root * np.asarray(centre, dtype=float))[pulled],
                        np.tile(-PSD_MARGIN * e, len(bodies)), np.zeros(len(nonneg))])
    cones = [clarabel.SecondOrderConeT(k), *[clarabel.PSDTriangleConeT(4) for _ in bodies]]
    cones += [clarabel.NonnegativeConeT(len(nonneg))] if nonneg else []
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    try:
        solution = clarabel.DefaultSolver(sp.csc_matrix((n + 1, n + 1)), np.r_[np.zeros(n), 1.0],
                                          sp.csc_matrix(A), b, cones, settings).solve()
    except Exception as err:  # Clarabel's errors (bad data, a panic) have no common class
        raise RuntimeError(f"{what}: the conic solver failed: {err}") from None
    status = {"Solved": "optimal", "AlmostSolved": "optimal_inaccurate"}.get(
        str(solution.status), str(solution.status))
    report = _checked(status, int(solution.iterations), "Clarabel", what, none_found, t0)
    return np.array(solution.x[:n], dtype=float), report


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
