"""Bad input gets a clear error naming what is wrong and what was expected."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import random_urdf

import sedsabso_jax as sj
from sedsabso_jax.dynamics._urdf import URDFError

ONE_JOINT = """<robot name="r"><link name="a"/><link name="b"/>
<joint name="j" type="{kind}"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


def write(tmp_path, text, name="r.urdf"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_missing_urdf(tmp_path):
    with pytest.raises(URDFError, match=r"cannot read URDF .*nope\.urdf"):
        sj.robots.from_urdf(tmp_path / "nope.urdf")


@pytest.mark.parametrize("text,match", [
    ("", "is empty"),
    ("<robot name='r'><link name='a'>", "not well-formed XML"),
    ("<notarobot/>", r"root element is <notarobot>, expected <robot>"),
    (ONE_JOINT.format(kind="floating"), "joint 'j' has type 'floating'; supported"),
    (ONE_JOINT.format(kind="planar"), "type 'planar'"),
    (ONE_JOINT.format(kind="fixed"), "no movable joint"),
    ("<robot name='r'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
     "<child link='zz'/></joint></robot>", "refers to missing link 'zz'"),
])
def test_malformed_urdf(tmp_path, text, match):
    with pytest.raises(URDFError, match=match):
        sj.robots.from_urdf(write(tmp_path, text))


def test_truncated_kuka_urdf(tmp_path):
    from importlib import resources

    text = (resources.files("sedsabso_jax") / "data/kuka_lwr4/kuka_lwr4.urdf").read_text()
    with pytest.raises(URDFError, match="not well-formed XML"):
        sj.robots.from_urdf(write(tmp_path, text[: len(text) // 2]))


def test_the_shipped_urdfs_read_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for robot in ("kuka_lwr4", "staubli_tx40"):
            sj.robots.load(robot)
            sj.dynamics.joint_limits(robot, sj.robots.load(robot))


def test_a_repeated_element_is_warned_of_and_the_first_kept(tmp_path):
    """A user's URDF that repeats an ``<origin>`` (as the KUKA file once did): the parser's
    note as a warning; the first element counts, as in pinocchio (urdfdom)."""
    text = ONE_JOINT.format(kind="revolute").replace(
        "<axis", '<origin xyz="0 0 1"/><origin xyz="5 5 5"/><axis')
    with pytest.warns(UserWarning, match="Scalar element defined multiple times: origin"):
        robot = sj.robots.from_urdf(write(tmp_path, text))
    np.testing.assert_array_equal(np.asarray(robot.T_fixed)[0, :3, 3], [0, 0, 1])


def test_entities_are_refused_not_expanded(tmp_path):
    secret = write(tmp_path, "SECRET", "secret.txt")
    text = (f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x SYSTEM "file://{secret}">]>'
            '<robot name="&x;"><link name="a"/></robot>')
    with pytest.raises(URDFError, match="DOCTYPE"):
        sj.robots.from_urdf(write(tmp_path, text))


def test_branching_tree_needs_tip(tmp_path):
    rng = np.random.default_rng(0)
    text, links = random_urdf(rng, 3, fixed_prob=0.0, branch=True)
    path = write(tmp_path, text)
    with pytest.raises(URDFError, match=r"branches at link 'link1'.*choose the tip link \(--tip"):
        sj.robots.from_urdf(path)
    with pytest.warns(UserWarning, match=r"locked at 0"):
        robot = sj.robots.from_urdf(path, tip="tool")
    assert robot.joint_names == ("j1", "j2", "j3")
    with pytest.warns(UserWarning, match=r"\['j2', 'j3'\] are off the chain"):
        side = sj.robots.from_urdf(path, tip="side2")
    assert side.joint_names == ("j1", "side_j1", "side_j2")
    with pytest.raises(URDFError, match="has no link 'hand'"):
        sj.robots.from_urdf(path, tip="hand")


def test_locked_branch_is_carried_rigidly(tmp_path):
    """A side chain locked at 0 weighs on the path: same torques as pinocchio's model of
    the whole tree with the side joints held at 0."""
    import pinocchio as pin

    rng = np.random.default_rng(1)
    text, _ = random_urdf(rng, 3, fixed_prob=0.0, branch=True)
    with pytest.warns(UserWarning):
        robot = sj.robots.from_urdf(write(tmp_path, text), tip="tool")
    model = pin.buildModelFromXML(text)
    data = model.createData()
    names = [model.names[i] for i in range(1, model.njoints)]
    q, qd, qdd = rng.normal(size=(3, 3))
    full = {k: np.zeros(model.nv) for k in ("q", "qd", "qdd")}
    for i, jn in enumerate(robot.joint_names):
        k = names.index(jn)
        full["q"][k], full["qd"][k], full["qdd"][k] = q[i], qd[i], qdd[i]
    tau_pin = pin.rnea(model, data, full["q"], full["qd"], full["qdd"])
    idx = [names.index(jn) for jn in robot.joint_names]
    np.testing.assert_allclose(sj.inverse_dynamics(robot, robot.params, q, qd, qdd),
                               tau_pin[idx], rtol=1e-10, atol=1e-10)


def test_zero_axis(tmp_path):
    text = ONE_JOINT.format(kind="revolute").replace('xyz="0 0 1"', 'xyz="0 0 0"')
    with pytest.raises(URDFError, match="zero axis"):
        sj.robots.from_urdf(write(tmp_path, text))


@pytest.mark.parametrize("shapes,match", [
    (((2,), (3,), (3,)),
     r"q must have shape \(\.\.\., 3\) for robot 'RS010N' with 3 joints, got shape \(2,\)"),
    (((3,), (4,), (3,)), r"qd must have shape \(\.\.\., 3\)"),
    (((3,), (3,), ()), r"qdd must have shape \(\.\.\., 3\).*got shape \(\)"),
    (((5, 3), (4, 3), (3,)), r"batch shapes do not broadcast: q \(5, 3\), qd \(4, 3\)"),
])
def test_joint_array_shapes(shapes, match):
    robot = sj.robots.rs010n()
    arrays = [np.zeros(s) for s in shapes]
    with pytest.raises(ValueError, match=match):
        sj.regressor(robot, *arrays)
    with pytest.raises(ValueError, match=match):
        sj.inverse_dynamics(robot, robot.params, *arrays)


def test_non_numeric_joint_array():
    with pytest.raises(TypeError, match="q must be a numeric array"):
        sj.regressor(sj.robots.rs010n(), "abc", np.zeros(3), np.zeros(3))


def test_parameter_shapes():
    robot = sj.robots.rs010n()
    z = np.zeros(3)
    with pytest.raises(ValueError, match=r"params must have shape \(36,\).*got \(35,\)"):
        sj.inverse_dynamics(robot, np.zeros(35), z, z, z)
    with pytest.raises(ValueError, match=r"params must have shape \(36,\), got \(12,\)"):
        robot.with_params(np.zeros(12))
    with pytest.raises(ValueError, match=r"params must have shape \(\.\.\., 36\)"):
        sj.base_parameters(robot).project(np.zeros(30))


def test_dh_tables():
    with pytest.raises(ValueError, match="one entry per joint"):
        sj.robots.from_mdh([0, 0], [0, 1, 2], [0, 0])
    with pytest.raises(ValueError, match="NaN or Inf"):
        sj.robots.from_dh([0, np.nan], [0, 0], [0, 0])
    with pytest.raises(ValueError, match="one flag per joint"):
        sj.robots.from_mdh([0, 0], [0, 1], [0, 0], prismatic=[True])
    with pytest.raises(ValueError, match=r"params must have shape \(24,\)"):
        sj.robots.from_mdh([0, 0], [0, 1], [0, 0], params=np.zeros(36))


def test_robot_fields():
    eye = np.eye(4)[None]
    with pytest.raises(ValueError, match="unsupported joint type 'spherical'"):
        sj.Robot(eye, [[0, 0, 1, 0, 0, 0]], ["spherical"])
    with pytest.raises(ValueError, match="must be a unit vector"):
        sj.Robot(eye, [[0, 0, 2, 0, 0, 0]], ["revolute"])
    with pytest.raises(ValueError, match="prismatic screw must have omega = 0"):
        sj.Robot(eye, [[0, 0, 1, 0, 0, 1]], ["prismatic"])
    bad = eye.copy()
    bad[0, 0, 0] = 2.0
    with pytest.raises(ValueError, match="not a rigid transform"):
        sj.Robot(bad, [[0, 0, 1, 0, 0, 0]], ["revolute"])
    with pytest.raises(ValueError, match=r"gravity must have shape \(3,\)"):
        sj.Robot(eye, [[0, 0, 1, 0, 0, 0]], ["revolute"], gravity=[0, -9.81])
