"""sj.identification: the estimators against closed forms and scipy on simulated data,
recovery of simulated parameters, the physically consistent fit, box searches, warnings and
bad input (estimator options, data, models); the torque model's terms against closed
forms; a box search's parameters on its faces; held-out error on the real KUKA files."""

from __future__ import annotations

import json
import types
import warnings

import numpy as np
import pytest
from conftest import random_dh

import sedsabso_jax as sj
from sedsabso_jax import (
    L1,
    OLS,
    WLS,
    Armature,
    BoxSearch,
    CoupledMotorFriction,
    Estimator,
    LevenbergMarquardt,
    Offset,
    PhysicallyConsistent,
    Quadratic,
    SmoothCoulomb,
    TorqueModel,
    baselines,
    identify,
    is_physically_consistent,
    validation_metrics,
)
from sedsabso_jax.identification import FitProblem, parse_friction

KUKA_LIMITS = np.array([176.0, 176.0, 100.0, 100.0, 100.0, 38.0, 38.0])


@pytest.fixture(scope="module")
def rs010n():
    robot = sj.robots.rs010n()
    return robot, sj.base_parameters(robot)


def model_of(robot, base, *terms, **options):
    """The torque model of ``robot`` with ``terms``, on precomputed base parameters."""
    return TorqueModel.of(robot, terms, base=base, **options)


def states(rng, n, T=200):  # one sample count: the regressor compiles once
    return (rng.uniform(-np.pi, np.pi, (T, n)), rng.standard_normal((T, n)),
            rng.standard_normal((T, n)))


def test_ols_recovers_simulated_parameters(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    # a physically consistent truth with friction, plus offsets and quadratic friction
    table, params = random_dh(rng, 3)
    off, fq = np.array([0.3, -0.2, 0.1]), np.array([0.05, 0.02, 0.01])
    tau = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd)) + off + fq * qd * abs(qd)
    ident = identify(robot, (q, qd, qdd, tau), OLS(), model_of(robot, base, Offset(),
                                                                Quadratic()))
    assert ident.names[-6:] == ("OFF1", "OFF2", "OFF3", "FQ1", "FQ2", "FQ3")
    truth = np.concatenate([np.asarray(base.project(params)), off, fq])
    np.testing.assert_allclose(ident.values, truth, rtol=1e-9, atol=1e-9)
    assert max(ident.fit["rms"]) < 1e-9
    np.testing.assert_allclose(ident.predict(q, qd, qdd), tau, atol=1e-9)
    # the same without the extra terms; LM and L1 reach it too
    tau0 = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd))
    for estimator in (OLS(), LevenbergMarquardt(), L1()):
        ident = identify(robot, (q, qd, qdd, tau0), estimator, model_of(robot, base))
        np.testing.assert_allclose(ident.values, base.project(params), rtol=1e-6, atol=1e-6)


def test_smooth_coulomb_model(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    params = np.asarray(robot.params).copy()
    params[10::12], params[11::12] = [1.0, 0.5, 0.2], [0.3, 0.2, 0.1]
    eps = 0.05
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    tau = Y @ params
    tau += (np.tanh(qd / eps) - np.sign(qd)) * params[10::12]  # the smooth Coulomb term
    model = model_of(robot, base, SmoothCoulomb(velocity=eps))
    ident = identify(robot, (q, qd, qdd, tau), OLS(), model)
    np.testing.assert_allclose(ident.values, base.project(params), rtol=1e-9, atol=1e-9)
    assert ident.settings["smooth_velocity"] == eps


def test_wls_weights(rs010n, rng):
    robot, base = rs010n
    plain = model_of(robot, base)
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    tau_noisy = tau + 0.5 * rng.standard_normal(tau.shape)
    ols = identify(robot, (q, qd, qdd, tau_noisy), OLS(), plain)
    # equal weights: WLS is OLS exactly
    same = identify(robot, (q, qd, qdd, tau_noisy), WLS([2.0, 2.0, 2.0]), plain)
    np.testing.assert_allclose(same.values, ols.values, rtol=1e-10, atol=1e-10)
    # asked for by name ("equal", what --method WLS --weights equal gives): the same
    equal = identify(robot, (q, qd, qdd, tau_noisy), WLS("equal"), plain)
    assert equal.settings["weights"] == "equal" and equal.settings["sigma"] == [1.0] * 3
    np.testing.assert_allclose(equal.values, ols.values, rtol=1e-10, atol=1e-10)
    assert sj.identification.estimator_candidates("WLS", "equal") == (WLS("equal"),)
    # equal noise: Gautier's weights come out nearly equal, so WLS stays close to OLS
    wls = identify(robot, (q, qd, qdd, tau_noisy), WLS(), plain)
    assert wls.settings["weights"] == "residual"
    sigma = np.array(wls.settings["sigma"])
    np.testing.assert_allclose(sigma, 0.5, rtol=0.1)
    assert np.max(np.abs(wls.values - ols.values)) < 0.1 * np.max(np.abs(ols.values))
    # unequal noise: WLS beats OLS on the parameters
    noise = np.array([3.0, 0.01, 0.01])
    tau_unequal = tau + noise * rng.standard_normal(tau.shape)
    true = np.asarray(base.values)
    err = {e.name: np.linalg.norm(identify(robot, (q, qd, qdd, tau_unequal), e,
                                           plain).values - true) for e in (OLS(), WLS())}
    assert err["WLS"] < 0.8 * err["OLS"]
    lim = identify(robot, (q, qd, qdd, tau_noisy), WLS("limits"), plain,
                   limits=[100.0, 100.0, 50.0])
    assert lim.settings["sigma"] == [100.0, 100.0, 50.0]
    assert "nrms_limits_percent" in lim.fit


def test_l1_is_the_l1_optimum(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    tau = tau + rng.standard_t(2, tau.shape)
    ident = identify(robot, (q, qd, qdd, tau), L1(), model_of(robot, base, Offset()))
    W = ident.model.regressor(q, qd, qdd).reshape(-1, len(ident.names))
    floor = baselines.l1_optimum((W, tau.reshape(-1)))
    assert ident.fit["l1"] == pytest.approx(float(floor.f), rel=1e-7)
    ols = identify(robot, (q, qd, qdd, tau), OLS(), model_of(robot, base, Offset()))
    assert ident.fit["l1"] <= ols.fit["l1"]


def test_physical_fit(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    _, params = random_dh(rng, 3)  # consistent, friction >= 0
    tau = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd))
    # consistent truth, no noise: the constrained optimum is the truth's base values
    ident = identify(robot, (q, qd, qdd, tau), PhysicallyConsistent(), model_of(robot, base))
    assert is_physically_consistent(ident.full_params)
    np.testing.assert_allclose(ident.values, base.project(params), rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(base.project(ident.full_params), ident.values, atol=1e-9)
    # the RS010N's own Table 2 is inconsistent (Ixx2 < 0): OLS gives it back, the physical
    # fit gives a consistent set with a larger residual
    assert not is_physically_consistent(robot.params)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    ols = identify(robot, (q, qd, qdd, tau), OLS(), model_of(robot, base))
    phys = identify(robot, (q, qd, qdd, tau), PhysicallyConsistent(prior_weight=1e-3),
                    model_of(robot, base))
    assert is_physically_consistent(phys.full_params)
    masses = np.asarray(phys.full_params).reshape(3, 12)[:, 6]
    assert np.all(masses > 0)
    assert phys.fit["l2"] > ols.fit["l2"]
    assert phys.settings["physical_fit"]["status"] == "optimal"
    assert phys.settings["physical_fit"]["iterations"] > 0


def test_swarm_identification(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    with pytest.warns(UserWarning, match="parameters ended on the box's faces"):
        ident = identify(robot, (q, qd, qdd, tau),
                         BoxSearch(sj.LDWPSO(), box=(0.1, 0.1), runs=2, iterations=30, seed=3),
                         model_of(robot, base))
    assert ident.result is not None and np.asarray(ident.result.f).shape == (2,)
    assert ident.fit["l1"] == pytest.approx(float(np.min(ident.result.f)), rel=1e-6)
    s = ident.settings
    assert s["runs"] == 2 and s["iterations"] == 30 and s["seed"] == 3
    assert s["box"] == {"fraction": 0.1, "floor": 0.1, "centre": "prior"}
    assert s["solver"]["population_size"] == 50
    json.dumps(ident.as_dict())  # JSON-ready
    v = np.asarray(base.values)
    half = np.maximum(0.1 * np.abs(v), 0.1)
    assert np.all(np.abs(ident.values - v) <= half + 1e-12)


def test_physical_fit_never_fails_silently(rs010n, rng, monkeypatch):
    """Clarabel's status is checked: an inaccurate solve warns, a failed one raises with
    the status (in cvxpy's words, as cvxpy's own map gives them), instead of returning
    whatever the solver left."""
    from cvxpy.reductions.solvers.conic_solvers.clarabel_conif import CLARABEL

    from sedsabso_jax.identification._estimators._conic import STATUS
    from sedsabso_jax.identification._estimators._programme import Programme

    assert {k: v for k, v in CLARABEL.STATUS_MAP.items() if v != "solver_error"} == STATUS
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    real = Programme.solver.func  # the cached property's function

    class Ending:  # Clarabel, whose solve ends with another status
        def __init__(self, programme, status):
            self.solver, self.status = real(programme), status

        def get_settings(self):
            return self.solver.get_settings()

        def update(self, **data):
            self.solver.update(**data)

        def solve(self):
            solution = self.solver.solve()
            return types.SimpleNamespace(status=self.status, iterations=solution.iterations,
                                         x=solution.x)

    def ending_with(status):
        monkeypatch.setattr(Programme, "solver", property(lambda self: Ending(self, status)))

    ending_with("AlmostSolved")
    data, physical, model = (q, qd, qdd, tau), PhysicallyConsistent(), model_of(robot, base)
    with pytest.warns(UserWarning, match="optimal_inaccurate"):
        ident = identify(robot, data, physical, model)
    assert ident.settings["physical_fit"]["status"] == "optimal_inaccurate"
    for status in ("PrimalInfeasible", "DualInfeasible", "AlmostPrimalInfeasible",
                   "NumericalError"):
        ending_with(status)
        with pytest.raises(RuntimeError, match=f"status '{CLARABEL.STATUS_MAP[status]}'"):
            identify(robot, data, physical, model)


def test_rank_deficiency_warns(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    q[:, 2], qd[:, 2], qdd[:, 2] = 0.3, 0.0, 0.0  # joint 3 never moves
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    with pytest.warns(UserWarning, match=r"rank deficient.*condition number.*FC3") as record:
        ident = identify(robot, (q, qd, qdd, tau), OLS(), model_of(robot, base))
    assert record[0].filename == __file__  # the warning points at the caller's line
    assert ident.fit["rank"] < len(ident.names)
    np.testing.assert_allclose(ident.predict(q, qd, qdd), tau, atol=1e-8)
    # a well-excited set does not warn
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        identify(robot, (q, qd, qdd, tau), OLS(), model_of(robot, base))


def test_predict_batches(rs010n, rng):
    robot, base = rs010n
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    ident = identify(robot, sj.Measurements(np.arange(200.0), q, qd, qdd, tau), OLS(),
                     model_of(robot, base, Offset()))
    shape = (4, 50, 3)
    batched = ident.predict(q.reshape(shape), qd.reshape(shape), qdd.reshape(shape))
    np.testing.assert_allclose(batched.reshape(200, 3), ident.predict(q, qd, qdd), atol=1e-12)
    assert "OLS" in repr(ident)


@pytest.mark.parametrize("make, match", [
    (lambda: OLS(sigma="robust"), r"^sigma must be None, 'equal', 'residual', 'limits' or "),
    (lambda: WLS(sigma=[1.0, -1.0, 1.0]), r"^sigma must be None, .*got \(1.0, -1.0, 1.0\)$"),
    (lambda: L1(sigma=[[1.0]]), "^sigma must be"),
    (lambda: LevenbergMarquardt(max_steps=0), r"^max_steps must be an integer >= 1, got 0$"),
    (lambda: LevenbergMarquardt(rtol=-1.0), r"^rtol must be a number > 0, got -1.0$"),
    (lambda: LevenbergMarquardt(atol=float("nan")), "^atol must be a number > 0"),
    (lambda: BoxSearch("GA"), r"^solver must be an optimiser instance"),
    (lambda: BoxSearch(sj.BSO(), runs=0), r"^runs must be an integer >= 1, got 0$"),
    (lambda: BoxSearch(sj.BSO(), iterations=2.5), r"^iterations must be an integer >= 1"),
    (lambda: BoxSearch(sj.BSO(), seed=-1), r"^seed must be an integer >= 0, got -1$"),
    (lambda: BoxSearch(sj.BSO(), box=(0.0, 0.0)), r"^box \(fraction, floor\) must be finite"),
    (lambda: BoxSearch(sj.BSO(), box=(np.nan, 0.5)), r"^box \(fraction, floor\) must be finite"),
    (lambda: BoxSearch(sj.BSO(), box=([0.0, np.inf], [1.0, 2.0])), r"^box: bounds must be "
     r"finite$"),
    (lambda: BoxSearch(sj.BSO(), box=([0.0, 3.0], [1.0, 2.0])), r"^box: bounds need lower < "
     r"upper; at index 1"),
    (lambda: BoxSearch(sj.BSO(), box="wide"), r"^box must be \(fraction, floor\) or \(lower, "
     r"upper\) arrays"),
    (lambda: BoxSearch(sj.BSO(), prior=[1.0, np.nan]), r"^prior must be finite full "
     r"parameters"),
    (lambda: PhysicallyConsistent(L1()), r"^least_squares must be OLS\(...\) or WLS\(...\)"),
    (lambda: PhysicallyConsistent(prior_weight=-1.0), r"^prior_weight must be a number >= 0, "
     r"got -1.0$"),
    (lambda: PhysicallyConsistent(prior_strength=True), r"^prior_strength must be a number"),
    (lambda: Estimator.named("GA"), r"^unknown estimator 'GA'; expected one of \('OLS', "),
])
def test_bad_estimator_options(make, match):
    """Each estimator checks its options when it is built: one line naming the option and
    what was expected."""
    with pytest.raises(ValueError, match=match) as err:
        make()
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("estimator, kwargs, match", [
    (OLS(), dict(model="viscous-coulomb+offset"), r"^model must be a TorqueModel \(TorqueModel"
     r"\.of\(robot, terms\); parse_friction reads the command line's 'a\+b' text\), got "),
    (WLS("limits"), {}, r"^sigma='limits' needs limits=\(one torque limit per joint\)$"),
    (WLS([1.0, 2.0]), {}, r"^sigma must be 3 positive finite numbers \(one per joint\)"),
    (OLS(), dict(limits=[1.0, 2.0]), "limits must be 3 positive"),
    (BoxSearch(sj.BSO(), box=([0.0], [1.0])), {}, r"box bounds must both have shape \(21,\)"),
    (BoxSearch(sj.BSO(), prior=np.zeros(5)), {}, "prior must be 36 finite full parameters"),
    (PhysicallyConsistent(prior=np.zeros(5)), {}, "prior must be 36"),
    ("OLS", {}, r"estimator must be an Estimator .* got 'OLS'"),
])
def test_bad_settings(rs010n, estimator, kwargs, match):
    """What only the robot or the model can tell: checked before any data are read."""
    robot, base = rs010n
    kwargs = {"model": model_of(robot, base), **kwargs}
    with pytest.raises((ValueError, TypeError), match=match):
        identify(robot, None, estimator, **kwargs)


def test_a_torque_model_carries_its_own_settings(rs010n):
    robot, base = rs010n
    model = TorqueModel.of(robot, [Offset()], base=base)
    assert model.friction == "viscous-coulomb+offset" and model.base is base
    # one term needs no list (0.5: "'Offset' object is not iterable")
    assert TorqueModel.of(robot, Offset(), base=base).names == model.names
    with pytest.raises(ValueError, match="model is a TorqueModel of robot 'kuka-lwr'"):
        identify(robot, None, OLS(), TorqueModel.of(sj.robots.kuka_lwr4()))
    with pytest.raises(TypeError, match="robot must be a sedsabso_jax.Robot"):
        TorqueModel.of("rs010n")
    with pytest.raises(TypeError, match=r"^terms must be terms \(Offset\(\), \.\.\.\), not the "
                                        r"text 'offset': parse_friction\('offset'\) reads it$"):
        TorqueModel.of(robot, "offset", base=base)
    for terms, match in [((Offset(), Offset()), "^one term of each kind, got "
                                                "'viscous-coulomb\\+offset\\+offset'$"),
                         ((CoupledMotorFriction(),), "^friction term 'coupling' needs a "
                                                     "transmission with a motor that turns"),
                         (("offset",), r"^terms must be terms \(Offset\(\), Quadratic")]:
        with pytest.raises((ValueError, TypeError), match=match):
            TorqueModel.of(robot, terms, base=base)
    with pytest.raises(ValueError, match=r"^one torque offset per recording needs the "
                                         r"Offset\(\) term"):
        TorqueModel.of(robot, (), base=base, recordings=2)
    with pytest.raises(ValueError, match=r"^SmoothCoulomb's velocity must be a number > 0, "
                                         r"got 0\.0$"):
        SmoothCoulomb(0.0)


@pytest.mark.parametrize("estimator", [OLS(), WLS(), L1(), LevenbergMarquardt(),
                                       BoxSearch(sj.BSO(), iterations=2),
                                       PhysicallyConsistent()], ids=lambda e: e.name)
def test_estimators_check_the_rows_they_fit(rs010n, estimator):
    """An estimator given rows of the wrong shape (or not finite) says so in one line."""
    robot, base = rs010n
    model = TorqueModel.of(robot, base=base)
    Y, tau = np.zeros((5, 3, model.dim)), np.zeros((5, 3))
    for args, match in [((Y[..., :-1], tau), r"^Y must have shape \(samples, 3, 21\) \(the "
                                             r"torque model's regressor\), got \(5, 3, 20\)$"),
                        ((Y, tau[:4]), r"^tau must have shape \(5, 3\) \(one row per sample "
                                       r"of Y\), got \(4, 3\)$"),
                        ((Y, np.full((5, 3), np.nan)), "^Y or tau contains NaN or Inf$"),
                        ((Y[:0], tau[:0]), "^no samples$")]:
        with pytest.raises(ValueError, match=match):
            estimator.fit(FitProblem(model, *args))


def test_bad_data(rs010n):
    robot, base = rs010n
    z = np.zeros((20, 3))
    plain = model_of(robot, base)
    with pytest.raises(ValueError, match=r"q must have shape \(samples, 3\)"):
        identify(robot, (np.zeros((20, 2)), z, z, z), OLS(), plain)
    with pytest.raises(ValueError, match="tau contains NaN"):
        identify(robot, (z, z, z, np.full((20, 3), np.nan)), OLS(), plain)
    with pytest.raises(ValueError, match="same number of samples"):
        identify(robot, (z, z, z, np.zeros((19, 3))), OLS(), plain)
    with pytest.raises(ValueError, match="no samples"):
        identify(robot, (np.zeros((0, 3)),) * 4, OLS(), plain)
    with pytest.raises(ValueError, match=r"data must be a Measurements, several, or one "
                                         r"recording's arrays \(q, qd, qdd, tau\) or \(times, "
                                         r"q, qd, qdd, tau\), got ndarray"):
        identify(robot, z, OLS(), plain)
    with pytest.raises(TypeError, match="robot must be"):
        identify("robot", (z, z, z, z))
    with pytest.raises(ValueError, match="base must be"):
        TorqueModel.of(robot, base="base")
    with pytest.raises(ValueError, match=r"got a tuple of 3$"):
        identify(robot, (z, z, z), OLS(), plain)


# ------------------------------------------------- each estimator against a closed form
@pytest.fixture(scope="module")
def noisy(rs010n):
    """RS010N torques with unequal noise per joint and a torque offset, and the model."""
    robot, base = rs010n
    rng = np.random.default_rng(7)
    q, qd, qdd = states(rng, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd)) + [2.0, -1.0, 0.5]
    tau = tau + np.array([2.0, 0.5, 0.1]) * rng.standard_t(3, tau.shape)
    model = model_of(robot, base, Offset())
    Y = model.regressor(q, qd, qdd)
    return (q, qd, qdd, tau), model, Y.reshape(-1, model.dim), tau.reshape(-1)


def test_least_squares_estimators_are_numpys_lstsq(noisy):
    """OLS and Levenberg-Marquardt minimise ||W x - b||; WLS the same on rows divided by
    sigma: the given numbers, the limits, or Gautier's two-step estimate computed here from
    numpy's OLS residual (d_j = columns acting on joint j), and with ``passes=2`` made
    again from the residual of the fit those weights give."""
    data, model, W, b = noisy
    robot = model.robot
    limits = np.array([100.0, 80.0, 20.0])

    def lstsq(sigma):
        row = np.tile(1.0 / sigma, len(b) // 3)
        return np.linalg.lstsq(W * row[:, None], b * row, rcond=None)[0]

    ols = lstsq(np.ones(3))
    r = (W @ ols - b).reshape(-1, 3)
    d_j = np.count_nonzero(np.any(W.reshape(-1, 3, model.dim) != 0, axis=0), axis=-1)
    gautier = np.sqrt(np.sum(r ** 2, axis=0) / (r.shape[0] - d_j))
    r2 = (W @ lstsq(gautier) - b).reshape(-1, 3)
    again = np.sqrt(np.sum(r2 ** 2, axis=0) / (r2.shape[0] - d_j))
    assert np.abs(again / gautier - 1).max() > 1e-3  # the second pass changes them
    for estimator, sigma, rtol in [(OLS(), np.ones(3), 1e-9),
                                   (LevenbergMarquardt(), np.ones(3), 1e-6),
                                   (WLS([1.0, 3.0, 0.2]), np.array([1.0, 3.0, 0.2]), 1e-9),
                                   (WLS("limits"), limits, 1e-9),
                                   (LevenbergMarquardt(sigma="limits"), limits, 1e-6),
                                   (WLS(), gautier, 1e-9),
                                   (WLS(passes=2), again, 1e-9),
                                   (OLS(sigma="residual", passes=2), again, 1e-9)]:
        ident = identify(robot, data, estimator, model, limits=limits)
        np.testing.assert_allclose(ident.settings["sigma"], sigma, rtol=1e-12)
        np.testing.assert_allclose(ident.values, lstsq(sigma), rtol=rtol, atol=rtol * 1e-3,
                                   err_msg=repr(estimator))


def test_l1_is_scipys_linear_programme(noisy):
    """L1 minimises sum |W x - b| / sigma: the primal LP ``min sum t, -t <= W x - b <= t``
    solved by scipy's HiGHS here (the package solves the dual)."""
    from scipy.optimize import linprog

    data, model, W, b = noisy
    for estimator, sigma in [(L1(), np.ones(3)), (L1([1.0, 3.0, 0.2]), [1.0, 3.0, 0.2])]:
        row = np.tile(1.0 / np.asarray(sigma), len(b) // 3)
        Ws, bs = W * row[:, None], b * row
        m, d = Ws.shape
        eye = np.eye(m)
        lp = linprog(np.r_[np.zeros(d), np.ones(m)],
                     A_ub=np.block([[Ws, -eye], [-Ws, -eye]]), b_ub=np.r_[bs, -bs],
                     bounds=[(None, None)] * d + [(0, None)] * m, method="highs")
        ident = identify(model.robot, data, estimator, model)
        assert ident.fit["l1"] == pytest.approx(lp.fun, rel=1e-9)
        assert np.abs(Ws @ ident.values - bs).sum() == pytest.approx(lp.fun, rel=1e-9)


def test_box_search_takes_any_optimiser_and_its_box(noisy):
    """A box search keeps the best run, stays in its box (explicit bounds here), and runs
    an evosax strategy as it runs a swarm."""
    data, model, W, b = noisy
    x = np.linalg.lstsq(W, b, rcond=None)[0]
    lower, upper = x - 0.5, x + 0.5
    with pytest.warns(UserWarning, match="parameters ended on the box's faces"):
        ident = identify(model.robot, data, BoxSearch(sj.BSO(), box=(lower, upper), runs=3,
                                                      iterations=20, seed=1), model)
    assert ident.method == "BSO" and ident.settings["box"] == "explicit"
    assert np.all((ident.values >= lower) & (ident.values <= upper))
    f = np.asarray(ident.result.f)
    assert ident.settings["best_run"] == int(np.argmin(f))
    assert ident.fit["l1"] == pytest.approx(f.min(), rel=1e-9)
    pytest.importorskip("evosax")
    width = np.abs(x) + 1.0  # CMA-ES converges inside a box wide enough: no face, no warning
    lower, upper = x - 0.5 * width, x + 0.5 * width
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cma = identify(model.robot, data, BoxSearch(sj.Evosax("CMA_ES"), box=(lower, upper),
                                                    iterations=100), model)
    assert cma.method == "evosax CMA_ES"
    assert np.all((cma.values >= lower) & (cma.values <= upper))
    assert cma.settings["at_bounds"] == {"count": 0, "names": [], "tolerance": 1e-3}


def test_estimators_by_name():
    """One registry: the command's --method names, in order, and their options."""
    assert Estimator.registered() == ("OLS", "WLS", "L1", "LM", "SEDSABSO", "BSO", "LDWPSO")
    assert Estimator.named("WLS", sigma="limits", runs=3) == WLS("limits")
    swarm = Estimator.named("LDWPSO", runs=3, iterations=7, sigma="residual")
    assert (swarm.solver, swarm.runs, swarm.iterations, swarm.sigma) == (
        sj.LDWPSO.paper(), 3, 7, "residual")


# ---------------------------------------------------------------------- real KUKA data
def _kuka(run: int):
    m = sj.load_kuka_lwr4(run)  # the packaged files, np.load(allow_pickle=False)
    return [m.q, m.qd, m.qdd, m.tau]


def test_kuka_held_out():
    """Identify on measurements_1, validate on measurements_2 (FloBaRoID's split)."""
    robot = sj.robots.kuka_lwr4()
    base = sj.base_parameters(robot)
    train, test = _kuka(1), _kuka(2)

    def held_out(estimator=OLS(), friction="viscous-coulomb"):
        model = TorqueModel.of(robot, parse_friction(friction), base=base)
        ident = identify(robot, train, estimator, model, limits=KUKA_LIMITS)
        predicted = ident.predict(*test[:3])
        return ident, validation_metrics(test[3], predicted, KUKA_LIMITS).nrms_limits_percent

    _, plain = held_out()
    assert plain == pytest.approx(0.2156, abs=5e-4)  # the 0.216 %
    best, value = held_out(WLS("limits"), "viscous-coulomb+offset+quadratic+smooth")
    assert value <= 0.17  # goal; best published on these files: 0.176 %
    assert value < 0.12
    phys, value = held_out(PhysicallyConsistent(WLS("limits")), "offset")
    assert is_physically_consistent(phys.full_params)
    assert value <= 0.17


# ------------------------------------------------------- the torque model's terms
def test_terms_columns_are_their_closed_forms(rs010n, rng):
    """Each term's columns, read from the model's regressor by name: a constant per joint,
    qd|qd|, tanh(qd / v) in the Coulomb columns, the rotor inertia and the coupled motor's
    friction through the transmission K (K[m, j] (K_m . qdd), K[m, j] (K_m . qd) and
    K[m, j] sign(K_m . qd)); the other base columns untouched."""
    robot, base = rs010n
    K = np.array([[2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.5, 4.0]])  # motor 3 turns 2 and 3
    terms = (SmoothCoulomb(0.1), CoupledMotorFriction(), Armature(), Quadratic(), Offset())
    model = TorqueModel.of(robot, terms, transmission=K, base=base)
    assert model.friction == "viscous-coulomb+offset+quadratic+smooth:0.1+armature+coupling"
    assert parse_friction(model.friction) == model.terms  # the text reads back
    assert model.terms == (Offset(), Quadratic(), SmoothCoulomb(0.1), Armature(),
                           CoupledMotorFriction())  # column order, whatever the order given
    q, qd, qdd = states(rng, 3, T=40)
    Y = model.regressor(q, qd, qdd)
    col = dict(zip(model.names, np.moveaxis(Y, -1, 0)))  # name -> (T, n)
    eye = np.eye(3)
    expected = {}
    for j in range(3):
        expected[f"OFF{j + 1}"] = np.tile(eye[j], (40, 1))
        expected[f"FQ{j + 1}"] = (qd * np.abs(qd))[:, [j]] * eye[j]
        expected[f"FC{j + 1}"] = np.tanh(qd / 0.1)[:, [j]] * eye[j]
        expected[f"IA{j + 1}"] = (qdd @ K[j])[:, None] * K[j]
    expected["FVM3"] = (qd @ K[2])[:, None] * K[2]
    expected["FCM3"] = np.sign(qd @ K[2])[:, None] * K[2]
    assert model.regrouped == ("IA1", "IA2")  # in the base regressor's span
    assert model.names[base.rank:] == ("OFF1", "OFF2", "OFF3", "FQ1", "FQ2", "FQ3", "IA3",
                                       "FVM3", "FCM3")
    for name, value in expected.items():
        if name in col:
            np.testing.assert_allclose(col[name], value, atol=1e-14, err_msg=name)
    rigid = np.asarray(base.regressor(q, qd, qdd))
    others = [i for i, n in enumerate(base.names) if not n.startswith("FC")]
    np.testing.assert_array_equal(Y[..., others], rigid[..., others])
    assert model.nonnegative.tolist() == [False] * (base.rank + 3) + [True] * 6
    assert model.settings()["smooth_velocity"] == 0.1 and model.settings()["regrouped"] == [
        "IA1", "IA2"]


def test_offsets_per_recording(rs010n, rng):
    """One offset per joint and recording: OFFj.r, 1 in the sample's recording's column,
    1/R in each without a recording."""
    robot, base = rs010n
    model = TorqueModel.of(robot, (Offset(),), base=base, recordings=2)
    assert model.names[base.rank:] == ("OFF1.1", "OFF1.2", "OFF2.1", "OFF2.2", "OFF3.1",
                                       "OFF3.2")
    q, qd, qdd = states(rng, 3, T=4)
    Y = model.regressor(q, qd, qdd, np.array([0, 1, 1, 0]))[..., base.rank:]
    np.testing.assert_array_equal(Y[1, 0], [0, 1, 0, 0, 0, 0])
    np.testing.assert_array_equal(Y[0, 2], [0, 0, 0, 0, 1, 0])
    np.testing.assert_array_equal(model.regressor(q, qd, qdd)[2, 1, base.rank:],
                                  [0, 0, 0.5, 0.5, 0, 0])
    assert model.settings() == {"offset_per_recording": 2}
    with pytest.raises(ValueError, match=r"recording must hold one integer in \[0, 2\)"):
        model.regressor(q, qd, qdd, np.array([0, 1, 2, 0]))


def test_parse_friction_reads_the_command_lines_text(rs010n):
    assert parse_friction("viscous-coulomb") == ()
    assert parse_friction("quadratic+viscous-coulomb+offset") == (Offset(), Quadratic())
    with pytest.raises(ValueError, match=r"^friction term 'offset' is given twice in "
                                         r"'offset\+smooth\+offset': each term once$"):
        parse_friction("offset+smooth+offset")  # 0.5 dropped the second one silently
    assert parse_friction("coupling+armature") == (Armature(), CoupledMotorFriction())
    for text, match in [("viscous-coulomb+glue", r"^unknown friction term\(s\) \['glue'\]; "
                         r"known: \('viscous-coulomb', 'offset', 'quadratic', 'smooth', "
                         r"'armature', 'coupling', 'stribeck', 'load', 'presliding'"
                         r"(, '[a-z-]+')*\) "  # and any term declared after them
                         r"\(joined by '\+', e\.g\. 'viscous-coulomb\+offset'\)$"),
                        ("offset:2", r"^friction term 'offset' takes no option, got offset:2$"),
                        ("smooth:fast", r"^friction term 'smooth': expected smooth:fit or "
                                        r"smooth:VELOCITY"),
                        ("load:quadratic", r"^friction term 'load': expected load, "
                                           r"load:viscous, load:fixed-point or "
                                           r"load:viscous,fixed-point, got load:quadratic$"),
                        ("smooth:-1", r"^friction term 'smooth': expected smooth:fit or "
                                      r"smooth:VELOCITY \(rad/s, .*each > 0\), got smooth:-1$"),
                        ("presliding:fit:-1", r"^friction term 'presliding': presliding:fit:"
                                              r"LARGEST .* a number in \(1e-05, 0\.5\], got "
                                              r"presliding:fit:-1 \(e\.g\. presliding:fit:"
                                              r"0\.02\)$"),
                        ("", "^friction must be a string of terms joined by '\\+'"),
                        (None, "^friction must be a string")]:
        with pytest.raises(ValueError, match=match):
            parse_friction(text)
    assert sj.identification.FRICTION_TERMS[:9] == (  # then any term declared after them
        "viscous-coulomb", "offset", "quadratic", "smooth", "armature", "coupling", "stribeck",
        "load", "presliding")
    assert parse_friction("smooth:fit+stribeck:0.05+load:viscous") == (
        SmoothCoulomb(fitted=True), sj.Stribeck(0.05), sj.LoadFriction(viscous=True))
    assert parse_friction("smooth:0.1,0.2,0.3") == (SmoothCoulomb((0.1, 0.2, 0.3)),)
    both = parse_friction("load:viscous,fixed-point")
    assert both == (sj.LoadFriction(viscous=True, fixed_point=True),)
    assert sj.TorqueModel.of(rs010n[0], both, base=rs010n[1]).friction == (
        "viscous-coulomb+load:viscous,fixed-point")
    with pytest.raises(ValueError, match="load:viscous,viscous"):
        parse_friction("load:viscous,viscous")


def test_candidate_models(rs010n):
    """The default candidates: the coupled motor's friction added where the transmission
    couples, one offset per recording added for several (the plain model and the offset
    model then one), the base parameters computed once."""
    from sedsabso_jax.identification import FRICTION_CANDIDATES, candidate_models

    robot, base = rs010n
    plain = candidate_models(robot, base=base)
    assert [m.friction for m in plain] == [
        "viscous-coulomb+smooth", "viscous-coulomb+offset+smooth",
        "viscous-coulomb+offset+smooth+armature",
        "viscous-coulomb+offset+smooth+load", "viscous-coulomb+offset+smooth+armature+load"]
    assert all(m.base is base for m in plain) and len(FRICTION_CANDIDATES) == 5
    coupled = sj.Transmission.from_gear_ratios([1.0, 1.0, 1.0], coupling={(3, 2): 1.0})
    per = candidate_models(robot, transmission=coupled, recordings=3)
    assert [m.friction for m in per] == [
        "viscous-coulomb+offset+smooth+coupling",
        "viscous-coulomb+offset+smooth+armature+coupling",
        "viscous-coulomb+offset+smooth+coupling+load",
        "viscous-coulomb+offset+smooth+armature+coupling+load"]
    assert {m.recordings for m in per} == {3} and len({id(m.base) for m in per}) == 1
    assert [m.friction for m in candidate_models(robot, [(Quadratic(),)], base=base)] == [
        "viscous-coulomb+quadratic"]


# ------------------------------------------------------------- estimators as objects
def test_estimators_answer_for_themselves():
    """What the orchestration asks an estimator: properties and methods, never its class;
    equinox modules, abstract or final, variants by dataclasses.replace."""
    import dataclasses

    import equinox as eqx

    from sedsabso_jax.identification import AbstractLeastSquares

    box = BoxSearch(sj.BSO(), iterations=2)
    table = {OLS(): (False, False, True, False), WLS("limits"): (False, False, True, True),
             L1(): (False, False, False, False), LevenbergMarquardt(): (False, False, False,
                                                                        False),
             box: (False, True, False, False),
             PhysicallyConsistent(WLS("limits")): (True, False, True, True)}
    for e, answers in table.items():
        assert isinstance(e, eqx.Module)
        assert (e.physical, e.costly, e.normal_equations, e.needs_limits) == answers, e
    assert OLS().physically_consistent() == PhysicallyConsistent(OLS())
    pc = PhysicallyConsistent(WLS(), prior_strength=1e-3)
    assert pc.physically_consistent() is pc and pc.name == "WLS" and pc.weights == "residual"
    for e in (L1(), LevenbergMarquardt(), box):
        with pytest.raises(ValueError, match=f"^a physically consistent fit is a least-squares "
                                             f"fit: use method 'OLS' or 'WLS', not "
                                             f"'{e.name}'$"):
            e.physically_consistent()
    assert dataclasses.replace(pc, prior_strength=0.5).prior_strength == 0.5
    assert BoxSearch("SEDSABSO") == BoxSearch(sj.SEDSABSO.paper())
    for abstract in (Estimator, AbstractLeastSquares, sj.identification.AbstractTerm):
        with pytest.raises(TypeError, match="abstract"):
            abstract()


def test_box_search_reports_parameters_on_its_faces(noisy):
    """A box too small for the data holds the fit back: the parameters that end on its
    faces (within 0.1 % of the box's width) are counted and named in the settings, and a
    warning at the caller's line says so (a box wide enough: none,
    test_box_search_takes_any_optimiser_and_its_box)."""
    from sedsabso_jax.identification import FACE_TOLERANCE

    data, model, W, b = noisy
    x = np.linalg.lstsq(W, b, rcond=None)[0]
    width = np.abs(x) + 1.0
    lower, upper = x + 0.5 * width, x + 0.6 * width  # the optimum below every coordinate
    small = BoxSearch(sj.LDWPSO(), box=(lower, upper), iterations=30)
    with pytest.warns(UserWarning, match=r"^LDWPSO: (\d+) of 24 parameters ended on the "
                                         r"box's faces \(.*\): the box may hold the fit back "
                                         r"\(widen it") as record:
        ident = identify(model.robot, data, small, model)
    faces = ident.settings["at_bounds"]
    assert faces["count"] >= 12 and faces["tolerance"] == FACE_TOLERANCE == 1e-3
    assert record[0].filename == __file__ and f"{faces['count']} of 24" in str(
        record[0].message)
    on = [n for n, v, lo, hi in zip(ident.names, ident.values, lower, upper)
          if min(v - lo, hi - v) <= 1e-3 * (hi - lo)]
    assert faces["names"] == on and faces["count"] == len(on)
