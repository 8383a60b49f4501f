"""Each joint's rows compressed to their triangular factor, once, and the standard
deviations of compressed rows.

The equations have many samples and few unknowns: ``T`` rows per joint (tens of
thousands) against about 100 columns. A joint's rows ``B_j`` (its columns and
right-hand side side by side) factor as ``B_j = Q_j R_j`` (a thin QR, once), and
``|B_j v| = |R_j v|`` for every ``v``: every fit of :mod:`._solvers` and
:mod:`._likelihood` (weighted least squares, Gautier's weights, total least squares,
each Gauss-Newton step) then works on the ``R_j``, exactly, at the cost of a few
hundred rows (Golub & Van Loan, *Matrix Computations*, Sec. 5.3).
"""

from __future__ import annotations

import numpy as np
from jaxtyping import Float

from .._fit._uncertainty import rows_function_std


def compress(blocks: Float[np.ndarray, "T n c"]) -> Float[np.ndarray, "n c c"]:
    """``R_j`` of each joint's rows ``blocks[:, j, :]`` (zero rows below ``T`` when
    there are fewer samples than columns)."""
    T, n, c = blocks.shape
    out = np.zeros((n, c, c))
    for j in range(n):
        R = np.asarray(np.linalg.qr(blocks[:, j, :], mode="r"))
        out[j, :R.shape[0]] = R
    return out


def std(W: Float[np.ndarray, "m d"], residual2: float, rows: int,
        G: Float[np.ndarray, "k d"]) -> Float[np.ndarray, " k"]:
    """The standard deviation of each row's function ``G x`` from compressed rows ``W``
    (``W^T W`` that of the ``rows`` rows they stand for) and the rows' squared residual
    norm ``residual2``: :func:`~.._fit._uncertainty.rows_function_std` (columns scaled to
    unit norm; ``inf`` where ``g`` has a part the rows do not determine)."""
    return rows_function_std(W, residual2, rows, G)
