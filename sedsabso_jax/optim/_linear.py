"""The linear regression cores every estimator of ``W x ~ b`` uses: least squares (one
factorisation, its rank and condition number) and the least absolute deviation (L1).

Least squares (:func:`factorize`): ``W P = Q R`` by a column-pivoted Householder QR
(LAPACK ``geqp3``), ``c = Q^T b``; the solution ``x = P R^-1 c``. Householder QR's
solution does not depend on the columns' scales (up to rounding), but rank and
conditioning do, so both are judged on UNIT-NORM columns (``R`` with its columns divided by
their norms, a factor of ``W`` scaled to unit-norm columns): a second pivoted QR of that
small ``d x d`` factor orders the columns by how independent they are, the rank counts
the relative diagonal above :data:`RANK_RTOL`, the columns below :data:`ILL_RTOL` are
called poorly identifiable, and the condition number is that of the scaled factor (SVD).
A rank-deficient problem gets the minimum-norm solution on unit-norm columns (LAPACK
``gelsd`` on the scaled factor), which does not depend on the units of the columns.

Least absolute deviation (:func:`l1_solve`): ``min ||W x - b||_1`` as the dual linear
programme (HiGHS), polished at its vertex.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse
from jaxtyping import ArrayLike, Float

#: Relative diagonal of the pivoted QR (unit-norm columns) below which a column counts as
#: linearly dependent on the others.
RANK_RTOL = 1e-10
#: ... and below which it counts as poorly identifiable (a warning, not an error).
ILL_RTOL = 1e-6


@dataclasses.dataclass(frozen=True, eq=False)
class Factorization:
    """``W P = Q R`` of a least-squares problem ``min ||W x - b||_2`` and its diagnostics.

    Attributes:
        R: ``(d, d)`` upper-triangular factor of the column-permuted ``W``.
        perm: the column permutation ``P`` (``W[:, perm] = Q R``).
        c: ``Q^T b``; ``||W x - b||^2 = ||R x[perm] - c||^2 + ||b||^2 - ||c||^2``.
        norms: the column norms of ``W`` (0 for a zero column).
        rank: numerical rank on unit-norm columns (:data:`RANK_RTOL`).
        condition_number: of ``W`` with unit-norm columns (``inf`` when rank deficient).
        order: columns from most to least independent (pivoted QR on unit-norm columns).
        relative: for each entry of ``order``, its QR diagonal relative to the first.
        shape: ``W``'s shape.
    """

    R: np.ndarray
    perm: np.ndarray
    c: np.ndarray
    norms: np.ndarray
    rank: int
    condition_number: float
    order: np.ndarray
    relative: np.ndarray
    shape: tuple[int, int]

    @property
    def weak(self) -> np.ndarray:
        """Columns whose relative diagonal is at most :data:`ILL_RTOL` (poorly
        identifiable; those at most :data:`RANK_RTOL` are dependent), least independent
        last."""
        return self.order[self.relative <= ILL_RTOL]

    def solve(self) -> np.ndarray:
        """The least-squares solution: ``P R^-1 c`` at full rank, else the minimum-norm
        solution on unit-norm columns."""
        d = self.R.shape[1]
        x = np.empty(d)
        if self.rank == d:
            x[self.perm] = scipy.linalg.solve_triangular(self.R, self.c)
            return x
        scale = _scale(self.norms[self.perm])
        z = scipy.linalg.lstsq(self.R / scale, self.c, cond=RANK_RTOL,
                               lapack_driver="gelsd")[0]
        x[self.perm] = z / scale
        return x

    def warn(self, what: str, names: Sequence[object] | None = None, stacklevel: int = 2
             ) -> None:
        """A UserWarning when the problem is rank deficient or poorly conditioned, with
        the condition number and the columns concerned (``names`` or indices)."""
        weak = self.weak
        if weak.size == 0:
            return
        label = [str(names[k]) for k in weak] if names is not None else [str(k) for k in weak]
        m, d = self.shape
        if self.rank < d:
            warnings.warn(f"{what} ({m} x {d}) is rank deficient (numerical rank {self.rank}, "
                          f"condition number {self.condition_number:.3g} with unit-norm "
                          f"columns); not identifiable from these data: {', '.join(label)}; "
                          f"the minimum-norm solution is returned", stacklevel=stacklevel + 1)
        else:
            warnings.warn(f"{what} ({m} x {d}) is ill-conditioned (condition number "
                          f"{self.condition_number:.3g} with unit-norm columns); poorly "
                          f"identifiable: {', '.join(label)}", stacklevel=stacklevel + 1)


def _scale(norms: np.ndarray) -> np.ndarray:
    return np.where(norms > 0, norms, 1.0)


def factorize(W: Float[ArrayLike, "m d"], b: Float[ArrayLike, " m"]) -> Factorization:
    """Factor ``min ||W x - b||_2`` (``W`` of shape ``(m, d)``, ``m >= 1``, ``b (m,)``)."""
    W, b = np.asarray(W, dtype=float), np.asarray(b, dtype=float)
    if W.ndim != 2 or b.shape != W.shape[:1]:
        raise ValueError(f"W must be (m, d) and b (m,); got W {W.shape}, b {b.shape}")
    m, d = W.shape
    Q, R, perm = scipy.linalg.qr(W, mode="economic", pivoting=True)
    c = Q.T @ b
    if m < d:  # fewer rows than columns: pad R to (d, d) with zero rows
        R, c = np.vstack([R, np.zeros((d - m, d))]), np.concatenate([c, np.zeros(d - m)])
    norms = np.linalg.norm(W, axis=0)
    Rs = R / _scale(norms[perm])  # the factor of W with unit-norm columns, same permutation
    R2, perm2 = scipy.linalg.qr(Rs, mode="r", pivoting=True)
    diag = np.abs(np.diag(R2))
    relative = diag / diag[0] if diag.size and diag[0] > 0 else np.zeros(d)
    order = perm[perm2]
    relative = np.where(norms[order] > 0, relative, 0.0)
    rank = int(np.sum(relative > RANK_RTOL))
    s = np.linalg.svd(Rs, compute_uv=False)
    cond = float(s[0] / s[-1]) if rank == d and s[-1] > 0 else np.inf
    return Factorization(R=R, perm=perm, c=c, norms=norms, rank=rank, condition_number=cond,
                         order=order, relative=relative, shape=(m, d))


def l1_solve(W: Float[ArrayLike, "m d"], b: Float[ArrayLike, " m"]
             ) -> tuple[Float[np.ndarray, " d"], int]:
    """``(argmin_x ||W x - b||_1, HiGHS iterations)``: the exact least-absolute-deviation
    fit (the paper's Eq. 17 is this objective) by linear programming.

    Solved as the DUAL of ``min_{x,t} sum t  s.t.  -t <= W x - b <= t``, which is

        max_y  b^T y   subject to   W^T y = 0,   -1 <= y <= 1

    (``d`` equality rows instead of ``2m`` inequality rows: about 30x faster with HiGHS on
    the paper's problem), on unit-norm columns; ``x`` is read from the equality
    constraints' marginals. The LP optimum is a vertex where ``d`` residuals vanish; the
    estimate is then polished by solving ``W_B x = b_B`` on the ``d`` rows with the
    smallest residuals, and the polished point is kept if its objective is not larger
    (this removes HiGHS's tolerance, ~1e-7 relative, so noise-free data reach ~1e-11 like
    least squares). Raises ``RuntimeError`` with HiGHS's message if the LP fails.
    """
    W, b = np.asarray(W, float), np.asarray(b, float)
    d = W.shape[1]
    scale = _scale(np.linalg.norm(W, axis=0))
    Ws = W / scale
    # linprog minimises: min -b^T y  s.t.  Ws^T y = 0,  -1 <= y <= 1
    res = scipy.optimize.linprog(-b, A_eq=Ws.T, b_eq=np.zeros(d), bounds=(-1.0, 1.0),
                                 method="highs")
    if res.status != 0:
        raise RuntimeError(f"l1_optimum: the LP failed (status {res.status}): {res.message}")
    z = np.asarray(res.eqlin.marginals, dtype=float)
    f = lambda v: np.abs(Ws @ v - b).sum()  # noqa: E731
    z = -z if f(-z) <= f(z) else z  # sign convention of the marginals
    rows = np.argsort(np.abs(Ws @ z - b))[:d]
    try:
        polished = np.linalg.solve(Ws[rows], b[rows])
        if np.all(np.isfinite(polished)) and f(polished) <= f(z):
            z = polished
    except np.linalg.LinAlgError:  # singular vertex: keep HiGHS's point
        pass
    return z / scale, int(res.nit)


def l1_solve_box(W: Float[ArrayLike, "m d"], b: Float[ArrayLike, " m"],
                 lower: Float[ArrayLike, " d"], upper: Float[ArrayLike, " d"]
                 ) -> tuple[Float[np.ndarray, " d"], int]:
    """``(argmin_{lower <= x <= upper} ||W x - b||_1, HiGHS iterations)``: the exact
    least-absolute-deviation fit inside a box, the best a swarm searching that box can
    reach. The unconstrained optimum (:func:`l1_solve`) when it lies in the box; otherwise
    the primal LP ``min sum t  s.t.  -t <= W x - b <= t,  lower <= x <= upper`` (on
    unit-norm columns, sparse, HiGHS). Raises ``RuntimeError`` if the LP fails."""
    W, b = np.asarray(W, float), np.asarray(b, float)
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    x, nit = l1_solve(W, b)
    if np.all(x >= lower) and np.all(x <= upper):
        return x, nit
    m, d = W.shape
    scale = _scale(np.linalg.norm(W, axis=0))
    Ws = scipy.sparse.csr_matrix(W / scale)
    eye = scipy.sparse.identity(m, format="csr")
    A = scipy.sparse.vstack([scipy.sparse.hstack([Ws, -eye]), scipy.sparse.hstack([-Ws, -eye])])
    c = np.concatenate([np.zeros(d), np.ones(m)])
    bounds = np.concatenate([np.stack([lower * scale, upper * scale], axis=1),
                             np.tile([0.0, np.inf], (m, 1))])
    res = scipy.optimize.linprog(c, A_ub=A.tocsc(), b_ub=np.concatenate([b, -b]),
                                 bounds=bounds, method="highs")
    if res.status != 0:
        raise RuntimeError(f"l1_solve_box: the LP failed (status {res.status}): {res.message}")
    return np.clip(res.x[:d] / scale, lower, upper), int(nit + res.nit)
