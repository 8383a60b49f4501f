"""The mass matrix, forward dynamics and rollouts against MuJoCo, built from one URDF
(MuJoCo compiles the text itself; the package reads it with ``robots.from_urdf``)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import random_urdf

import sedsabso_jax as sj
from sedsabso_jax.dynamics import end_errors, forward_dynamics, mass_matrix, rollout, windows

mujoco = pytest.importorskip("mujoco")

DT, STEPS = 0.002, 100


def models(rng, tmp_path, n, *, fixed_prob=0.3):
    """``(robot, mujoco model, armature)`` of one random URDF: viscous friction (MuJoCo's
    damping, the robot's Fv) and armature on; Coulomb friction off in both (the robot's
    Fc zeroed, MuJoCo's frictionloss zeroed) and MuJoCo's constraints (joint limits) off."""
    text, _ = random_urdf(rng, n, fixed_prob=fixed_prob, friction=True)
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    robot = sj.robots.from_urdf(path)
    p = np.asarray(robot.params).reshape(-1, 12).copy()
    p[:, 10] = 0.0
    robot = robot.with_params(p.ravel())
    m = mujoco.MjModel.from_xml_string(text)
    assert [m.joint(i).name for i in range(m.njnt)] == list(robot.joint_names)
    assert m.nv == n
    np.testing.assert_allclose(m.dof_damping, p[:, 11], rtol=1e-12)
    armature = rng.uniform(0.01, 0.5, n)
    m.dof_armature[:] = armature
    m.dof_frictionloss[:] = 0.0
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    return robot, m, armature


def mujoco_rollout(m, q0, qd0, tau, integrator):
    m.opt.timestep = DT
    if integrator == "rk4":
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    elif integrator == "implicit":  # velocity derivatives implicit, Coriolis' too
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICIT
    else:
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_EULERDAMP
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = q0, qd0
    qs, qds = [d.qpos.copy()], [d.qvel.copy()]
    for tau_k in tau:
        d.qfrc_applied[:] = tau_k
        mujoco.mj_step(m, d)
        qs.append(d.qpos.copy())
        qds.append(d.qvel.copy())
    return np.array(qs), np.array(qds)


def full_matrix(m, d, out):
    """``mj_fullM``: ``(m, d, out)`` since MuJoCo 3.4's sparse ``d.M``, ``(m, out, d.qM)``
    before."""
    if hasattr(d, "qM"):
        mujoco.mj_fullM(m, out, d.qM)
    else:
        mujoco.mj_fullM(m, d, out)


def close(actual, expected, rel=1e-9):
    actual, expected = np.asarray(actual), np.asarray(expected)
    assert actual.shape == expected.shape
    err = np.max(np.abs(actual - expected)) / max(1.0, np.max(np.abs(expected)))
    assert err < rel, f"relative error {err:.3g}"


def test_mass_matrix_and_accelerations_equal_mujoco(rng, tmp_path):
    n = 5
    robot, m, armature = models(rng, tmp_path, n, fixed_prob=0.5)
    d = mujoco.MjData(m)
    q, qd, tau = rng.uniform(-2, 2, (3, n)), rng.standard_normal((3, n)), \
        rng.standard_normal((3, n)) * 5
    M_ours = mass_matrix(robot, None, q, armature=armature)
    qdd_ours = forward_dynamics(robot, None, q, qd, tau, armature=armature)
    assert M_ours.shape == (3, n, n) and qdd_ours.shape == (3, n)
    for k in range(3):
        d.qpos[:], d.qvel[:], d.qfrc_applied[:] = q[k], qd[k], tau[k]
        mujoco.mj_forward(m, d)
        M = np.zeros((n, n))
        full_matrix(m, d, M)
        close(M_ours[k], M)
        close(qdd_ours[k], d.qacc)
    # extra is part of the model's inverse dynamics: tau = M qdd + h + extra
    offset = jnp.arange(n) * 0.3 - 0.5
    close(forward_dynamics(robot, None, q, qd, tau + offset, armature=armature,
                           extra=lambda q, qd: offset), qdd_ours, 1e-12)
    # without armature: MuJoCo's matrix less its armature
    close(mass_matrix(robot, robot.params, q)[-1], M - np.diag(armature))


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    """One random 4-joint robot shared by the rollout tests (one compilation each)."""
    rng = np.random.default_rng(44)
    robot, m, armature = models(rng, tmp_path_factory.mktemp("chain"), 4)
    q0, qd0 = rng.uniform(-1, 1, 4), rng.standard_normal(4)
    tau = rng.standard_normal((STEPS, 4)) * 3  # a new torque every step, held over it
    return robot, m, armature, q0, qd0, tau


@pytest.mark.parametrize("integrator", ["rk4", "euler", "implicit"])
def test_rollout_equals_mujoco(chain, integrator):
    robot, m, armature, q0, qd0, tau = chain
    q, qd = rollout(robot, None, q0, qd0, tau, DT, armature=armature, integrator=integrator)
    q_mj, qd_mj = mujoco_rollout(m, q0, qd0, tau, integrator)
    assert q.shape == qd.shape == (STEPS + 1, 4)
    assert np.max(np.abs(q_mj[-1] - q0)) > 1e-2  # it moved
    close(q, q_mj)
    close(qd, qd_mj)


def test_integrator_order(chain):
    """Over 0.4 s, halving the step (two substeps of each 4 ms step) cuts RK4's error ~16x
    and semi-implicit Euler's ~2x (against RK4 with 32 substeps)."""
    robot, _, armature, q0, qd0, tau = chain

    def end(integrator, substeps):
        q, _ = rollout(robot, None, q0, qd0, tau, 0.004, armature=armature,
                       integrator=integrator, substeps=substeps)
        return np.asarray(q[-1])

    reference = end("rk4", 32)
    for integrator, order in (("rk4", 4), ("euler", 1)):
        e1, e2 = (np.max(np.abs(end(integrator, s) - reference)) for s in (1, 2))
        assert 0.7 * 2**order < e1 / e2 < 1.4 * 2**order, (integrator, e1 / e2)


def test_windows_batched_and_end_errors(chain):
    """A recording made by the model itself, cut into overlapping windows and simulated
    all at once, reproduces every window exactly; the same as the windows one by one."""
    robot, _, armature, q0, qd0, tau = chain
    q_rec, qd_rec = rollout(robot, None, q0, qd0, tau, DT, armature=armature)
    q_rec, qd_rec = np.asarray(q_rec[:-1]), np.asarray(qd_rec[:-1])  # T = STEPS samples
    q0w, qd0w, tauw, qw = windows(q_rec, qd_rec, tau, DT, 0.04, stride=0.03)
    starts = np.arange(0, STEPS - 20, 15)
    assert q0w.shape == (len(starts), 4) and tauw.shape == (len(starts), 20, 4)
    assert qw.shape == (len(starts), 21, 4)
    np.testing.assert_array_equal(tauw[1], tau[15:35])
    np.testing.assert_array_equal(qw[2], q_rec[30:51])
    q, _ = rollout(robot, None, q0w, qd0w, tauw, DT, armature=armature)
    close(q, qw, 1e-10)
    # every window at once equals the windows one by one
    for k in (0, len(starts) - 1):
        q_k, _ = rollout(robot, None, q0w[k:k + 1], qd0w[k:k + 1], tauw[k:k + 1], DT,
                         armature=armature)
        close(q[k], q_k[0], 1e-12)
    err = end_errors(robot, q, qw)
    assert err.shape == (len(starts), 4) and np.max(err) < 1e-8
    shifted = qw.at[:, -1].add(np.pi / 180)
    deg = [1.0 if t == "revolute" else np.pi / 180 for t in robot.joint_types]
    np.testing.assert_allclose(end_errors(robot, qw, shifted), np.broadcast_to(deg, err.shape),
                               rtol=1e-9)


def test_bad_shapes_and_options(chain):
    robot, _, armature, q0, qd0, tau = chain
    with pytest.raises(ValueError, match="tau must have shape"):
        rollout(robot, None, q0, qd0, tau[:, :3], DT)
    with pytest.raises(ValueError, match="tau must have shape"):
        rollout(robot, None, q0, qd0, tau[0], DT)
    with pytest.raises(ValueError, match="integrator"):
        rollout(robot, None, q0, qd0, tau, DT, integrator="rk45")
    with pytest.raises(ValueError, match="armature"):
        mass_matrix(robot, None, q0, armature=np.ones(3))
    with pytest.raises(ValueError, match="params must have shape"):
        forward_dynamics(robot, np.ones(5), q0, qd0, tau[0])
    with pytest.raises(ValueError, match="no window"):
        windows(np.zeros((10, 4)), np.zeros((10, 4)), np.zeros((10, 4)), DT, 0.1)
