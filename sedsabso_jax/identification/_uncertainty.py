"""Standard deviations of identified parameters from the residual covariance.

For the weighted rows ``W x ~ b`` an estimator fitted (``m`` rows, ``d`` parameters of
rank ``r``), with residual ``e = W x - b``, the least-squares covariance is (Gautier and
Khalil's, Swevers et al.'s standard, e.g. FloBaRoID's and FIGAROH's)::

    s^2 = e.e / (m - r)            the weighted residual variance
    cov = s^2 (W^T W)^-1           (the pseudo-inverse, from the SVD of W)
    std = sqrt(diag(cov)),  relative std = 100 std / |x|  [%]

It is exact for ordinary and weighted least squares when the errors of the rows are
independent, zero-mean, of equal variance after weighting, and the model is right.
For Gautier's two-step WLS the weights are estimated from the data (``s^2`` is then near
1); the formula treats them as known. For the other estimators (L1, a box search, a
physically consistent fit with active constraints or a prior) it is the least-squares
linearisation at the returned values: it ignores the constraints and the prior (both of
which shrink the spread) and is an approximation. A parameter the rows cannot determine
(a component along the null space of ``W``) has an infinite standard deviation.
"""

from __future__ import annotations

import numpy as np
from jaxtyping import Float

#: Singular values below this fraction of the largest are the null space of ``W``.
RANK_TOLERANCE = 1e-10
#: A parameter whose unit vector has a component above this along the null space of ``W``
#: is undetermined (infinite standard deviation).
NULL_COMPONENT = 1e-6


def parameter_std(W: Float[np.ndarray, "m d"], residual: Float[np.ndarray, " m"]
                  ) -> Float[np.ndarray, " d"]:
    """``sqrt(diag(s^2 (W^T W)^+))`` with ``s^2 = residual.residual / (m - rank)`` (module
    docstring); ``inf`` for a parameter the rows do not determine, ``nan`` for all when
    there are no more rows than the rank (no residual degrees of freedom)."""
    W, residual = np.asarray(W, dtype=float), np.asarray(residual, dtype=float)
    m, d = W.shape
    _, s, Vt = np.linalg.svd(W, full_matrices=False)  # Vt: (d, d) when m >= d
    rank = int(np.sum(s > RANK_TOLERANCE * s[0])) if s.size and s[0] > 0 else 0
    if m <= rank or m < d:
        return np.full(d, np.nan)
    variance = float(residual @ residual) / (m - rank)
    V = Vt[:rank].T / s[:rank]                       # columns v_k / s_k
    std = np.sqrt(variance * np.sum(V * V, axis=1))  # diag(V S^-2 V^T)
    null = Vt[rank:]
    undetermined = np.sqrt(np.sum(null * null, axis=0)) > NULL_COMPONENT
    return np.where(undetermined, np.inf, std)


def relative_std_percent(std: Float[np.ndarray, " d"], values: Float[np.ndarray, " d"]
                         ) -> Float[np.ndarray, " d"]:
    """``100 std / |value|`` in %; ``inf`` where a value is 0 (and its std is not)."""
    std, values = np.asarray(std, dtype=float), np.abs(np.asarray(values, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(values > 0, 100.0 * std / np.where(values > 0, values, 1.0),
                        np.where(std > 0, np.inf, 0.0))
