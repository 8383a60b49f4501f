"""Baselines against independent references: numpy's lstsq, noise-free robot data with
known parameters, and closed-form L1 minimisers (median, weighted median)."""

from __future__ import annotations

import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import L1Residual
from sedsabso_jax import baselines as bl
from sedsabso_jax.dynamics._base_parameters import random_states


def eq17(W, tau, x):
    """Eq. 17 written out independently of the package."""
    return float(np.sum(np.abs(np.asarray(W) @ np.asarray(x) - np.asarray(tau))))


@pytest.fixture(scope="module")
def rs010n_noise_free():
    robot = sj.robots.rs010n()
    # 300 samples for the base set too: the regressor compiled for it is reused below
    base = sj.base_parameters(robot, n_samples=300, seed=3)
    q, qd, qdd = random_states(robot, 300, seed=7)
    W = np.asarray(base.regressor(q, qd, qdd)).reshape(-1, base.rank)
    return L1Residual(W, W @ np.asarray(base.values)), np.asarray(base.values)


def outlier_problem(rng, m=200, d=5, n_outliers=8):
    W = rng.standard_normal((m, d))
    x_true = rng.standard_normal(d)
    tau = W @ x_true + 0.01 * rng.standard_normal(m)
    tau[rng.choice(m, n_outliers, replace=False)] += rng.choice([-1, 1], n_outliers) * 50.0
    return W, tau, x_true


def test_ols_matches_numpy_lstsq(rng):
    W, tau = rng.standard_normal((120, 7)), rng.standard_normal(120)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # full rank: no warning
        res = bl.ols((W, tau))
    expected = np.linalg.lstsq(W, tau, rcond=None)[0]
    np.testing.assert_allclose(res.x, expected, rtol=1e-12, atol=1e-12)
    assert res.method == "OLS"
    assert float(res.f) == pytest.approx(eq17(W, tau, expected), rel=1e-12)
    assert res.history_f.shape == (0,) and res.history_n.shape == (0,)


@pytest.mark.parametrize("solve", [bl.ols, lambda p: bl.least_squares(p, "LM"),
                                   lambda p: bl.least_squares(p, "GN")],
                         ids=["OLS", "LM", "GN"])
def test_recovers_rs010n_base_parameters(rs010n_noise_free, solve):
    problem, values = rs010n_noise_free
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # success: no warning from any solver
        res = solve(problem)
    assert np.linalg.norm(res.x - values) <= 1e-8 * np.linalg.norm(values)
    scale = np.sum(np.abs(np.asarray(problem.tau)))
    assert eq17(problem.W, problem.tau, res.x) <= 1e-10 * scale
    assert float(res.f) <= 1e-10 * scale


def test_least_squares_matches_lstsq_from_x0(rs010n_noise_free, rng):
    # same shape as the noise-free test, so the compiled solves are reused
    problem, values = rs010n_noise_free
    W = np.asarray(problem.W)
    tau = np.asarray(problem.tau) + rng.standard_normal(W.shape[0])
    expected = np.linalg.lstsq(W, tau, rcond=None)[0]
    for method in ("LM", "GN"):
        x0 = values + rng.standard_normal(values.shape)
        res = bl.least_squares((W, tau), method, x0=x0)
        assert res.method == method and int(res.n_evaluations) >= 1
        assert np.linalg.norm(res.x - expected) <= 1e-8 * np.linalg.norm(expected)
        assert float(res.f) == pytest.approx(eq17(W, tau, expected), rel=1e-10)
        again = bl.least_squares((W, tau), method, x0=x0)
        assert again.compile_s == 0.0  # compiled code reused
        np.testing.assert_array_equal(again.x, res.x)


def test_least_squares_on_float32_problem(rs010n_noise_free):
    # solved in float64 from the float32-rounded data (optimistix's LM fails on float32)
    problem32 = L1Residual(rs010n_noise_free[0].W, rs010n_noise_free[0].tau, dtype=jnp.float32)
    W, tau = np.asarray(problem32.W, float), np.asarray(problem32.tau, float)
    expected = np.linalg.lstsq(W, tau, rcond=None)[0]
    res = bl.least_squares(problem32, "LM")
    assert res.x.dtype == np.float64
    assert np.linalg.norm(res.x - expected) <= 1e-8 * np.linalg.norm(expected)


def test_least_squares_warns_when_out_of_steps(rs010n_noise_free):
    # LM from zeros needs several steps on this problem; one is not enough
    with pytest.warns(UserWarning, match="did not succeed.*maximum number of steps"):
        bl.least_squares(rs010n_noise_free[0], "LM", max_steps=1)


def test_l1_of_constant_model_is_median(rng):
    tau = rng.standard_normal(101) * 3.0 + 1.0
    res = bl.l1_optimum((np.ones((101, 1)), tau))
    assert res.method == "L1-LP"
    assert float(res.x[0]) == pytest.approx(np.median(tau), abs=1e-9)


def test_l1_of_weighted_model_is_weighted_median(rng):
    w, y = rng.uniform(0.1, 5.0, 60), rng.standard_normal(60)
    order = np.argsort(y)
    cum = np.cumsum(w[order])
    weighted_median = y[order][np.searchsorted(cum, 0.5 * cum[-1])]
    res = bl.l1_optimum((w[:, None], w * y))
    assert float(res.x[0]) == pytest.approx(weighted_median, abs=1e-9)


def test_l1_is_the_floor_with_outliers(rng):
    W, tau, x_true = outlier_problem(rng)
    l1, o = bl.l1_optimum((W, tau)), bl.ols((W, tau))
    lm = bl.least_squares((W, tau), "LM")
    f_l1 = eq17(W, tau, l1.x)
    assert float(l1.f) == pytest.approx(f_l1, rel=1e-12)
    slack = 1e-9 * f_l1  # LP tolerances
    assert f_l1 <= eq17(W, tau, o.x) - 1.0  # outliers: OLS is clearly worse
    assert f_l1 <= eq17(W, tau, lm.x) + slack
    for scale in (1e-6, 1e-3, 1e-1):
        for dx in scale * rng.standard_normal((200 // 3 + 1, W.shape[1])):
            assert f_l1 <= eq17(W, tau, l1.x + dx) + slack
    # L1 ignores the outliers, least squares does not
    assert np.linalg.norm(l1.x - x_true) < 0.2 * np.linalg.norm(o.x - x_true)
    assert bl.gap_to_optimum(o.f, l1.f) > 0.0
    assert bl.gap_to_optimum(l1.f, l1.f) == 0.0


def test_gap_to_optimum():
    assert bl.gap_to_optimum(3.0, 2.0) == pytest.approx(0.5)
    np.testing.assert_allclose(bl.gap_to_optimum(np.array([2.0, 4.0]), 2.0), [0.0, 1.0])
    gap = bl.gap_to_optimum(1.0, 0.0)  # zero optimum: no division by zero
    assert np.isfinite(gap) and gap > 1e300


def test_ols_warns_on_rank_deficient_W(rng):
    W = rng.standard_normal((50, 3))
    W = np.column_stack([W, W[:, 1]])  # duplicate column
    tau = rng.standard_normal(50)
    with pytest.warns(UserWarning, match=r"rank deficient \(numerical rank 3.*condition"):
        res = bl.ols((W, tau))
    # minimum-norm solution: the duplicated coefficient is split evenly
    expected = np.linalg.lstsq(W, tau, rcond=1e-10)[0]
    np.testing.assert_allclose(res.x, expected, rtol=1e-10, atol=1e-12)
    assert float(res.x[1]) == pytest.approx(float(res.x[3]), rel=1e-10)


@pytest.mark.parametrize("call,error,match", [
    (lambda p: bl.least_squares(p, "BFGS"), ValueError, r"method must be one of \['GN', 'LM'\]"),
    (lambda p: bl.least_squares(p, "LM", x0=np.zeros(5)), ValueError, r"x0 must have shape \(4,\)"),
    (lambda p: bl.ols(p.W), TypeError, "problem must be an L1Residual or a tuple"),
    (lambda p: bl.l1_optimum([p.W, p.tau]), TypeError, "problem must be an L1Residual"),
    (lambda p: bl.least_squares("W", "LM"), TypeError, "problem must be an L1Residual"),
])
def test_bad_input(call, error, match):
    problem = L1Residual(np.ones((6, 4)) + np.eye(6, 4), np.ones(6))
    with pytest.raises(error, match=match):
        call(problem)


def test_gap_with_scale_is_zero_for_rounding_level_differences():
    # noise-free data: OLS may land below the LP's rounding-level optimum
    assert bl.gap_to_optimum(1.3e-10, 1.3e-9) == pytest.approx(-0.9)
    assert abs(bl.gap_to_optimum(1.3e-10, 1.3e-9, scale=1e4)) < 1e-3
    assert bl.gap_to_optimum(3.0, 2.0, scale=1e4) == pytest.approx(0.5)  # real gaps unchanged
