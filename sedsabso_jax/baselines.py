"""Baselines for the paper's identification problem (Eq. 17, ``f(p) = sum |W p - tau|``):
ordinary least squares (column-pivoted QR), optimistix's Levenberg-Marquardt or
Gauss-Newton on the L2 problem, and the exact L1 optimum (a linear programme, HiGHS), the
floor no optimiser of Eq. 17 goes below. Each returns a :class:`~sedsabso_jax.Result`."""

from __future__ import annotations

from .optim._baselines import gap_to_optimum as gap_to_optimum
from .optim._baselines import l1_optimum as l1_optimum
from .optim._baselines import least_squares as least_squares
from .optim._baselines import ols as ols

__all__ = ["ols", "least_squares", "l1_optimum", "gap_to_optimum"]
