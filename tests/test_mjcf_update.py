"""Identified parameters written into the robot's own MJCF
(:func:`sedsabso_jax.dynamics.update_mjcf`): MuJoCo's ``mj_inverse`` of the updated file
equals the package's inverse dynamics with the new parameters (plus armature) to 1e-9, for
a random chain with welded bodies, joint ``ref``s, a jointed side body off the chain, geoms,
comments and actuators (all kept), and for the Panda imported by MuJoCo; from_mjcf reads
the new parameters back. Mismatched robots and non-physical parameters are refused."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import mj_torques, random_inertial, random_mjcf

import sedsabso_jax as sj
from sedsabso_jax.dynamics import update_mjcf

mujoco = pytest.importorskip("mujoco")
TOL = 1e-9


def _model(path):
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)  # frictionloss
    return m



def assert_close(tau, expected, tol=TOL):
    tau, expected = np.asarray(tau), np.asarray(expected)
    assert np.max(np.abs(tau - expected)) <= tol * np.max(np.abs(expected)), (tau, expected)


def new_params(rng, n):
    """Physically consistent parameters, origin-referenced, with friction."""
    out = []
    for _ in range(n):
        m, c, I = random_inertial(rng)
        I_o = I + m * (c @ c * np.eye(3) - np.outer(c, c))
        out += [I_o[0, 0], I_o[1, 1], I_o[2, 2], I_o[0, 1], I_o[0, 2], I_o[1, 2], m,
                *(m * c), *rng.uniform(0.1, 1, 2)]
    return np.array(out)


def read(path, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the side joint, locked; armature
        return sj.robots.from_mjcf(path, **kwargs)


def decorated(rng, n):
    """random_mjcf with refs, geoms, a comment and a jointed side body on link1."""
    text = random_mjcf(rng, n, damping=True, armature=True, fixed_prob=0.6)
    for i in range(n):
        text = text.replace(f'<joint name="j{i + 1}" ', f'<joint name="j{i + 1}" '
                            f'ref="{0.1 * (i + 1)!r}" ')
    text = text.replace("<inertial ", '<geom size="0.03" mass="0.2"/><inertial ')
    text = text.replace('<joint name="j1" ', '<body name="side" pos="0.1 0 0.05">'
                        '<joint name="js" axis="1 0 0"/><geom size="0.02"/>'
                        '<inertial pos="0.1 0 0" mass="0.7" diaginertia="0.01 0.02 0.02"/>'
                        '<body name="side_tip" pos="0.2 0 0"><geom size="0.02"/></body>'
                        '</body><joint name="j1" ', 1)
    return text.replace("<worldbody>", "<!-- kept comment --><worldbody>", 1)


@pytest.mark.parametrize("seed,n", [(1, 4), (2, 6)])
def test_random_chain_updated_equals_mj_inverse(tmp_path, seed, n):
    rng = np.random.default_rng(seed)
    source = tmp_path / "arm.xml"
    source.write_text(decorated(rng, n))
    robot = read(source, tip=f"link{n}")
    assert robot.joint_names == tuple(f"j{i + 1}" for i in range(n))
    assert any(b.startswith("fixed_") for b in _names(_model(source), "body"))  # welded
    new = new_params(rng, n)
    armature = rng.uniform(0.01, 0.2, n)
    text = update_mjcf(source, robot, new, armature=armature, comment="identified -- test")
    out = tmp_path / "arm_identified.xml"
    out.write_text(text)
    m, m0 = _model(out), _model(source)
    q, qd, qdd = rng.uniform(-2.0, 2.0, (3, 4, n))
    expected = sj.inverse_dynamics(robot.with_params(new), new, q, qd, qdd)
    no_coulomb = new.reshape(n, 12).copy()
    no_coulomb[:, 10] = 0.0  # frictionloss is a constraint, off in mj_inverse
    assert_close(mj_torques(m, robot, q, qd, qdd),
                 sj.inverse_dynamics(robot, no_coulomb.ravel(), q, qd, qdd) + armature * qdd)
    # read back: the new parameters, friction included
    again = read(out, tip=f"link{n}")
    assert again.joint_names == robot.joint_names and again.link_names == robot.link_names
    assert_close(sj.inverse_dynamics(again, again.params, q, qd, qdd), expected)
    np.testing.assert_allclose(sj.robots.armature_from_mjcf(out, again), armature, rtol=1e-15)
    dofs = [m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)]
            for j in robot.joint_names]
    np.testing.assert_allclose(m.dof_solimp[dofs, :3], [[0.999, 0.999, 0.001]] * n)
    # everything else kept
    for kind in ("geom", "actuator", "body", "joint"):
        assert _names(m, kind) == _names(m0, kind)
    assert "<!-- kept comment -->" in text and "<!-- identified - - test -->" in text
    np.testing.assert_array_equal(m.geom_size, m0.geom_size)
    np.testing.assert_array_equal(m.qpos0, m0.qpos0)  # the refs
    assert np.count_nonzero(m.qpos0) == n


def _names(m, kind):
    count = getattr(m, {"geom": "ngeom", "actuator": "nu", "body": "nbody",
                        "joint": "njnt"}[kind])
    obj = getattr(mujoco.mjtObj, f"mjOBJ_{kind.upper()}")
    return [mujoco.mj_id2name(m, obj, i) for i in range(count)]


MUJOCO_TAG = '<mujoco><compiler fusestatic="false" discardvisual="true"/></mujoco>'


def test_panda_through_mujoco(tmp_path, robots_dir):
    from lxml import etree

    root = etree.parse(str(robots_dir / "panda_description/urdf/panda.urdf")).getroot()
    for element in list(root.iter("visual", "collision")):
        element.getparent().remove(element)
    root.insert(0, etree.fromstring(MUJOCO_TAG))
    urdf = tmp_path / "for_mujoco.urdf"
    urdf.write_bytes(etree.tostring(root))
    source = tmp_path / "panda.xml"
    mujoco.mj_saveLastXML(str(source), mujoco.MjModel.from_xml_path(str(urdf)))
    robot = read(source, tip="panda_hand")
    n = robot.n_joints
    rng = np.random.default_rng(3)
    new = new_params(rng, n)
    out = tmp_path / "panda_identified.xml"
    out.write_text(update_mjcf(source, robot, new))
    q, qd, qdd = rng.uniform(-2.0, 2.0, (3, 3, n))
    no_coulomb = new.reshape(n, 12).copy()
    no_coulomb[:, 10] = 0.0
    assert_close(mj_torques(_model(out), robot, q, qd, qdd),
                 sj.inverse_dynamics(robot, no_coulomb.ravel(), q, qd, qdd))
    again = read(out, tip="panda_hand")
    np.testing.assert_allclose(again.params, new, rtol=1e-12, atol=1e-12)


def test_errors(tmp_path):
    rng = np.random.default_rng(4)
    source = tmp_path / "arm.xml"
    source.write_text(random_mjcf(rng, 3, damping=True, fixed_prob=0.0))
    robot = read(source)
    other = tmp_path / "other.xml"
    other.write_text(random_mjcf(rng, 3, fixed_prob=0.0).replace('name="j2"', 'name="jx"')
                     .replace('joint="j2"', 'joint="jx"'))
    with pytest.raises(ValueError, match=r"other\.xml.*does not match robot 'random'.*'j2'"):
        update_mjcf(other, robot)
    short = read(tmp_path / "arm.xml", tip="link2")
    cut = sj.Robot(short.T_fixed[1:], short.screws[1:], short.joint_types[1:],
                   short.params[12:], joint_names=short.joint_names[1:],
                   link_names=short.link_names[1:])
    with pytest.raises(ValueError, match=r"movable bodies .* are \['link1', 'link2'\], the "
                                         r"robot's links \['link2'\]"):
        update_mjcf(source, cut)
    bad = np.asarray(robot.params).copy()
    bad[6] = -1.0  # a negative mass
    with pytest.raises(ValueError, match="physically consistent"):
        update_mjcf(source, robot, bad)
    with pytest.raises(ValueError, match="armature must be >= 0"):
        update_mjcf(source, robot, armature=[-1.0, 0.0, 0.0])
