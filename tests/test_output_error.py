"""The output-error refinement (identification by simulation error) on a simulated plant,
started from a wrong model (one link 30 % heavier, every viscous friction 1.5 times the
plant's): the refinement, which sees positions and torques only, must bring the model back,
keep every body physical, and give a model that MuJoCo simulates as the package does."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import random_urdf

import sedsabso_jax as sj
from sedsabso_jax.dynamics._inertia import pseudo_inertia
from sedsabso_jax.identification import (
    OutputError,
    Refined,
    mujoco_torques,
    refine,
    rollout_errors,
)
from sedsabso_jax.identification._fit._output_error import _cholesky_params, _inertial

RATE, SECONDS = 500.0, 6.0


def motion(n, phase, seconds=SECONDS):
    """Smooth joint motions (two harmonics each) and their exact derivatives."""
    t = np.arange(int(seconds * RATE)) / RATE
    w = 2 * np.pi * np.array([0.4, 0.9])
    amp = 0.5 * np.array([1.0, 0.4])
    arg = w[None, :, None] * t[:, None, None] + phase + np.arange(n)[None, None, :]
    q = (amp[None, :, None] * np.sin(arg)).sum(1)
    qd = (amp[None, :, None] * w[None, :, None] * np.cos(arg)).sum(1)
    qdd = -(amp[None, :, None] * w[None, :, None] ** 2 * np.sin(arg)).sum(1)
    return t, q, qd, qdd


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    """A random 3-joint arm, its torques along two motions (exact inverse dynamics plus
    0.3 N m offsets), and its exact physical fit made wrong."""
    rng = np.random.default_rng(7)
    text, _ = random_urdf(rng, 3, prismatic_prob=0.0, fixed_prob=0.0, friction=True)
    path = tmp_path_factory.mktemp("oe") / "arm.urdf"
    path.write_text(text)
    robot = sj.robots.from_urdf(path)
    p = np.asarray(robot.params).reshape(-1, 12).copy()
    p[:, 10] = 0.0  # viscous friction only: the plant needs no sticking
    robot = robot.with_params(p.ravel())
    data = []
    for phase in (0.0, 1.3):
        t, q, qd, qdd = motion(3, phase)
        tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd)) + 0.3
        data.append(sj.Measurements(t, q, qd, qdd, tau))
    exact = sj.identify(robot, data[0], sj.PhysicallyConsistent(sj.OLS()),
                        sj.TorqueModel.of(robot, (sj.Offset(),)))
    wrong = np.asarray(exact.full_params).reshape(-1, 12).copy()
    wrong[1, :10] *= 1.3  # a heavier body: still a physical one
    wrong[:, 11] *= 1.5
    return robot, data, dataclasses.replace(exact, full_params=wrong.ravel())


def test_cholesky_parameters_round_trip_and_stay_physical():
    rng = np.random.default_rng(0)
    robot = sj.robots.kuka_lwr4()
    p = np.asarray(robot.params).reshape(-1, 12)
    theta = _cholesky_params(p)
    np.testing.assert_allclose(np.asarray(_inertial(theta)), p[:, :10], atol=1e-14)
    # any value of the searched numbers is a physical body
    J = pseudo_inertia(np.asarray(_inertial(rng.normal(size=(50, 10)))))
    assert np.linalg.eigvalsh(J).min() > 0


@pytest.fixture(scope="module")
def refined(plant):
    """The wrong fit refined on positions alone, a few steps."""
    robot, (train, _), fit = plant
    return refine(fit, train, OutputError(length=0.2, windows=8, steps=4, torque_weight=0.0))


def test_refinement_undoes_a_biased_fit(plant, refined):
    robot, (train, held_out), fit = plant
    assert isinstance(refined, Refined) and refined.steps >= 1
    assert refined.cost[1] < 0.1 * refined.cost[0], refined.cost
    assert np.linalg.eigvalsh(pseudo_inertia(refined.params.reshape(-1, 12)[:, :10])
                              ).min() > 0
    before = rollout_errors(fit, held_out, lengths=(0.5,), count=16).own
    after = rollout_errors(refined, held_out, lengths=(0.5,), count=16).own
    assert np.median(after) < 0.5 * np.median(before), (np.median(before), np.median(after))
    # the torques of a new motion: closer to the plant's than the start's
    start = dataclasses.replace(refined, params=refined.start[0], armature=refined.start[1],
                                offset=refined.start[2])
    err = {name: np.sqrt(np.mean((m.predict(held_out.q, held_out.qd, held_out.qdd)
                                  - held_out.tau) ** 2))
           for name, m in (("start", start), ("refined", refined))}
    assert err["refined"] < 0.5 * err["start"], err


def test_refined_model_in_mujoco_matches_its_own_torques(plant, refined):
    pytest.importorskip("mujoco")
    robot, (train, _), fit = plant
    q, qd, qdd = train.q[::50], train.qd[::50], train.qdd[::50]
    # the torques as measured (the actuators' ctrl, offsets included), at speed (MuJoCo's
    # dry friction a soft constraint, the package's tanh(qd / 1e-3): equal away from rest)
    moving = np.all(np.abs(qd) > 0.05, axis=1)
    q, qd, qdd = q[moving], qd[moving], qdd[moving]
    np.testing.assert_allclose(mujoco_torques(refined.mjcf(), q, qd, qdd),
                               refined.predict(q, qd, qdd), atol=1e-6)


def test_refine_rejects_bad_options(plant):
    robot, (train, _), fit = plant
    with pytest.raises(ValueError, match="windows must be a positive integer"):
        OutputError(windows=0)
    with pytest.raises(ValueError, match="give limits"):
        refine(fit, train, OutputError(torque_weight=1.0))
    with pytest.raises(TypeError, match="OutputError"):
        refine(fit, train, "lm")
    with pytest.raises(ValueError, match="limits must be positive"):
        refine(fit, train, OutputError(torque_weight=1.0), limits=[1.0, 2.0])
    with pytest.raises(TypeError, match="one Measurements"):
        refine(fit, [train, train])
    ols = sj.identify(robot, train)
    with pytest.raises(ValueError, match="physically consistent"):
        refine(ols, train)


def test_the_mjcf_names_the_refinement_and_what_mujoco_cannot_hold(plant, refined):
    pytest.importorskip("mujoco")
    robot, (train, _), fit = plant
    xml = refined.mjcf()
    assert "refined by simulation error (8 windows of 0.2 s" in xml
    assert "every part of the refined model is held" in xml
    smooth = dataclasses.replace(refined, model=sj.TorqueModel.of(robot, (sj.SmoothCoulomb(),)))
    assert "the Coulomb friction's smooth shape" in smooth.mjcf()
