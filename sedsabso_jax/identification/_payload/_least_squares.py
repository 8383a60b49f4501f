"""The least squares of a payload fitted against a given robot
(:func:`~._identify_payload.identify_payload` without unloaded recordings): row weights,
the estimate with the standard deviation of any linear function of it, and the
physically consistent projection of the payload's parameters.

Rows ``W x ~ b`` (each joint's rows divided by its sigma), ``x = [robot values; payload
p]``. Columns are scaled to unit norm, ``W = Ws diag(D)``, and ``Ws = U S V^T`` (SVD, rank
``r`` at :data:`~.._fit._uncertainty.RANK_TOLERANCE`); the estimate is the minimum-norm least
squares ``x = D^-1 V S^-1 U^T b``. For a linear function ``g . x`` (a row of a Jacobian)::

    var(g . x) = s^2 sum_k ((D^-1 g) . v_k / s_k)^2,   s^2 = |W x - b|^2 / (m - r)

(the covariance ``s^2 (W^T W)^+`` of :mod:`~.._fit._uncertainty`, exact for least squares with
independent errors of equal variance after weighting), infinite where ``D^-1 g`` has a
component along the null space of ``Ws``: the data do not determine that function.

Physical consistency (Wensing, Kim & Slotine, IEEE RA-L 2018, as
:mod:`~.._estimators._physical`): the payload is a body exactly when its pseudo-inertia
``J(p)`` is positive semidefinite. When the unconstrained ``p`` already is (eigenvalues
>= :data:`~.._estimators._programme.PSD_MARGIN`), it is the constrained optimum too and is
kept; otherwise :func:`consistent` solves::

    min ||S V^T xs - U^T b||  +  ridge     over robot values and J >= PSD_MARGIN 1

a small semidefinite programme (:func:`~.._estimators._conic.statement`, Clarabel through
cvxpy) with a ridge of :data:`~.._estimators._physical.RIDGE` times the data term's mean
curvature toward the unconstrained estimate, which keeps directions the data leave free
finite.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from jaxtyping import Float
from threadpoolctl import threadpool_limits

from .._estimators._conic import Placed, satisfied, statement
from .._estimators._estimator import Sigma, per_joint
from .._estimators._physical import RIDGE
from .._fit._uncertainty import NULL_COMPONENT, RANK_TOLERANCE


def joint_sigma(Y: Float[np.ndarray, "T n d"], tau: Float[np.ndarray, "T n"], sigma: Sigma
                ) -> Float[np.ndarray, " n"]:
    """Each joint's sigma: ones (``None`` or ``"equal"``), the given numbers, or
    ``"residual"``: Gautier's estimate, the RMS of the joint's residual (over the samples
    less the columns acting on the joint) after an unweighted fit, then once more after
    the fit so weighted: the first pass's residual of a joint with small torques carries
    the large joints' noise through the shared parameters."""
    n = Y.shape[1]
    if sigma is None or (isinstance(sigma, str) and sigma == "equal"):
        return np.ones(n)
    if isinstance(sigma, str):
        if sigma != "residual":
            raise ValueError(f"sigma must be None, 'equal', 'residual' or {n} positive numbers "
                             f"(one per joint), got {sigma!r}")
        acting = np.count_nonzero(np.any(Y != 0, axis=0), axis=-1)
        s = np.ones(n)
        for _ in range(2):
            fit = LinearFit.of((Y / s[:, None]).reshape(-1, Y.shape[-1]),
                               (tau / s).reshape(-1))
            r = ((fit.residual.reshape(tau.shape) * s) ** 2).sum(axis=0)
            s = np.sqrt(r / np.maximum(Y.shape[0] - acting, 1))
            s = np.where(s > 0, s, max(float(s.max()), 1e-12))
        return s
    given = per_joint("sigma", sigma, n, allow_none=False)
    assert given is not None  # allow_none=False
    return given


@dataclasses.dataclass(frozen=True, eq=False)
class LinearFit:
    """The minimum-norm least squares of ``W x ~ b`` on unit-norm columns (module
    docstring): ``x``, the residual ``W x - b``, the weighted residual variance ``s^2``,
    and what :meth:`std` needs (the scale ``D``, singular values and vectors, rank)."""

    x: np.ndarray
    residual: np.ndarray
    variance: float
    scale: np.ndarray
    s: np.ndarray
    Vt: np.ndarray
    Ub: np.ndarray
    rank: int

    @classmethod
    def of(cls, W: Float[np.ndarray, "m d"], b: Float[np.ndarray, " m"]) -> LinearFit:
        norms = np.linalg.norm(W, axis=0)
        # a column of rounding errors (a zero torque computed) is a zero column
        live = norms > RANK_TOLERANCE * norms.max(initial=0.0)
        scale = np.where(live, norms, 1.0)
        # one BLAS thread: OpenBLAS's threads made this SVD 1.5-3x slower on 2 cores
        # (1800 x 20 and 42000 x 74 rows), as they did the validations' fits (_folds)
        with threadpool_limits(limits=1, user_api="blas"):
            U, s, Vt = np.linalg.svd(np.where(live, W / scale, 0.0), full_matrices=False)
        rank = int(np.sum(s > RANK_TOLERANCE * s[0])) if s.size and s[0] > 0 else 0
        Ub = U.T @ b
        x = (Vt[:rank].T @ (Ub[:rank] / s[:rank])) / scale
        residual = W @ x - b
        dof = W.shape[0] - rank
        variance = float(residual @ residual) / dof if dof > 0 else float("nan")
        return cls(x, residual, variance, scale, s, Vt, Ub, rank)

    def constrained(self, nonneg: tuple[int, ...], bodies: tuple[Placed, ...], what: str,
                    none_found: str) -> tuple[np.ndarray, dict]:
        """The least squares of these rows over unknowns that meet the constraints of
        :func:`~.._estimators._conic.statement` (``nonneg`` and ``bodies`` placed in the
        scaled unknowns ``xs = scale x``), with a pull of
        :data:`~.._estimators._physical.RIDGE` times the data term's mean curvature
        toward ``x``: ``(x, the solver's report)``."""
        M = self.s[:, None] * self.Vt  # ||W x - b||^2 = ||M xs - U^T b||^2 + const
        norm = max(float(np.linalg.norm(self.Ub)), 1e-300)
        root = np.sqrt(RIDGE * float(np.sum(M ** 2)) / self.scale.size) / norm
        xs, report = statement(M.shape[0], M.shape[1], nonneg, bodies).solve(
            M / norm, self.Ub / norm, root, root * self.x * self.scale, what, none_found)
        return xs / self.scale, report

    def determined(self, G: Float[np.ndarray, "k d"]) -> np.ndarray:
        """Whether the data determine each row's function ``G x``."""
        g = np.atleast_2d(G) / self.scale
        null = self.Vt[self.rank:] @ g.T
        size = np.maximum(np.linalg.norm(g, axis=1), 1e-300)
        return np.linalg.norm(null, axis=0) <= NULL_COMPONENT * size

    def std(self, G: Float[np.ndarray, "k d"]) -> np.ndarray:
        """The standard deviation of each row's ``G x`` (``inf`` where undetermined)."""
        g = np.atleast_2d(G) / self.scale
        spread = (self.Vt[:self.rank] @ g.T) / self.s[:self.rank, None]
        std = np.sqrt(self.variance * np.sum(spread ** 2, axis=0))
        return np.where(self.determined(G), std, np.inf)

    def condition(self, columns: np.ndarray) -> float:
        """The condition number of ``columns`` (scaled) after the other columns: how well
        the data excite them apart from the rest (``inf`` where some are undetermined)."""
        # the columns' block of the scaled (W^T W)^+ is (P^T P)^-1, P the columns projected
        # off the others: its eigenvalues are 1 / sigma(P)^2
        if not np.all(self.determined(np.eye(self.scale.size)[columns] * self.scale)):
            return float("inf")
        V = self.Vt[:self.rank].T / self.s[:self.rank]
        inverse = V[columns] @ V[columns].T
        eig = np.linalg.eigvalsh(inverse)
        return float(np.sqrt(eig[-1] / eig[0]))


def is_consistent(p10: Float[np.ndarray, " 10"]) -> bool:
    """Whether ``p10``'s pseudo-inertia has eigenvalues >= the physical fits' margin."""
    return satisfied(p10, bodies=(0,))


def consistent(fit: LinearFit, n_robot: int) -> tuple[np.ndarray, dict]:
    """The physically consistent least squares (module docstring) of ``fit``'s rows whose
    last 10 columns are the payload's: ``(x, solver report)``."""
    payload = Placed(n_robot + np.arange(10), fit.scale[n_robot:], np.zeros(10))
    return fit.constrained((), (payload,), "payload", "no consistent payload was found")
