"""Standard deviations of identified parameters: against statsmodels' standard errors on the
same rows, and their coverage of the true values over many noise draws."""

from __future__ import annotations

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification._estimators._estimator import FitProblem
from sedsabso_jax.identification._fit._uncertainty import parameter_std, relative_std_percent

SAMPLES = 40  # few rows: the residual's degrees of freedom (m - d) matter
SIGMA = np.array([0.5, 2.0, 5.0])  # N m, per joint: the weighting matters


@pytest.fixture(scope="module")
def problem():
    """The RS010N's Coulomb + viscous model on a short random motion: its regressor, the
    true values and the noise-free torques."""
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(11)
    q, qd, qdd = rng.uniform(-1.5, 1.5, (3, SAMPLES, robot.n_joints))
    model = sj.TorqueModel.of(robot)
    Y = model.regressor(q, qd, qdd)
    true = np.asarray(model.base.values)
    return robot, model, Y, true, (q, qd, qdd)


def _std(estimator, model, Y, tau):
    out = estimator.fit(FitProblem(model, Y, tau, warn=False))
    return out.x, parameter_std(out.W, out.W @ out.x - out.b)


@pytest.mark.parametrize("weighted", [False, True], ids=["OLS", "WLS"])
def test_equals_statsmodels_standard_errors(problem, weighted):
    sm = pytest.importorskip("statsmodels.api")
    robot, model, Y, true, (q, qd, qdd) = problem
    rng = np.random.default_rng(3)
    tau = Y @ true + rng.standard_normal((SAMPLES, 3)) * SIGMA
    fit = sj.identify(robot, (q, qd, qdd, tau), sj.WLS(tuple(SIGMA)) if weighted else sj.OLS(),
                      model)
    X, y = Y.reshape(-1, Y.shape[-1]), tau.reshape(-1)
    weights = np.tile(1 / SIGMA**2, SAMPLES) if weighted else np.ones(len(y))
    reference = sm.WLS(y, X, weights=weights).fit()
    np.testing.assert_allclose(fit.values, reference.params, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fit.std, reference.bse, rtol=1e-9)
    np.testing.assert_allclose(fit.relative_std_percent, 100 * reference.bse / np.abs(
        reference.params), rtol=1e-9)
    document = fit.as_dict()
    np.testing.assert_allclose(document["std"], reference.bse, rtol=1e-9)


@pytest.mark.parametrize("estimator", [sj.OLS(), sj.WLS(tuple(SIGMA))], ids=["OLS", "WLS"])
def test_one_sigma_covers_68_percent_of_the_truths(problem, estimator):
    """OLS under noise of one standard deviation for every joint (where it is the right
    estimator), WLS under a different one per joint with those as its weights."""
    robot, model, Y, true, _ = problem
    rng = np.random.default_rng(7)
    draws = 400
    inside = []
    for _ in range(draws):
        noise = rng.standard_normal((SAMPLES, 3)) * (SIGMA if estimator.sigma else 2.0)
        x, std = _std(estimator, model, Y, Y @ true + noise)
        inside.append(np.abs(x - true) <= std)
    coverage = float(np.mean(inside))
    # t with 120 - 21 = 99 degrees of freedom: P(|t| <= 1) = 0.680; 400 draws x 21
    # parameters put the estimate's standard deviation near 0.006. Measured: 0.668 (OLS),
    # 0.676 (WLS); without the degrees-of-freedom correction 0.62-0.63, WLS's without its
    # weights 0.90, twice the spread 0.95
    assert 0.655 < coverage < 0.705, coverage


def test_undetermined_parameter_is_infinite_and_relative_handles_zero():
    W = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 2.0],
                  [1.0, 0.0, 0.0]])
    std = parameter_std(W, np.array([0.1, -0.2, 0.1, 0.0, 0.3]))
    assert np.isfinite(std[0]) and np.isinf(std[1:]).all()
    # W's first column alone: (W^T W)^-1 = 1/6, s^2 = 0.15 / (5 - 2)
    assert std[0] == pytest.approx(np.sqrt(0.15 / 3 / 6), rel=1e-12)
    assert np.isnan(parameter_std(W[:2], np.zeros(2))).all()  # no degrees of freedom
    rel = relative_std_percent(np.array([0.1, 0.0, 0.2]), np.array([-2.0, 0.0, 0.0]))
    assert rel[0] == pytest.approx(5.0) and rel[1] == 0.0 and np.isinf(rel[2])
