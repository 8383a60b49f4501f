"""Physically consistent identification: least squares over parameters a real body can have.

Wensing, Kim & Slotine, "Linear matrix inequalities for physically consistent inertial
parameter identification: a statistical perspective on the mass distribution", IEEE RA-L
3(1), 2018 (arXiv 2017): a link's 10 inertial parameters belong to a physical body exactly
when its 4x4 pseudo-inertia ``J = [[tr(I)/2 1 - I, h], [h^T, m]]`` (``I`` about the
link-frame origin, ``h = m c``) is positive semidefinite; ``J`` is linear in the parameters,
so the constraint is a linear matrix inequality. Positive mass, a positive-definite inertia
satisfying the triangle inequalities and a centre of mass inside the body all follow.

The fit (:func:`fit_physical`) minimises, over every link's ``J`` (eigenvalues >=
:data:`~._programme.PSD_MARGIN`), the friction coefficients (``Fc, Fv >= 0``, ``FQ >=
0``) and the torque offsets (free), armature and motor friction (``>= 0``), and the
columns of a term that is a body (a payload: its own pseudo-inertia positive
semidefinite)::

    ||W x - b||^2 + lambda ||p - p_prior||^2,     x = [K p, extras]

with ``W, b`` the (weighted) stacked regressor and torques, ``K`` the map from full to base
parameters and ``p`` the full parameters (12 per link). It is a convex semidefinite
programme, solved to its global optimum by Clarabel (the data enter only through the ``d
x d`` triangular factor of :func:`~sedsabso_jax.optim._linear.factorize`; the programme is
built once per model shape, as cvxpy would state it: :mod:`._programme`).
``lambda`` is the user's ``prior_weight`` plus ``prior_strength`` times the data term's
mean curvature (the scale-free form, chosen by validation in
:func:`~sedsabso_jax.choose_prior_strength`), but at least :data:`RIDGE` times that
curvature: the data leave some directions of ``p`` free (the non-identifiable ones), and
along some of them the feasible set is unbounded, so a tiny pull to the prior keeps the
solution finite. A solve that is not optimal is an error; an inaccurate one a warning.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from jaxtyping import ArrayLike, Float

from ...dynamics._robot import N_LINK_PARAMETERS
from ...optim._linear import Factorization
from .._model._torque_model import TorqueModel
from ._conic import NOT_SOLVED, satisfied, shared_statement, solve_data
from ._programme import programme

#: Smallest pull to the prior, relative to the mean curvature of the data term.
RIDGE = 1e-9
#: How the fit's errors name it, and what a failed solve did not find.
WHAT, NONE_FOUND = "physically consistent fit", "no consistent parameters were found"


@dataclasses.dataclass(frozen=True)
class PhysicalFit:
    """What :func:`fit_physical` returns: the model's values (base parameters, then the
    extras), the full parameters (12 per link, or None) and the solver's report
    (:meth:`~._conic.Statement.solve`)."""

    values: np.ndarray
    full_params: np.ndarray | None
    report: dict


def fit_physical(model: TorqueModel, factor: Factorization, prior: Float[ArrayLike, " p"],
                 prior_weight: float = 0.0, prior_strength: float = 0.0) -> PhysicalFit:
    """Physically consistent least squares (see the module docstring) for ``model``, on the
    data factored in ``factor`` (``factorize(W, b)`` of the weighted stacked regressor and
    torques); ``prior`` the full a-priori parameters (12 per link). The pull to the prior
    is ``lambda = prior_weight + prior_strength * (the data term's mean curvature)``:
    ``prior_strength`` is scale-free (the same value means the same balance for any
    weighting, robot or number of samples), which is what validation chooses
    (:func:`~sedsabso_jax.choose_prior_strength`)."""
    n = model.robot.n_joints
    d_full = N_LINK_PARAMETERS * n
    n_extra = model.dim - model.base.rank
    K = np.asarray(model.base.matrix, dtype=float)
    # x = C [p; extras]: base values from the full parameters, extras unchanged
    C = np.zeros((model.dim, d_full + n_extra))
    C[: K.shape[0], :d_full] = K
    C[K.shape[0]:, d_full:] = np.eye(n_extra)
    M = factor.R @ C[factor.perm]  # data term: ||M [p; e] - c||^2 + const
    scale = max(float(np.linalg.norm(factor.c)), 1e-300)  # the objective in units of ||c||^2
    curvature = float(np.sum(M ** 2)) / (d_full + n_extra)
    lam = max(float(prior_weight) + float(prior_strength) * curvature, RIDGE * curvature)
    nonneg = tuple(int(k) for k in np.flatnonzero(model.nonnegative[model.base.rank:]))
    body = np.flatnonzero(model.bodies[model.base.rank:])
    if body.size % 10 or np.any(body[::10] + 9 != body[9::10]):
        raise ValueError("a body's columns must be 10 in a row (a term's every column)")
    t0 = time.perf_counter()
    shape = programme(n, model.dim, n_extra, nonneg, tuple(int(k) for k in body[::10]))
    data = shape.data(M / scale, factor.c / scale, np.sqrt(lam) / scale,
                      np.sqrt(lam) / scale * np.asarray(prior, dtype=float))
    x, report = solve_data(shape.solver, data, WHAT, NONE_FOUND, started=t0)
    full, extra_values = shape.parameters(x)
    return PhysicalFit(np.concatenate([K @ full, extra_values]), full, report)


def fit_bodies(model: TorqueModel, factor: Factorization) -> PhysicalFit:
    """Least squares with the constraints of the model's terms only: their coefficients
    ``>= 0`` where a physical body has them so, and the terms that are bodies (a
    payload) with a positive semidefinite pseudo-inertia; the base values free (the
    links unconstrained). A pull of :data:`RIDGE` times the data term's mean curvature
    toward the unconstrained minimum-norm solution keeps directions the data leave free
    finite. Where the unconstrained solution already meets the constraints it is the
    constrained optimum, and is returned as it is. ``full_params`` is None (no full link
    parameters)."""
    rank = model.base.rank
    M = factor.R @ np.eye(model.dim)[factor.perm]
    scale = max(float(np.linalg.norm(factor.c)), 1e-300)
    root = np.sqrt(RIDGE * float(np.sum(M ** 2)) / model.dim) / scale
    nonneg = tuple(rank + int(k) for k in np.flatnonzero(model.nonnegative[rank:]))
    bodies = tuple(rank + int(k) for k in np.flatnonzero(model.bodies[rank:])[::10])
    t0 = time.perf_counter()
    free = factor.solve()
    if satisfied(free, nonneg, bodies):
        return PhysicalFit(free, None, {"solver": NOT_SOLVED, "status": "optimal",
                                        "iterations": 0, "seconds": time.perf_counter() - t0})
    x, report = shared_statement(model.dim, model.dim, nonneg, bodies).solve(
        M / scale, factor.c / scale, root, root * free, WHAT, NONE_FOUND, started=t0)
    return PhysicalFit(x, None, report)
