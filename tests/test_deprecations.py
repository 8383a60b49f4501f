"""Names renamed in 0.2 and call forms replaced in 0.3 keep working through 0.3.x: each
warns (DeprecationWarning, at the caller's line, "removed after sedsabso-jax 0.3") and does
what the new form does."""

from __future__ import annotations

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax._output import jsonable


def test_sedsabso_renamed_hyperparameters():
    with pytest.deprecated_call() as record:
        old = sj.SEDSABSO(q=2, f_min=0.2, f_max=0.8)
    assert sorted(str(w.message).split(" is ")[0] for w in record) == [
        "SEDSABSO(f_max=...)", "SEDSABSO(f_min=...)", "SEDSABSO(q=...)"]
    assert "use n_trials=..." in str(record[0].message)
    assert old == sj.SEDSABSO(n_trials=2, exponent_start=0.2, exponent_end=0.8)
    with pytest.deprecated_call(match=r"SEDSABSO\.q is deprecated"):
        assert old.q == 2
    with pytest.raises(TypeError, match="both q= .deprecated. and n_trials="):
        sj.SEDSABSO(q=2, n_trials=3)


def test_warnings_point_at_the_caller():
    with pytest.deprecated_call() as record:
        sj.SEDSABSO(q=1)
    assert record[0].filename == __file__


def test_identify_weights_is_sigma(rng):
    robot = sj.robots.rs010n()
    base = sj.base_parameters(robot)
    q, qd, qdd = rng.standard_normal((3, 200, 3))
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    tau = tau + 0.1 * rng.standard_normal(tau.shape)
    new = sj.identify(robot, (q, qd, qdd, tau), sj.WLS([1.0, 2.0, 3.0]), base=base)
    with pytest.deprecated_call() as record:
        old = sj.identify(robot, q, qd, qdd, tau, method="WLS", weights=[1.0, 2.0, 3.0],
                          base=base)
    messages = [str(w.message) for w in record]
    assert any(m.startswith("identify(weights=...) is deprecated and will be removed after "
                            "sedsabso-jax 0.3; use sigma=") for m in messages), messages
    np.testing.assert_array_equal(old.values, new.values)


@pytest.fixture(scope="module")
def recording():
    """A small noisy RS010N recording over two periods of one motion."""
    robot = sj.robots.rs010n()
    rng = np.random.default_rng(5)
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)), rng.uniform(-0.3, 0.3, (3, 3)),
                                np.zeros(3), wf=2 * np.pi / 4)
    data = sj.simulate_measurements_along(robot, traj, np.arange(160) / 20.0,
                                          torque_noise=0.02, seed=1)
    return robot, data, (data.times, data.q, data.qd, data.qdd, data.tau)


def _same_cv(a, b):
    np.testing.assert_array_equal(a.fold_scores, b.fold_scores)
    assert jsonable(a.settings) == jsonable(b.settings) and a.period_s == b.period_s


def test_validation_keyword_forms(recording):
    """cross_validate, select_model and choose_prior_strength with 0.2's (robot, times, q,
    qd, qdd, tau, **identify_settings): a warning at the caller's line, the new result."""
    from sedsabso_jax.identification import _validation as V

    robot, data, arrays = recording
    limits = [100.0, 100.0, 50.0]
    with pytest.deprecated_call(match=r"cross_validate\(robot, times, q, qd, qdd, tau, "
                                      r"method=\.\.\., friction=\.\.\., \.\.\.\) is "
                                      r"deprecated") as record:
        old = V.cross_validate(robot, *arrays, folds=3, method="WLS", sigma="limits",
                               friction="offset", limits=limits)
    assert record[0].filename == __file__
    _same_cv(old, V.cross_validate(robot, data, sj.WLS("limits"), "offset", folds=3,
                                   limits=limits))
    with pytest.deprecated_call(match=r"select_model\(robot, times"):
        old = V.select_model(robot, *arrays, frictions=("viscous-coulomb", "offset"),
                             weightings=(("OLS", None), ("L1", "limits")), folds=3,
                             limits=limits, physical=False)
    new = V.select_model(robot, data, estimators=(sj.OLS(), sj.L1("limits")),
                         frictions=("viscous-coulomb", "offset"), folds=3, limits=limits)
    assert old.as_dict()["chosen"] == new.as_dict()["chosen"]
    assert [s for s, _ in old.candidates] == [s for s, _ in new.candidates]
    for (_, a), (_, b) in zip(old.candidates, new.candidates):
        _same_cv(a, b)
    with pytest.deprecated_call(match=r"select_model\(weightings=\.\.\.\)"):
        V.select_model(robot, data, weightings=(("OLS", None),), frictions="offset", folds=3)
    with pytest.deprecated_call(match=r"choose_prior_strength\(robot, times"):
        old = V.choose_prior_strength(robot, *arrays, strengths=(0.0, 1.0), folds=3,
                                      method="WLS", sigma="limits", limits=limits)
    new = V.choose_prior_strength(robot, data, sj.WLS("limits"), strengths=(0.0, 1.0), folds=3,
                                  limits=limits)
    assert (old.chosen, old.best) == (new.chosen, new.best)
    assert new.estimator == sj.PhysicallyConsistent(sj.WLS("limits"), prior_strength=old.chosen)
    for (_, a), (_, b) in zip(old.candidates, new.candidates):
        _same_cv(a, b)


@pytest.mark.parametrize("module, old, new", [
    ("sedsabso_jax.excitation", "search_box", lambda: sj.excitation.coefficient_box),
    ("sedsabso_jax.robots", "KUKA_LWR4_URDF", lambda: sj.robots.kuka_lwr4_urdf),
    ("sedsabso_jax.robots", "RS010N_TABLE2", lambda: sj.paper.TABLE2),
    ("sedsabso_jax.identification", "Model", lambda: sj.TorqueModel),
    ("sedsabso_jax.optim", "minimise", lambda: sj.minimise),
    ("sedsabso_jax.dynamics", "robots", lambda: sj.robots),
    ("sedsabso_jax", "metrics", lambda: sj.identification._metrics),
    ("sedsabso_jax.measurements.transmission", "Transmission", lambda: sj.Transmission),
    ("sedsabso_jax.reproduce.experiment", "run", lambda: sj.reproduce.run),
])
def test_moved_module_names(module, old, new):
    import importlib

    mod = importlib.import_module(module)
    with pytest.deprecated_call(match=f"{module}.{old} is deprecated"):
        value = getattr(mod, old)
    assert value is new()
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        mod.no_such_name  # noqa: B018
