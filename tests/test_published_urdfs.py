"""Published URDFs, from the ``example-robot-data`` package (the arms it holds: UR3, UR5,
UR10, Panda, Kinova's Jaco, xArm7, Z1, SO-100, SO-101, TALOS's arm, TIAGo's arm, flying
arms, pendulums, a quadruped's leg) read as pinocchio reads them: inverse dynamics to
1e-12 of the largest torque at a few random states (the files' joint friction and damping
left out, which pinocchio's RNEA does not have), and every joint's limits. A joint without
position limits, continuous or with a ``<limit>`` that gives no range (pinocchio reads
lower = upper = 0), is read unbounded, with one warning naming the latter."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import random_state

import sedsabso_jax as sj

pin = pytest.importorskip("pinocchio")

#: (name, file under the package's robots/, tip link or None where the chain is one path)
ARMS = [
    ("UR3", "ur_description/urdf/ur3_robot.urdf", None),
    ("UR5", "ur_description/urdf/ur5_robot.urdf", None),
    ("UR5 limited", "ur_description/urdf/ur5_joint_limited_robot.urdf", None),
    ("UR10", "ur_description/urdf/ur10_robot.urdf", None),
    ("Panda", "panda_description/urdf/panda.urdf", "panda_hand"),  # fingers locked at 0
    ("Kinova", "kinova_description/robots/kinova.urdf", None),  # continuous joints
    ("xArm7", "xarm_description/urdf/xarm7.urdf", None),
    ("Z1", "z1_description/urdf/z1.urdf", None),
    ("SO-100", "so_arm_description/urdf/so100.urdf", None),
    ("SO-101", "so_arm_description/urdf/so101.urdf", None),
    ("TALOS arm", "talos_data/robots/talos_left_arm.urdf", None),
    ("TIAGo arm", "tiago_description/robots/tiago_no_hand.urdf", "arm_7_link"),  # prismatic
    ("flying arm 2", "borinot_description/urdf/borinot_flying_arm_2.urdf", None),
    ("flying arm 5", "hextilt_description/urdf/hextilt_flying_arm_5.urdf", None),
    ("two DOF", "asr_twodof_description/urdf/TwoDofs.urdf", None),
    ("double pendulum", "double_pendulum_description/urdf/double_pendulum.urdf", None),
    ("double pendulum simple",
     "double_pendulum_description/urdf/double_pendulum_simple.urdf", None),
    ("double pendulum continuous",
     "double_pendulum_description/urdf/double_pendulum_continuous.urdf", None),
    ("quadruped leg", "quadruped_description/urdf/quadruped.urdf", "FL_contact"),
]
NO_RANGE = "without a position range"



def _pin_state(model, joints, q, qd, qdd):
    """pinocchio's configuration, velocity and acceleration: the chain's joints at ``q,
    qd, qdd`` (a continuous joint's q as (cos, sin)), every other joint at rest at 0."""
    Q, V, A = pin.neutral(model), np.zeros(model.nv), np.zeros(model.nv)
    for j, joint in enumerate(joints):
        Q[joint.idx_q:joint.idx_q + joint.nq] = (
            [np.cos(q[j]), np.sin(q[j])] if joint.nq == 2 else q[j])
        V[joint.idx_v], A[joint.idx_v] = qd[j], qdd[j]
    return Q, V, A


def _pin_limits(model, joints) -> tuple[np.ndarray, ...]:
    """``(q_min, q_max, qd_max, tau_max, no range)`` as pinocchio reads the chain's joints;
    unbounded where continuous or lower = upper = 0 (``no range``: the latter)."""
    lower = np.array([model.lowerPositionLimit[j.idx_q] for j in joints])
    upper = np.array([model.upperPositionLimit[j.idx_q] for j in joints])
    continuous = np.array([j.nq == 2 for j in joints])
    no_range = ~continuous & (lower == 0) & (upper == 0)
    free = continuous | no_range | (np.abs(lower) > 1e300)
    velocity = np.array([model.velocityLimit[j.idx_v] for j in joints])
    effort = np.array([model.effortLimit[j.idx_v] for j in joints])
    return (np.where(free, -np.inf, lower), np.where(free, np.inf, upper),
            np.where(velocity > 0, velocity, np.inf), np.where(effort > 0, effort, np.nan),
            no_range)


@pytest.mark.parametrize("name, file, tip", ARMS, ids=[a[0] for a in ARMS])
def test_published_arm_reads_as_pinocchio_reads_it(name, file, tip, robots_dir, rng):
    path = robots_dir / file
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = sj.robots.from_urdf(path, tip=tip)
        limits = sj.joint_limits_from_urdf(path, robot)
    model = pin.buildModelFromUrdf(str(path))
    joints = [model.joints[model.getJointId(j)] for j in robot.joint_names]
    params = np.asarray(robot.params).copy()
    params[10::12] = params[11::12] = 0.0  # the files' friction and damping: not pinocchio's
    q, qd, qdd = random_state(rng, robot, 3)
    tau = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd))
    for k in range(3):
        expected = pin.rnea(model, model.createData(), *_pin_state(model, joints, q[k],
                                                                   qd[k], qdd[k]))
        expected = expected[[j.idx_v for j in joints]]
        error = np.abs(tau[k] - expected).max() / np.abs(expected).max()
        assert error < 1e-12, f"{name}: torques differ from pinocchio's by {error:.1e}"
    q_min, q_max, qd_max, tau_max, no_range = _pin_limits(model, joints)
    for ours, theirs in ((limits.q_min, q_min), (limits.q_max, q_max),
                         (limits.qd_max, qd_max), (limits.tau_max, tau_max)):
        np.testing.assert_array_equal(ours, theirs)
    named = [str(w.message) for w in caught if NO_RANGE in str(w.message)]
    unbounded = [j for j, free in zip(robot.joint_names, no_range) if free]
    assert len(named) == bool(unbounded), f"{name}: expected one warning naming {unbounded}"
    assert not unbounded or f"joints {unbounded} have" in named[0], named
