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
#: A searched parameter within this factor of a bound counts as on it.
AT_BOUND = 1.02


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


def std_of_columns(J: Float[np.ndarray, "m d"], s2: float, rtol: float = 1e-10
                   ) -> Float[np.ndarray, " d"]:
    """Each parameter's standard deviation ``sqrt(s2 diag((J^T J)^-1))`` from the SVD of
    ``J`` with unit-norm columns (of its triangular factor: the same singular values and
    directions, from a blocked QR of the many rows): ``inf`` for a parameter with a part
    in a direction the rows do not determine (a singular value below ``rtol`` of the
    largest)."""
    norms = np.linalg.norm(J, axis=0)
    scale = np.where(norms > 0, norms, 1.0)
    R = np.linalg.qr(J / scale, mode="r") if J.shape[0] > J.shape[1] else J / scale
    _, sv, Vt = np.linalg.svd(R, full_matrices=False)
    ok = sv > rtol * sv.max()
    var = (Vt[ok] ** 2 / sv[ok, None] ** 2).sum(0) * s2 / scale ** 2
    free = np.abs(Vt[~ok]).max(0) > NULL_COMPONENT if (~ok).any() else np.zeros(J.shape[1], bool)
    return np.where(free | (norms == 0), np.inf, np.sqrt(var))


def searched_std(model, out, samples, step: float = 1e-4) -> dict:
    """Each searched parameter's value, standard deviation, whether it ended on a bound
    (within :data:`AT_BOUND`) and whether the data determine it: ``s^2 (J^T J)^-1`` of the
    weighted residual over the log parameters and the linear values together
    (:func:`std_of_columns`), the parameters' part by central differences of the rows. A
    parameter whose standard deviation (in log scale) exceeds its search box's width
    (``log(upper / lower)``) is not determined: the data cannot place it within the box
    (e.g. the displacement of a friction at rest fitted as 0); its std is ``inf``."""
    found = [f for _, f in model.nonlinear()]
    names = [n for f in found for n in f.names]
    theta = np.concatenate([f.values for f in found])
    lower = np.concatenate([f.lower for f in found])
    upper = np.concatenate([f.upper for f in found])
    unit = [f.unit for f in found for _ in f.names]
    sigma = np.asarray(out.sigma, dtype=float)

    def residual(z: np.ndarray) -> np.ndarray:
        Y = samples.rows(model.with_nonlinear(np.exp(z)), cache=False)
        return ((Y @ out.x - samples.tau) / sigma).reshape(-1)

    z = np.log(theta)
    r = residual(z)
    Jz = np.stack([(residual(z + step * e) - residual(z - step * e)) / (2 * step)
                   for e in np.eye(z.size)], -1)
    W = (samples.rows(model) / sigma[:, None]).reshape(r.size, -1)
    J = np.concatenate([Jz, W], -1)
    dof = max(r.size - J.shape[1], 1)
    log_std = std_of_columns(J, float(r @ r) / dof)[:z.size]
    determined = log_std <= np.log(upper / lower)
    std = np.where(determined, theta * log_std, np.inf)  # d theta = theta d z
    return {name: {"value": float(t), "std": float(s), "unit": u,
                   "at_bound": bool(t <= lower[i] * AT_BOUND or t >= upper[i] / AT_BOUND),
                   "determined": bool(d)}
            for i, (name, t, s, u, d) in enumerate(zip(names, theta, std, unit, determined))}


def function_std(W: Float[np.ndarray, "m d"], residual: Float[np.ndarray, " m"],
                 G: Float[np.ndarray, "k d"]) -> Float[np.ndarray, " k"]:
    """The standard deviation of each row's function ``G x`` of the values, from the
    covariance of :func:`parameter_std` (columns scaled to unit norm, a column of
    rounding errors taken as zero): ``inf`` where ``G``'s row has a part the rows do not
    determine."""
    residual = np.asarray(residual, dtype=float)
    return rows_function_std(W, float(residual @ residual), residual.shape[0], G)


def rows_function_std(W: Float[np.ndarray, "m d"], residual2: float, rows: int,
                      G: Float[np.ndarray, "k d"]) -> Float[np.ndarray, " k"]:
    """:func:`function_std` from rows ``W`` whose ``W^T W`` is that of ``rows`` rows (the
    rows themselves, or a compression of them) and the rows' squared residual norm
    ``residual2``: ``s^2 g (W^T W)^+ g^T`` with ``s^2 = residual2 / (rows - rank)``."""
    W = np.asarray(W, dtype=float)
    norms = np.linalg.norm(W, axis=0)
    live = norms > RANK_TOLERANCE * norms.max(initial=0.0)
    scale = np.where(live, norms, 1.0)
    _, s, Vt = np.linalg.svd(np.where(live, W / scale, 0.0), full_matrices=False)
    rank = int(np.sum(s > RANK_TOLERANCE * s[0])) if s.size and s[0] > 0 else 0
    g = np.atleast_2d(G) / scale
    if rows <= rank:
        return np.full(g.shape[0], np.nan)
    variance = float(residual2) / (rows - rank)
    spread = (Vt[:rank] @ g.T) / s[:rank, None]
    std = np.sqrt(variance * np.sum(spread ** 2, axis=0))
    null = np.linalg.norm(Vt[rank:] @ g.T, axis=0)
    size = np.maximum(np.linalg.norm(g, axis=1), 1e-300)
    return np.where(null > NULL_COMPONENT * size, np.inf, std)
