"""The ways to solve the equations of :mod:`._equations`.

Each joint's rows are divided by its sigma, Gautier's two-step estimate (the RMS of the
joint's residual after an unweighted fit, then once more after the fit so weighted;
:func:`~._lstsq.gautier_sigma`). On the weighted rows ``W theta ~ b``:

- ``"ordinary"``: least squares (minimum norm, columns scaled to unit norm). The currents
  are in the gains' columns: an errors-in-variables fit, whose gains the currents' noise
  biases toward zero (:mod:`._likelihood`).
- ``"total"``: total least squares of the homogeneous system ``[W, -b] [theta; 1] = 0``
  (Gautier & Briot 2014; FIGAROH's drive-gain step): the right singular vector of the
  smallest singular value of the column-scaled ``[W, -b]``, normalised so that the known
  payload's coefficient is 1. It treats every column as noisy, the regressor's as much as
  the currents'.
- ``"likelihood"``: the maximum likelihood for noise in the currents (:mod:`._likelihood`),
  from the total least squares' estimate.
- ``"physical"``: the maximum likelihood's gains, then the model's values at those gains
  over the payloads a real body can be (its pseudo-inertia positive semidefinite,
  Wensing, Kim & Slotine, IEEE RA-L 2018) with its mass (and centre of mass) as known, and
  the model's terms' coefficients ``>= 0`` where a physical body has them so (a conic
  programme, Clarabel through cvxpy).

The standard deviations are those of the least squares (or of the likelihood's
linearisation) at the returned estimate (:func:`~.._fit._uncertainty.function_std`).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ...dynamics._inertia import pseudo_inertia
from .._estimators._physical import PSD_MARGIN, RIDGE
from .._payload._least_squares import LinearFit, pseudo_inertia_map
from ._equations import GainEquations, payload_columns
from ._likelihood import gain_map, maximum_likelihood
from ._lstsq import eigen, gautier_sigma, lstsq

#: The ways to solve the equations (module docstring).
GAIN_METHODS = ("ordinary", "total", "likelihood", "physical")


@dataclasses.dataclass(frozen=True, eq=False)
class Solution:
    """The unknowns ``theta`` (the free model values, then the gains), and for their
    standard deviations the weighted rows' Jacobian ``W`` and ``residual`` with ``G``, the
    derivatives of ``theta`` by ``W``'s unknowns (:func:`~.._fit._uncertainty.function_std`);
    the solver's ``report``."""

    theta: np.ndarray
    W: np.ndarray
    residual: np.ndarray
    G: np.ndarray
    report: dict


def weighted(eq: GainEquations) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(W, b, sigma)``: the rows divided by each joint's sigma (module docstring)."""
    X, b = eq.rows
    sigma = gautier_sigma(X, b)
    return (X / sigma[:, None]).reshape(-1, X.shape[-1]), (b / sigma).reshape(-1), sigma


def total(W: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Total least squares of ``W theta ~ b`` (module docstring), on the columns scaled to
    unit norm and, where ``W`` is rank deficient, on the combinations of them it
    determines (the others are left at 0, as the minimum-norm least squares leaves them):
    the eigenvector of the smallest eigenvalue of ``[W, -b]``'s scaled Gram matrix."""
    scale, lam, V, rank = eigen(W)
    basis = V[:, :rank]  # the determined combinations of the scaled columns
    Wb = (W / scale) @ basis
    Z = np.column_stack([Wb, -b])
    z_norms = np.linalg.norm(Z, axis=0)
    Zs = Z / z_norms
    unit = np.linalg.eigh(Zs.T @ Zs)[1][:, 0]
    if not abs(unit[-1]) > 1e-8:
        raise ValueError("total least squares: the smallest singular vector leaves out the "
                         "known payload: the payload's mass does not fix the scale")
    v = unit / z_norms
    return (basis @ (v[:-1] / v[-1])) / scale


def physical(eq: GainEquations, fit: LinearFit) -> tuple[np.ndarray, dict]:
    """The least squares of ``fit``'s rows over consistent payloads of the known mass and
    nonnegative term coefficients (module docstring): ``(theta, solver report)``."""
    import cvxpy as cp

    free, u = eq.free, fit.scale.size
    position = {int(c): i for i, c in enumerate(free)}
    S, s0 = np.zeros((10, u)), np.zeros(10)
    for row, column in enumerate(payload_columns(eq.model)):
        if int(column) in position:
            S[row, position[int(column)]] = 1.0
        else:
            s0[row] = eq.known[list(eq.fixed).index(column)]
    nonneg = [position[int(c)] for c in np.flatnonzero(eq.model.nonnegative)
              if int(c) in position]
    if np.all(fit.x[nonneg] >= 0) and np.linalg.eigvalsh(
            pseudo_inertia(S @ fit.x + s0)).min() >= PSD_MARGIN:
        return fit.x, {"solver": "none (the least-squares solution is consistent)",
                       "status": "optimal"}
    scale = fit.scale
    M = fit.s[:, None] * fit.Vt  # ||W theta - b||^2 = ||M (scale theta) - U^T b||^2 + const
    norm = max(float(np.linalg.norm(fit.Ub)), 1e-300)
    ridge = np.sqrt(RIDGE * float(np.sum(M ** 2)) / u)
    xs = cp.Variable(u, name="theta_scaled")
    J = cp.Variable((4, 4), symmetric=True, name="payload")
    theta = cp.multiply(1.0 / scale, xs)
    constraints = [J - PSD_MARGIN * np.eye(4) >> 0,
                   S @ theta + s0 == pseudo_inertia_map() @ cp.hstack(
                       [J[i, j] for i in range(4) for j in range(4)])]
    if nonneg:
        constraints.append(xs[nonneg] >= 0)
    objective = cp.norm(cp.hstack([(M @ xs - fit.Ub) / norm,
                                   ridge * (xs - fit.x * scale) / norm]), 2)
    problem = cp.Problem(cp.Minimize(objective), constraints)
    t0 = time.perf_counter()
    try:
        problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError as err:
        raise RuntimeError(f"drive gains: the conic solver failed: {err}") from None
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise RuntimeError(f"drive gains: Clarabel ended with status {problem.status!r}; no "
                           f"consistent payload of the given mass was found")
    return np.asarray(xs.value, dtype=float) / scale, {
        "solver": "Clarabel (cvxpy)", "status": str(problem.status),
        "iterations": int(problem.solver_stats.num_iters or 0),
        "seconds": time.perf_counter() - t0}


def solve(eq: GainEquations, method: str) -> Solution:
    """The equations ``eq`` solved by ``method`` (one of :data:`GAIN_METHODS`)."""
    if method not in GAIN_METHODS:
        raise ValueError(f"method must be one of {GAIN_METHODS}, got {method!r}")
    W, b, sigma = weighted(eq)
    identity = np.eye(W.shape[1])
    report: dict = {"sigma": sigma.tolist()}
    if method == "ordinary":
        theta = lstsq(W, b)
        return Solution(theta, W, W @ theta - b, identity, report)
    theta = total(W, b)
    if method == "total":
        return Solution(theta, W, W @ theta - b, identity, report)
    problem, x, h, s, found = maximum_likelihood(eq, theta)
    report = {**report, **found}
    if method == "physical":
        x, solved = physical(eq, LinearFit.of(*problem.rows(h, s)))
        report["solver"] = solved
    return Solution(np.r_[x, 1.0 / h], problem.jacobian(x, h, s), problem.residual(x, h, s),
                    gain_map(x.size, h), report)
