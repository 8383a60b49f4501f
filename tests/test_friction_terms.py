"""Friction that is not one linear column: Stribeck's curve, friction growing with the
transmitted torque (a fixed point of the fit), and velocity scales searched by the fit.
Their columns against closed forms and an independent rigid-body torque (the full
parameters' inverse dynamics), the coefficients and scales of simulated plants recovered
from noisy torques, their standard deviations, and the command line's text."""

from __future__ import annotations

import equinox as eqx
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.dynamics import N_LINK_PARAMETERS
from sedsabso_jax.identification import parse_friction
from sedsabso_jax.identification._fit._uncertainty import std_of_columns as _std


def motion(n, T=4000, rate=100.0, seed=0):
    """A smooth multi-sine motion of ``n`` joints (q, qd, qdd, times): many passes
    through rest at many accelerations."""
    rng = np.random.default_rng(seed)
    t = np.arange(T) / rate
    w = rng.uniform(0.3, 1.6, (3, n))
    a = rng.uniform(0.2, 0.6, (3, n))
    phase = rng.uniform(0, 2 * np.pi, (3, n))
    arg = w[:, None] * t[None, :, None] + phase[:, None]
    q = (a[:, None] * np.sin(arg)).sum(0)
    qd = (a[:, None] * w[:, None] * np.cos(arg)).sum(0)
    qdd = -(a[:, None] * w[:, None] ** 2 * np.sin(arg)).sum(0)
    return q, qd, qdd, t


def rigid_torque(robot, q, qd, qdd):
    """The rigid-body torque of the robot's own parameters: its inverse dynamics with each
    link's friction set to zero (independent of the base parameters)."""
    params = np.asarray(robot.params).reshape(-1, N_LINK_PARAMETERS).copy()
    params[:, 10:] = 0.0  # FC, FV
    return np.asarray(sj.inverse_dynamics(robot, params.reshape(-1), q, qd, qdd))


@pytest.fixture(scope="module")
def rs010n():
    robot = sj.robots.rs010n()
    return robot, sj.base_parameters(robot)


def test_stribeck_and_load_columns_are_their_closed_forms(rs010n):
    robot, _ = rs010n
    params = np.asarray(robot.params).reshape(-1, N_LINK_PARAMETERS).copy()
    params[:, 10:] = (1.5, 0.7)  # a prior with friction: the load must leave it out
    robot = eqx.tree_at(lambda r: r.params, robot, params.reshape(-1))
    base = sj.base_parameters(robot)
    q, qd, qdd, _ = motion(3, T=50)
    model = sj.TorqueModel.of(robot, (sj.SmoothCoulomb(0.05), sj.Stribeck((0.1, 0.2, 0.3)),
                                      sj.LoadFriction(viscous=True)), base=base)
    assert model.friction == ("viscous-coulomb+smooth:0.05+stribeck:0.1,0.2,0.3+"
                              "load:viscous")
    Y = model.regressor(q, qd, qdd)
    col = dict(zip(model.names, np.moveaxis(Y, -1, 0)))
    load = rigid_torque(robot, q, qd, qdd)  # the load point: the robot's own parameters
    smooth = np.tanh(qd / 0.05)
    for j, vs in enumerate((0.1, 0.2, 0.3)):
        row = np.eye(3)[j]
        np.testing.assert_allclose(col[f"FS{j + 1}"], (np.exp(-(qd[:, j] / vs) ** 2)
                                                       * smooth[:, j])[:, None] * row,
                                   atol=1e-14)
        np.testing.assert_allclose(col[f"FL{j + 1}"], (np.abs(load[:, j]) * smooth[:, j])[
            :, None] * row, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(col[f"FLV{j + 1}"], (np.abs(load[:, j]) * qd[:, j])[
            :, None] * row, rtol=1e-9, atol=1e-9)
    assert model.nonnegative[-9:].all() and model.waiting and not model.nonlinear()


def load_point(model):
    return next(t for t in model.terms if t.name == "load").load_point


def test_prediction_reads_the_load_of_its_load_point(rs010n):
    """``predict(values)`` of a model without a load point is the model reading
    ``values`` times ``values``; with one (a fitted model), the load there."""
    robot, base = rs010n
    q, qd, qdd, _ = motion(3, T=30, seed=1)
    model = sj.TorqueModel.of(robot, (sj.LoadFriction(),), base=base)
    values = np.r_[np.asarray(base.values) * 1.3, [0.05, 0.1, 0.02]]
    expected = model.reading(values).regressor(q, qd, qdd) @ values
    np.testing.assert_allclose(model.predict(values, q, qd, qdd), expected, rtol=1e-12)
    assert not np.allclose(model.regressor(q, qd, qdd) @ values, expected)  # prior's load
    assert load_point(model.reading(values)) == tuple(values[model.rigid_columns])
    fitted = model.reading(np.r_[np.asarray(base.values) * 0.7, np.zeros(3)])
    np.testing.assert_allclose(fitted.predict(values, q, qd, qdd),
                               fitted.regressor(q, qd, qdd) @ values, rtol=1e-12)
    assert not np.allclose(fitted.predict(values, q, qd, qdd), expected)


def simulated(robot, friction, seed=0, noise=0.01):
    """Measurements of ``robot`` along :func:`motion` with ``friction(rigid torque, qd)``
    added and ``noise`` of each joint's RMS torque."""
    q, qd, qdd, t = motion(robot.n_joints, seed=seed)
    clean = sj.simulate_measurements(robot, q, qd, qdd, t)
    tau = clean.tau + friction(rigid_torque(robot, q, qd, qdd), qd)
    rng = np.random.default_rng(seed + 100)
    tau = tau + noise * np.sqrt(np.mean(tau ** 2, 0)) * rng.standard_normal(tau.shape)
    return sj.Measurements(t, q, qd, qdd, tau)


def test_load_coefficients_are_recovered(rs010n):
    """A plant whose Coulomb friction grows by k |tau_rigid| (k = 0.04, 0.08, 0.06), 1 %
    noise: the two stages (the load of a fit without the term, then the fit with it) and
    the fixed point each find every k within 10 %, and the fitted model keeps the load
    its fit used (predictions read it): the first stage's, or the fixed point's."""
    robot, base = rs010n
    k = np.array([0.04, 0.08, 0.06])
    data = simulated(robot, lambda load, qd: k * np.abs(load) * np.sign(qd))
    for term in (sj.LoadFriction(), sj.LoadFriction(fixed_point=True)):
        model = sj.TorqueModel.of(robot, (term,), base=base)
        for estimator in (sj.OLS(), sj.PhysicallyConsistent(sj.OLS())):
            fit = sj.identify(robot, data, estimator, model)
            found = fit.values[[fit.names.index(f"FL{j + 1}") for j in range(3)]]
            np.testing.assert_allclose(found, k, rtol=0.1, err_msg=estimator.name)
            load = fit.settings["load"]
            if term.fixed_point:  # the fit's load: the torque of its own values
                assert load["settled"] and load["iterations"] < 15
                assert load_point(fit.model) == pytest.approx(
                    tuple(fit.model.rigid_values(fit.values)), rel=1e-4, abs=1e-6)
            else:  # the fit's load: that of a least-squares fit without the term
                assert load == {"iterations": 1}
                plain = sj.identify(robot, data, sj.OLS(), sj.TorqueModel.of(robot, base=base))
                assert load_point(fit.model) == pytest.approx(
                    tuple(plain.values[fit.model.rigid_columns]))


def test_stribeck_velocities_are_searched_and_recovered(rs010n):
    """A plant with Stribeck friction (FS = 2, 3, 1.5 N m; v_s = 0.08, 0.15, 0.25 rad/s),
    1 % noise: the fitted scales within 10 %, with standard deviations that cover the
    error, none on a bound; the linear part found with them."""
    robot, base = rs010n
    vs, fs = np.array([0.08, 0.15, 0.25]), np.array([2.0, 3.0, 1.5])
    data = simulated(robot, lambda load, qd: fs * np.exp(-(qd / vs) ** 2) * np.sign(qd),
                     seed=2)
    model = sj.TorqueModel.of(robot, (sj.Stribeck(fitted=True),), base=base)
    fit = sj.identify(robot, data, sj.OLS(), model)
    shapes = fit.settings["searched"]["parameters"]
    found = np.array([shapes[f"v_stribeck{j + 1}"]["value"] for j in range(3)])
    std = np.array([shapes[f"v_stribeck{j + 1}"]["std"] for j in range(3)])
    np.testing.assert_allclose(found, vs, rtol=0.1)
    assert np.all(np.abs(found - vs) < 5 * std) and np.all(std < 0.1 * vs)
    assert not any(s["at_bound"] for s in shapes.values())
    np.testing.assert_allclose(fit.values[[fit.names.index(f"FS{j + 1}") for j in range(3)]],
                               fs, rtol=0.1)
    assert fit.model.terms[0].velocity == pytest.approx(tuple(found))  # the model as fitted
    assert fit.model.friction == "viscous-coulomb+stribeck:fit"


def test_a_scale_the_data_cannot_see_is_reported(rs010n):
    """A plant without any Stribeck friction: the fitted Stribeck scales are not
    determined, or end on a bound, and the report says so (std inf or at_bound)."""
    robot, base = rs010n
    data = simulated(robot, lambda load, qd: 0.0 * qd, seed=3)
    model = sj.TorqueModel.of(robot, (sj.Stribeck(fitted=True),), base=base)
    shapes = sj.identify(robot, data, sj.OLS(), model).settings["searched"]["parameters"]
    assert all(s["std"] is None or s["at_bound"] or s["std"] > 0.3 * s["value"]
               for s in shapes.values()), shapes


def test_a_model_that_is_not_linear_is_validated_split_by_split(rs010n):
    """Cross-validation refits a model that is not linear on each split's training
    samples: on a plant with load friction the load model predicts better than the linear
    one; on a Stribeck plant, fitted Stribeck scales from a poor start (0.5 rad/s) better
    than the same scales fixed."""
    robot, base = rs010n
    k = np.array([0.1, 0.15, 0.1])
    data = simulated(robot, lambda load, qd: k * np.abs(load) * np.sign(qd), seed=4)
    linear = sj.cross_validate(robot, data, sj.OLS(), sj.TorqueModel.of(robot, base=base))
    loaded = sj.cross_validate(robot, data, sj.OLS(),
                               sj.TorqueModel.of(robot, (sj.LoadFriction(),), base=base))
    assert loaded.score < 0.8 * linear.score
    assert len(loaded.fold_scores) == len(linear.fold_scores)
    vs = np.array([0.08, 0.15, 0.25])
    data = simulated(robot, lambda load, qd: 2.0 * np.exp(-(qd / vs) ** 2) * np.sign(qd),
                     seed=6, noise=0.001)
    fixed, fitted = (sj.cross_validate(robot, data, sj.OLS(), sj.TorqueModel.of(
        robot, (sj.Stribeck(0.5, fitted=f),), base=base)) for f in (False, True))
    assert fitted.score < 0.9 * fixed.score


def test_std_of_a_direction_the_rows_do_not_determine():
    """The scales' standard deviations: sqrt(s2 diag((J^T J)^-1)) where the columns are
    independent; inf for a zero column and for both columns of a dependent pair."""
    rng = np.random.default_rng(0)
    J = rng.standard_normal((50, 3))
    np.testing.assert_allclose(_std(J, 2.0), np.sqrt(2.0 * np.diag(np.linalg.inv(J.T @ J))),
                               rtol=1e-10)
    J[:, 1] = 0.0
    assert np.isinf(_std(J, 2.0)[1]) and np.isfinite(_std(J, 2.0)[[0, 2]]).all()
    J[:, 1] = 3.0 * J[:, 0]
    assert np.isinf(_std(J, 2.0)[:2]).all() and np.isfinite(_std(J, 2.0)[2])


def test_the_command_fits_and_reports_them(tmp_path, rs010n):
    import json

    from sedsabso_jax.cli import main

    robot, _ = rs010n
    vs = np.array([0.08, 0.15, 0.25])
    data = simulated(robot, lambda load, qd: 2.0 * np.exp(-(qd / vs) ** 2) * np.sign(qd),
                     seed=5)
    path = data.save(tmp_path / "d.npz")
    out = tmp_path / "fit.json"
    status = main(["identify", "--robot", "rs010n", "--data", str(path), "--method", "OLS",
                   "--weights", "equal", "--no-physical", "--folds", "0",
                   "--friction", "offset+stribeck:fit+load", "--json", str(out)])
    assert status == 0
    doc = json.loads(out.read_text())
    settings = doc["settings"]
    assert settings["friction"] == "viscous-coulomb+offset+stribeck:fit+load"
    assert set(settings["searched"]["parameters"]) == {"v_stribeck1", "v_stribeck2",
                                                       "v_stribeck3"}
    assert settings["load"] == {"iterations": 1}
    assert parse_friction(settings["friction"])[1] == sj.Stribeck(fitted=True)


def test_another_plant_through_tree_at(rs010n):
    """The simulated plants above are the robot's own parameters (a guard on the helper)."""
    robot, _ = rs010n
    q, qd, qdd, _ = motion(3, T=20)
    other = eqx.tree_at(lambda r: r.params, robot, robot.params * 2.0)
    np.testing.assert_allclose(rigid_torque(other, q, qd, qdd),
                               2.0 * rigid_torque(robot, q, qd, qdd), rtol=1e-12, atol=1e-9)


def test_load_columns_do_not_depend_on_the_load_point(rs010n):
    """Which load-friction columns the base regressor spans is decided once, not at the
    load point: a model linearised where a joint carries no load (its column all zero
    there) keeps the columns the validation fitted, so a fit's values always match the
    model's columns."""
    robot, base = rs010n
    model = sj.TorqueModel.of(robot, (sj.Offset(), sj.LoadFriction()), base=base)
    unloaded = model.reading(np.zeros(model.dim))
    assert unloaded.names == model.names and not model.regrouped
    assert unloaded.regressor(*motion(robot.n_joints)[:3]).shape[-1] == model.dim
    # a reading keeps the model's regrouping (not found again): built at that load
    # point, the model finds the same
    point = unloaded.terms[-1].load_point
    built = sj.TorqueModel.of(robot, (sj.Offset(), sj.LoadFriction(load_point=point)),
                              base=base)
    assert built.names == model.names
