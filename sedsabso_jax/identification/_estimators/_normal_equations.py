"""Least-squares rows compressed to what a least-squares fit reads from them.

A least-squares estimator with one weight per joint (OLS, WLS, the physically consistent
fit) sees the rows ``Y (T, n, d)``, ``tau (T, n)`` only through each joint's normal
equations ``G_j = Y_j^T Y_j``, ``h_j = Y_j^T tau_j`` and ``s_j = tau_j^T tau_j``. A
validation fits many splits of one recording; their normal equations are sums over the
samples, so a split's are those of all samples minus those of the rest
(:class:`NormalEquations`), at the cost of a product with the left-out rows only. Each
joint's equations become ``d`` rows again (:meth:`NormalEquations.problem`): ``R_j =
diag(sqrt(lambda)) V^T`` and ``c_j = R_j^+ h_j`` from the eigendecomposition of
``G_j`` (columns scaled to unit norm first), so that ``||Y_j x - tau_j||^2 = ||R_j x -
c_j||^2 + floor_j`` for every ``x``. The estimators fit those ``n d`` rows as they would
the ``T n`` rows (``floor`` and ``samples`` carry what Gautier's residual weighting needs).

Forming ``G`` squares the condition number of the rows (100 with unit-norm columns
becomes 1e4: 4 of float64's 16 digits); the fits on all the data, whose parameters and
diagnostics the user reads, keep the QR of the rows.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from jaxtyping import Float

from .._model._torque_model import TorqueModel
from ._estimator import FitProblem

#: Eigenvalues of a joint's scaled normal matrix below this fraction of its largest are
#: directions the rows do not determine (the rank tolerance of the rows' QR, squared).
EIGEN_RTOL = 1e-20


@dataclasses.dataclass(frozen=True, eq=False)
class NormalEquations:
    """Per joint ``G (n, d, d)``, ``h (n, d)``, ``s (n,)`` of ``samples`` rows."""

    G: np.ndarray
    h: np.ndarray
    s: np.ndarray
    samples: int

    @classmethod
    def of(cls, Y: Float[np.ndarray, "T n d"], tau: Float[np.ndarray, "T n"]) -> NormalEquations:
        Yj = np.ascontiguousarray(np.moveaxis(Y, 1, 0))  # (n, T, d): one product per joint
        G = np.stack([y.T @ y for y in Yj])
        h = np.einsum("jtd,tj->jd", Yj, tau)
        return cls(G, h, np.einsum("tj,tj->j", tau, tau), int(Y.shape[0]))

    def __sub__(self, other: NormalEquations) -> NormalEquations:
        return NormalEquations(self.G - other.G, self.h - other.h, self.s - other.s,
                               self.samples - other.samples)

    def problem(self, model: TorqueModel, limits: np.ndarray | None) -> FitProblem:
        """The ``d`` rows per joint that a least-squares fit reads as it reads the
        original rows (module docstring)."""
        n, d = self.h.shape
        Y = np.zeros((d, n, d))
        tau = np.zeros((d, n))
        floor = np.zeros(n)
        for j in range(n):
            norms = np.sqrt(np.clip(np.diag(self.G[j]), 0.0, None))
            scale = np.where(norms > 0, norms, 1.0)
            lam, V = np.linalg.eigh(self.G[j] / np.outer(scale, scale))
            keep = lam > EIGEN_RTOL * max(float(lam[-1]), 0.0)
            root = np.sqrt(lam[keep])
            rows = root[:, None] * V[:, keep].T * scale  # R_j, on the original columns
            rows[:, norms == 0] = 0.0  # exactly: Gautier's weighting counts the columns
            c = (V[:, keep].T @ (self.h[j] / scale)) / root
            Y[: rows.shape[0], j] = rows
            tau[: rows.shape[0], j] = c
            floor[j] = max(float(self.s[j] - c @ c), 0.0)
        return FitProblem(model, Y, tau, limits, warn=False, floor=floor, samples=self.samples)

