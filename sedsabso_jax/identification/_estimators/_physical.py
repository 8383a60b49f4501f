"""Physically consistent identification: least squares over parameters a real body can have.

Wensing, Kim & Slotine, "Linear matrix inequalities for physically consistent inertial
parameter identification: a statistical perspective on the mass distribution", IEEE RA-L
3(1), 2018 (arXiv 2017): a link's 10 inertial parameters belong to a physical body exactly
when its 4x4 pseudo-inertia ``J = [[tr(I)/2 1 - I, h], [h^T, m]]`` (``I`` about the
link-frame origin, ``h = m c``) is positive semidefinite; ``J`` is linear in the parameters,
so the constraint is a linear matrix inequality. Positive mass, a positive-definite inertia
satisfying the triangle inequalities and a centre of mass inside the body all follow.

The fit (:func:`fit_physical`) minimises, over every link's ``J`` (eigenvalues >=
:data:`PSD_MARGIN`), the friction coefficients (``Fc, Fv >= 0``, ``FQ >= 0``) and the
torque offsets (free), armature and motor friction (``>= 0``), and the columns of a term
that is a body (a payload: its own pseudo-inertia positive semidefinite)::

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
import functools
import time

import numpy as np
from jaxtyping import ArrayLike, Float

from ...dynamics._inertia import pseudo_inertia
from ...dynamics._robot import N_LINK_PARAMETERS
from ...optim._linear import Factorization
from .._model._torque_model import TorqueModel
from ._conic import NOT_SOLVED, solve, solve_data
from ._programme import PSD_MARGIN, inertial_params, programme

#: Smallest pull to the prior, relative to the mean curvature of the data term.
RIDGE = 1e-9
#: How the fit's errors name it, and what a failed solve did not find.
WHAT, NONE_FOUND = "physically consistent fit", "no consistent parameters were found"


@dataclasses.dataclass(frozen=True)
class PhysicalFit:
    """What :func:`fit_physical` returns: the model's values (base parameters, then the
    extras), the full parameters (12 per link, or None) and the solver's report
    (:func:`~._conic.solve`)."""

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


@functools.lru_cache(maxsize=32)
def _bodies_programme(dim: int, rank: int, nonneg: tuple[int, ...], bodies: tuple[int, ...]):
    """The least squares of :func:`fit_bodies` for one shape of model, its data as cvxpy
    parameters: canonicalised once, by a first solve of the trivial instance (whose
    equilibration every later solve keeps, as :class:`~._programme.Programme`'s)."""
    import cvxpy as cp

    M = cp.Parameter((dim, dim), name="M")
    c = cp.Parameter(dim, name="c")
    root_ridge = cp.Parameter(nonneg=True, name="root_ridge")
    pulled = cp.Parameter(dim, name="root_ridge_start")
    x = cp.Variable(dim, name="x")
    extras = x[rank:]
    constraints = [extras[list(nonneg)] >= 0] if nonneg else []
    for k, start in enumerate(bodies):
        B = cp.Variable((4, 4), symmetric=True, name=f"body{k + 1}")
        constraints += [B - PSD_MARGIN * np.eye(4) >> 0,
                        extras[start:start + 10] == cp.hstack(inertial_params(B))]
    problem = cp.Problem(cp.Minimize(cp.norm(cp.hstack([M @ x - c, root_ridge * x - pulled]),
                                             2)), constraints)
    parameters = {"M": M, "c": c, "root_ridge": root_ridge, "pulled": pulled}
    for v in parameters.values():
        v.value = np.ones(v.shape) if v is root_ridge else np.zeros(v.shape)
    problem.solve(solver=cp.CLARABEL)
    return problem, parameters, x


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
    ridge = RIDGE * float(np.sum(M ** 2)) / model.dim
    nonneg = tuple(int(k) for k in np.flatnonzero(model.nonnegative[rank:]))
    body = np.flatnonzero(model.bodies[rank:])
    t0 = time.perf_counter()
    free = factor.solve()
    extras = free[rank:]
    if np.all(extras[list(nonneg)] >= 0) and all(
            np.linalg.eigvalsh(pseudo_inertia(extras[k:k + 10])).min() >= PSD_MARGIN
            for k in body[::10]):
        return PhysicalFit(free, None, {"solver": NOT_SOLVED, "status": "optimal",
                                        "iterations": 0, "seconds": time.perf_counter() - t0})
    problem, values, x = _bodies_programme(model.dim, rank, nonneg,
                                           tuple(int(k) for k in body[::10]))
    values["M"].value = M / scale
    values["c"].value = factor.c / scale
    values["root_ridge"].value = np.sqrt(ridge) / scale
    values["pulled"].value = np.sqrt(ridge) / scale * free
    report = solve(problem, WHAT, NONE_FOUND, started=t0)
    return PhysicalFit(np.asarray(x.value, dtype=float), None, report)
