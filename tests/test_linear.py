"""The one least-squares core (``optim/_linear.py``) against numpy/scipy, on problems whose
columns differ in scale by many orders of magnitude, rank deficient, ill-conditioned, with
zero columns or fewer rows than columns; and the box rule."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.optim._linear import ILL_RTOL, RANK_RTOL, factorize


def scaled_problem(rng, m=200, d=6):
    scales = 10.0 ** np.linspace(-6, 6, d)  # units from micro to mega
    W = rng.standard_normal((m, d)) * scales
    return W, rng.standard_normal(m), scales


def test_full_rank_matches_lstsq_whatever_the_column_scales(rng):
    W, b, scales = scaled_problem(rng)
    f = factorize(W, b)
    assert f.rank == 6 and f.weak.size == 0
    expected = np.linalg.lstsq(W / scales, b, rcond=None)[0] / scales
    np.testing.assert_allclose(f.solve(), expected, rtol=1e-10)
    # the condition number is that of the unit-norm columns, not of W itself
    Wn = W / np.linalg.norm(W, axis=0)
    assert f.condition_number == pytest.approx(np.linalg.cond(Wn), rel=1e-8)
    assert np.linalg.cond(W) > 1e10 > 1e3 > f.condition_number
    # ||W x - b||^2 = ||R x[perm] - c||^2 + ||b||^2 - ||c||^2
    x = rng.standard_normal(6)
    lhs = np.sum((W @ x - b) ** 2)
    rhs = np.sum((f.R @ x[f.perm] - f.c) ** 2) + b @ b - f.c @ f.c
    assert lhs == pytest.approx(rhs, rel=1e-9)


def test_dependent_columns_are_found_on_unit_norm_columns(rng):
    W, b, _ = scaled_problem(rng, d=4)
    W = np.column_stack([W, 1e8 * W[:, 1]])  # column 4 = 1e8 x column 1: dependent
    f = factorize(W, b)
    assert f.rank == 4
    assert set(f.weak.tolist()) & {1, 4}  # one of the pair is put last
    # minimum-norm solution on unit-norm columns (independent of the columns' units)
    norms = np.linalg.norm(W, axis=0)
    expected = np.linalg.lstsq(W / norms, b, rcond=RANK_RTOL)[0] / norms
    np.testing.assert_allclose(f.solve(), expected, rtol=1e-8, atol=1e-14)
    with pytest.warns(UserWarning, match=r"rank deficient \(numerical rank 4.*: (1|4)"):
        f.warn("test")
    names = ["a", "b", "c", "d", "e"]
    with pytest.warns(UserWarning, match="not identifiable from these data: [be]"):
        f.warn("test", names)


def test_ill_conditioned_columns_warn_but_solve(rng):
    m = 300
    a, c = rng.standard_normal((2, m))
    W = np.column_stack([a, a + 1e-8 * c, rng.standard_normal(m)])  # nearly collinear
    b = W @ np.array([1.0, 2.0, 3.0])
    f = factorize(W, b)
    assert f.rank == 3 and 1e6 < f.condition_number < 1e12
    assert 0 < f.relative[-1] <= ILL_RTOL
    with pytest.warns(UserWarning, match=r"ill-conditioned \(condition number .*poorly "
                                         r"identifiable: [01]$"):
        f.warn("test")
    np.testing.assert_allclose(W @ f.solve(), b, rtol=1e-6)
    well = factorize(rng.standard_normal((50, 3)), rng.standard_normal(50))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        well.warn("test")  # a well-conditioned problem says nothing


def test_zero_column_and_fewer_rows_than_columns(rng):
    W = np.column_stack([rng.standard_normal(20), np.zeros(20), rng.standard_normal(20)])
    b = rng.standard_normal(20)
    f = factorize(W, b)
    assert f.rank == 2 and 1 in f.weak and np.isinf(f.condition_number)
    x = f.solve()
    assert x[1] == 0.0
    np.testing.assert_allclose(x[[0, 2]], np.linalg.lstsq(W[:, [0, 2]], b, rcond=None)[0],
                               rtol=1e-10)
    short = factorize(rng.standard_normal((3, 5)), rng.standard_normal(3))
    assert short.rank == 3 and short.R.shape == (5, 5)
    with pytest.raises(ValueError, match=r"W must be \(m, d\) and b \(m,\)"):
        factorize(np.ones((4, 2)), np.ones(3))


def test_box_around():
    lower, upper = sj.box_around([10.0, -0.01, 0.0], 0.1, 0.1)
    np.testing.assert_allclose(lower, [9.0, -0.11, -0.1])
    np.testing.assert_allclose(upper, [11.0, 0.09, 0.1])
    for fraction, floor in ((0.0, 0.0), (-0.1, 1.0), (0.1, np.inf), (np.nan, 1.0)):
        with pytest.raises(ValueError, match=r"box \(fraction, floor\) must be finite"):
            sj.box_around([1.0], fraction, floor)
    with pytest.raises(ValueError, match="box centre must be a finite 1-D array"):
        sj.box_around([[1.0]], 0.1, 0.1)
