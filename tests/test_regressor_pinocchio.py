"""Torques and regressor against pinocchio (an independent implementation) on random
URDFs and DH chains, and against closed forms."""

from __future__ import annotations

import os

import numpy as np
import pinocchio as pin
import pytest
from conftest import (
    friction_torque,
    inertial_columns,
    pin_from_dh,
    pin_from_mdh,
    pin_regressor_in_our_order,
    random_dh,
    random_state,
    random_urdf,
)

import sedsabso_jax as sj

URDF_CASES = [(n, seed) for n in range(1, 8) for seed in range(2)]


def _write(tmp_path, text, name="robot.urdf"):
    path = os.path.join(tmp_path, name)
    with open(path, "w") as fh:
        fh.write(text)
    return path


@pytest.mark.parametrize("n,seed", URDF_CASES)
def test_random_urdf_matches_pinocchio(tmp_path, n, seed):
    rng = np.random.default_rng(1000 * n + seed)
    text, _ = random_urdf(rng, n, friction=True)
    robot = sj.robots.from_urdf(_write(tmp_path, text))
    model = pin.buildModelFromXML(text)
    data = model.createData()
    assert robot.n_joints == model.nv == n
    q, qd, qdd = random_state(rng, robot, 4)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    for k in range(4):
        tau_pin = pin.rnea(model, data, q[k], qd[k], qdd[k]) + friction_torque(robot.params, qd[k])
        np.testing.assert_allclose(tau[k], tau_pin, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(inertial_columns(Y[k], n),
                                   pin_regressor_in_our_order(model, q[k], qd[k], qdd[k]),
                                   rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(Y @ np.asarray(robot.params), tau, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("convention", ["mdh", "dh"])
@pytest.mark.parametrize("n", [1, 3, 6])
def test_random_dh_matches_pinocchio(rng, convention, n):
    table, params = random_dh(rng, n)
    if convention == "mdh":
        robot = sj.robots.from_mdh(table["alpha"], table["a"], table["d"], table["theta"],
                                   prismatic=table["prismatic"], params=params)
        model = pin_from_mdh(table, params)
    else:
        robot = sj.robots.from_dh(table["d"], table["a"], table["alpha"], table["theta"],
                                  prismatic=table["prismatic"], params=params)
        model = pin_from_dh(table, params)
    data = model.createData()
    q, qd, qdd = random_state(rng, robot, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd))
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    for k in range(3):
        # joint offsets: pinocchio's q is the joint variable itself
        tau_pin = pin.rnea(model, data, q[k], qd[k], qdd[k]) + friction_torque(params, qd[k])
        np.testing.assert_allclose(tau[k], tau_pin, rtol=1e-10, atol=1e-10)
        if convention == "mdh":  # same body frames: regressors comparable column by column
            np.testing.assert_allclose(inertial_columns(Y[k], n),
                                       pin_regressor_in_our_order(model, q[k], qd[k], qdd[k]),
                                       rtol=1e-10, atol=1e-10)


def test_pendulum_closed_form():
    """One revolute joint about z, gravity along -y, CoM at distance l on the link's x:
    tau = (Izz_c + m l^2) qdd + m g l cos q + Fc sign(qd) + Fv qd."""
    m, l, Izz_c, g, Fc, Fv = 2.0, 0.3, 0.05, 9.81, 0.4, 0.7
    params = [0.0, 0.0, Izz_c + m * l**2, 0.0, 0.0, 0.0, m, m * l, 0.0, 0.0, Fc, Fv]
    robot = sj.robots.from_mdh([0.0], [0.0], [0.0], params=params, gravity=(0.0, -g, 0.0))
    q = np.linspace(-3, 3, 7)
    qd = np.linspace(-1, 1.5, 7)
    qdd = np.linspace(2, -2, 7)
    tau = sj.inverse_dynamics(robot, robot.params, q[:, None], qd[:, None], qdd[:, None])[:, 0]
    expected = (Izz_c + m * l**2) * qdd + m * g * l * np.cos(q) + Fc * np.sign(qd) + Fv * qd
    np.testing.assert_allclose(tau, expected, rtol=1e-13, atol=1e-13)


def test_two_link_planar_closed_form():
    """Planar RR arm in the vertical plane with point masses at the link ends (textbook
    form, e.g. Spong, Hutchinson & Vidyasagar 2006, Sec. 7.3)."""
    l1, l2, m1, m2, g = 0.7, 0.5, 1.3, 0.9, 9.81
    # MDH: joint 2 sits at distance l1 along link 1's x; point masses at (l, 0, 0).
    params = np.zeros(24)
    for i, (m, l) in enumerate([(m1, l1), (m2, l2)]):
        params[12 * i: 12 * i + 10] = [0, m * l**2, m * l**2, 0, 0, 0, m, m * l, 0, 0]
    robot = sj.robots.from_mdh([0, 0], [0, l1], [0, 0], params=params, gravity=(0, -g, 0))
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.normal(size=(3, 2))
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    M = np.array([
        [m1 * l1**2 + m2 * (l1**2 + 2 * l1 * l2 * c2 + l2**2), m2 * (l1 * l2 * c2 + l2**2)],
        [m2 * (l1 * l2 * c2 + l2**2), m2 * l2**2],
    ])
    h = m2 * l1 * l2 * s2
    C = np.array([-h * (2 * qd[0] * qd[1] + qd[1] ** 2), h * qd[0] ** 2])
    G = np.array([(m1 + m2) * l1 * g * np.cos(q[0]) + m2 * l2 * g * np.cos(q[0] + q[1]),
                  m2 * l2 * g * np.cos(q[0] + q[1])])
    np.testing.assert_allclose(sj.inverse_dynamics(robot, params, q, qd, qdd), M @ qdd + C + G,
                               rtol=1e-12, atol=1e-12)


def test_kuka_urdf_matches_pinocchio():
    robot = sj.robots.kuka_lwr4()
    from importlib import resources

    path = resources.files("sedsabso_jax") / "data" / "kuka_lwr4" / "kuka_lwr4.urdf"
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, qd, qdd = random_state(rng, robot)
        tau = sj.inverse_dynamics(robot, robot.params, q, qd, qdd)
        expected = pin.rnea(model, data, q, qd, qdd) + friction_torque(robot.params, qd)
        np.testing.assert_allclose(tau, expected, rtol=1e-10, atol=1e-10)


def test_rs010n_matches_pinocchio():
    """The paper robot through pinocchio's own modified-DH composition."""
    robot = sj.robots.rs010n()
    table = {"alpha": [0, -np.pi / 2, 0], "a": [0, 0.35, 1.035], "d": [0, 0, 0],
             "theta": [0, 0, 0], "prismatic": [False] * 3}
    model = pin_from_mdh(table, np.asarray(robot.params))
    data = model.createData()
    rng = np.random.default_rng(3)
    q, qd, qdd = random_state(rng, robot, 5)
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    for k in range(5):
        np.testing.assert_allclose(tau[k], pin.rnea(model, data, q[k], qd[k], qdd[k]),
                                   rtol=1e-10, atol=1e-10)
