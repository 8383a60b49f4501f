"""MuJoCo MJCF in (:func:`sedsabso_jax.robots.from_mjcf`): the robot read from a file
gives MuJoCo's own inverse dynamics (``mj_inverse``) to 1e-9 of the largest torque, for
random serial MJCF chains (tests/conftest.py's ``random_mjcf``: hinge and slide joints at
random axes and anchors, welded bodies, random inertials and gravity, damping), with the
armature added from :func:`~sedsabso_jax.robots.armature_from_mjcf`, and for
manufacturers' URDFs that MuJoCo imports and saves as MJCF, where it also equals
:func:`~sedsabso_jax.robots.from_urdf` of the same file. Branches, ``ref``, the joint
limits, the errors and ``--robot arm.xml`` on the command line.

MuJoCo's ``frictionloss`` is a constraint, not a force ``mj_inverse`` adds with the
constraints off: it is checked as read (``Fc``), not against MuJoCo's torques."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import mj_torques, random_mjcf

import sedsabso_jax as sj
from sedsabso_jax.dynamics import MJCFError

mujoco = pytest.importorskip("mujoco")
TOL = 1e-9


def _model(path):
    m = mujoco.MjModel.from_xml_path(str(path))
    # joint limits and frictionloss are constraints: leave them out of mj_inverse
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    return m



def states(rng, n, k=3):
    return rng.uniform(-2.0, 2.0, (3, k, n))


def assert_close(tau, expected, tol=TOL):
    tau, expected = np.asarray(tau), np.asarray(expected)
    assert np.max(np.abs(tau - expected)) <= tol * np.max(np.abs(expected)), (tau, expected)


def write(tmp_path, text, name="arm.xml"):
    path = tmp_path / name
    path.write_text(text)
    return path


# ----------------------------------------------------------------- random serial chains
@pytest.mark.parametrize("seed,n", [(1, 4), (2, 7)])
def test_random_chain_equals_mj_inverse(tmp_path, seed, n):
    rng = np.random.default_rng(seed)
    path = write(tmp_path, random_mjcf(rng, n, damping=True, fixed_prob=0.5))
    robot = sj.robots.from_mjcf(path)
    m = _model(path)
    assert robot.n_joints == n and robot.name == "random"
    assert robot.joint_names == tuple(f"j{i + 1}" for i in range(n))
    assert robot.link_names == tuple(f"link{i + 1}" for i in range(n))
    np.testing.assert_array_equal(robot.gravity, m.opt.gravity)
    np.testing.assert_allclose(np.asarray(robot.params).reshape(n, 12)[:, 11], m.dof_damping)
    q, qd, qdd = states(rng, n)
    assert_close(sj.inverse_dynamics(robot, robot.params, q, qd, qdd),
                 mj_torques(m, robot, q, qd, qdd))


def test_armature_is_added_by_armature_from_mjcf(tmp_path):
    rng = np.random.default_rng(4)
    text = random_mjcf(rng, 5, damping=True, armature=True)
    rotor = hasattr(mujoco.MjModel, "actuator_armature")  # MuJoCo >= 4: an actuator's too
    if rotor:
        text = text.replace('joint="j2" gear="1"/>', 'joint="j2" gear="3" armature="0.05"/>')
    path = write(tmp_path, text)
    with pytest.warns(UserWarning, match=r"have an armature.*armature_from_mjcf"):
        robot = sj.robots.from_mjcf(path)
    m = _model(path)
    armature = sj.robots.armature_from_mjcf(path, robot)
    np.testing.assert_allclose(armature, m.dof_armature + [0, 9 * 0.05 * rotor, 0, 0, 0],
                               rtol=1e-15)
    q, qd, qdd = states(rng, 5)
    assert_close(sj.inverse_dynamics(robot, robot.params, q, qd, qdd) + armature * qdd,
                 mj_torques(m, robot, q, qd, qdd))


def test_frictionloss_is_coulomb_friction(tmp_path):
    rng = np.random.default_rng(5)
    path = write(tmp_path, random_mjcf(rng, 3, damping=True, frictionloss=True))
    robot = sj.robots.from_mjcf(path, name="mine")
    m = _model(path)
    p = np.asarray(robot.params).reshape(3, 12)
    np.testing.assert_array_equal(p[:, 10], m.dof_frictionloss)
    np.testing.assert_array_equal(p[:, 11], m.dof_damping)
    assert robot.name == "mine"


# A branching arm: a hinge with a ref (q = 0 is qpos = 0), a welded plate and a side arm
# (its hinge locked at 0) off the chain, a free object on the world, limits and actuators.
BRANCHED = """<mujoco model="branched">
  <compiler angle="degree" autolimits="true"/>
  <option gravity="0.5 -1 -9.7"/>
  <worldbody>
    <body name="box" pos="2 0 0"><freejoint/><geom size="0.1" mass="3"/></body>
    <body name="base" pos="0.1 0.2 0.3" euler="10 20 30">
      <inertial pos="0 0 0.1" mass="2" diaginertia="0.1 0.2 0.3"/>
      <body name="a" pos="0 0 0.2" euler="0 90 0">
        <joint name="j1" axis="0.3 0.4 0.5" pos="0.1 0 0" range="-90 90" damping="0.2"/>
        <inertial pos="0.1 0 0.02" mass="1.5" fullinertia="0.02 0.03 0.04 0.001 0.002 0.003"/>
        <body name="plate" pos="0.05 0.1 0" euler="30 0 0">
          <inertial pos="0 0.02 0" mass="0.4" diaginertia="0.01 0.01 0.02"/>
        </body>
        <body name="side" pos="0 -0.2 0">
          <joint name="js" axis="1 0 0" ref="20"/>
          <inertial pos="0.1 0 0" mass="0.7" diaginertia="0.01 0.02 0.02"/>
        </body>
        <body name="b" pos="0.3 0 0" euler="0 0 45">
          <joint name="j2" type="slide" axis="0 1 1" range="-0.1 0.2" ref="0.05"/>
          <inertial pos="0 0.1 0" mass="1" diaginertia="0.01 0.02 0.03"/>
          <body name="c" pos="0 0.1 0.2">
            <joint name="j3" axis="0 0 1" pos="0 0.05 0" ref="30" actuatorfrcrange="-7 9"/>
            <inertial pos="0.05 0.05 0" mass="0.8" diaginertia="0.01 0.01 0.01"/>
            <body name="tool" pos="0 0 0.1"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="m1" joint="j1" gear="50" ctrlrange="-2 3"/>
    <motor name="m2" joint="j2" forcerange="-40 30"/>
    <position name="p3" joint="j3" kp="10" ctrlrange="-1 1"/>
  </actuator>
</mujoco>"""


def test_branches_ref_welded_and_locked_bodies(tmp_path):
    path = write(tmp_path, BRANCHED)
    with pytest.raises(MJCFError, match=r"branches at body 'world' into bodies \['box', "
                       r"'base'\]; choose the tip body .* one of \['box', 'plate', 'side', "
                       r"'tool'\]"):
        sj.robots.from_mjcf(path)
    with pytest.warns(UserWarning, match=r"joints \['js'\] are off the chain"):
        robot = sj.robots.from_mjcf(path, tip="tool")
    assert robot.joint_names == ("j1", "j2", "j3") and robot.link_names == ("a", "b", "c")
    assert robot.joint_types == ("revolute", "prismatic", "revolute")
    m = _model(path)
    np.testing.assert_array_equal(robot.gravity, [0.5, -1, -9.7])
    q, qd, qdd = states(np.random.default_rng(6), 3)
    assert_close(sj.inverse_dynamics(robot, robot.params, q, qd, qdd),
                 mj_torques(m, robot, q, qd, qdd))
    with pytest.warns(UserWarning, match="off the chain"):
        short = sj.robots.from_mjcf(path, tip="b")
    assert short.joint_names == ("j1", "j2")


def test_joint_limits_from_mjcf(tmp_path):
    path = write(tmp_path, BRANCHED)
    with pytest.warns(UserWarning):
        robot = sj.robots.from_mjcf(path, tip="c")
    limits = sj.joint_limits_from_mjcf(path, robot, qdd_max=4.0)
    np.testing.assert_allclose(limits.q_min, [-np.pi / 2, -0.1, -np.inf])
    np.testing.assert_allclose(limits.q_max, [np.pi / 2, 0.2, np.inf])
    # j1: a motor, |gear * ctrl| <= 50 * 3; j2: forcerange; j3: the joint's actuatorfrcrange
    np.testing.assert_allclose(limits.tau_max, [150.0, 40.0, 9.0])
    assert np.all(np.isinf(limits.qd_max)) and np.all(np.asarray(limits.qdd_max) == 4.0)
    assert limits.names == robot.joint_names and limits.angular == (True, False, True)
    same = sj.dynamics.joint_limits(str(path), robot)  # what --robot arm.xml uses
    np.testing.assert_allclose(same.tau_max, limits.tau_max)
    # a random chain's motors have no control range: unknown efforts
    free = write(tmp_path, random_mjcf(np.random.default_rng(7), 2), "free.xml")
    free_robot = sj.robots.from_mjcf(free)
    unknown = sj.joint_limits_from_mjcf(free, free_robot)
    assert np.all(np.isnan(unknown.tau_max)) and np.all(np.isinf(unknown.q_max))


# -------------------------------------------------------------------------------- errors
def _chain(joints: str) -> str:
    return (f'<mujoco><worldbody><body name="a">{joints}<geom size="0.1"/></body>'
            f"</worldbody></mujoco>")


@pytest.mark.parametrize("text,match", [
    (_chain('<freejoint name="f"/>'), r"joint 'f' of body 'a' is a free joint; supported "
                                      r"on the chain: hinge, slide"),
    (_chain('<joint name="s" type="ball"/>'), r"joint 's' of body 'a' is a ball joint"),
    (_chain('<joint name="x" axis="1 0 0"/><joint name="y" axis="0 1 0"/>'),
     r"body 'a' has 2 joints \['x', 'y'\]; expected at most one per body"),
    (_chain(""), r"has no hinge or slide joint"),
    ("<mujoco><worldbody><body name='a'", r"could not be compiled by MuJoCo: .*XML"),
    ("<mujoco><worldbody><bogus/></worldbody></mujoco>",
     r"could not be compiled by MuJoCo: .*unrecognized element"),
])
def test_errors(tmp_path, text, match):
    path = write(tmp_path, text)
    with pytest.raises(MJCFError, match=match) as info:
        sj.robots.from_mjcf(path)
    assert isinstance(info.value, ValueError) and str(path) in str(info.value)


def test_missing_file_and_tip(tmp_path):
    with pytest.raises(MJCFError, match=r"cannot read MJCF .*nope\.xml.*no such file"):
        sj.robots.from_mjcf(tmp_path / "nope.xml")
    path = write(tmp_path, random_mjcf(np.random.default_rng(8), 2, fixed_prob=0.0))
    with pytest.raises(MJCFError, match=r"has no body 'hand' \(tip\); bodies: \['link1', "
                       r"'link2'\]"):
        sj.robots.from_mjcf(path, tip="hand")
    robot = sj.robots.from_mjcf(path)
    with pytest.raises(MJCFError, match="has no joint 'j9'"):
        sj.robots.armature_from_mjcf(path, sj.Robot(robot.T_fixed[:1], robot.screws[:1],
                                                    robot.joint_types[:1], joint_names=["j9"]))


# ------------------------------------------------------------- manufacturers' URDFs
#: (name, file under example-robot-data's robots/, tip or None)
ARMS = [
    ("Panda", "panda_description/urdf/panda.urdf", "panda_hand"),  # fingers locked at 0
    ("Kinova", "kinova_description/robots/kinova.urdf", None),  # continuous joints
    ("xArm7", "xarm_description/urdf/xarm7.urdf", None),  # friction and damping
]
#: What MuJoCo's URDF importer needs: no meshes (visual and collision elements dropped),
#: every link kept as a body (fusestatic is on by default for URDF).
MUJOCO_TAG = '<mujoco><compiler fusestatic="false" discardvisual="true"/></mujoco>'



@pytest.mark.parametrize("name,file,tip", ARMS, ids=[a[0] for a in ARMS])
def test_published_urdf_through_mujoco(tmp_path, robots_dir, name, file, tip):
    from lxml import etree

    root = etree.parse(str(robots_dir / file)).getroot()
    for element in list(root.iter("visual", "collision")):
        element.getparent().remove(element)
    root.insert(0, etree.fromstring(MUJOCO_TAG))
    urdf = tmp_path / "for_mujoco.urdf"
    urdf.write_bytes(etree.tostring(root))
    mjcf = tmp_path / "saved.xml"
    mujoco.mj_saveLastXML(str(mjcf), mujoco.MjModel.from_xml_path(str(urdf)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's fingers, locked
        robot = sj.robots.from_mjcf(mjcf, tip=tip)
        direct = sj.robots.from_mjcf(urdf, tip=tip)  # MuJoCo reads the URDF itself
        reference = sj.robots.from_urdf(robots_dir / file, tip)
    n = robot.n_joints
    assert robot.joint_names == reference.joint_names == direct.joint_names
    q, qd, qdd = states(np.random.default_rng(9), n)
    # (a) MuJoCo's torques of the saved MJCF; its frictionloss (a constraint) left out
    no_coulomb = np.asarray(robot.params).reshape(n, 12).copy()
    no_coulomb[:, 10] = 0.0
    assert_close(sj.inverse_dynamics(robot, no_coulomb.ravel(), q, qd, qdd),
                 mj_torques(_model(mjcf), robot, q, qd, qdd))
    # (b) the URDF compiled by MuJoCo equals from_urdf of it: geometry, inertials, friction
    expected = sj.inverse_dynamics(reference, reference.params, q, qd, qdd)
    assert_close(sj.inverse_dynamics(direct, direct.params, q, qd, qdd), expected)
    np.testing.assert_allclose(direct.params, reference.params, rtol=0, atol=1e-12)
    # mj_saveLastXML writes 6 significant digits: the saved file agrees to those
    assert_close(sj.inverse_dynamics(robot, robot.params, q, qd, qdd), expected, tol=1e-5)


# ------------------------------------------------------------------------ command line
def test_command_line_reads_mjcf(tmp_path, capsys):
    from sedsabso_jax.cli import main

    path = write(tmp_path, random_mjcf(np.random.default_rng(10), 1, damping=True))
    assert main(["base-parameters", "--robot", str(path)]) == 0
    assert "random:" in capsys.readouterr().out
    assert main(["base-parameters", "--robot", str(tmp_path / "missing.xml")]) == 2
    assert "no such file" in capsys.readouterr().err
