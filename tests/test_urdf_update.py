"""The user's own URDF, updated: the identified inertials and joint friction written into
it, everything else kept, and pinocchio's torques of the written file equal to the fit's."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from lxml import etree
from test_urdf_export import pin_torques

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.dynamics import update_urdf

pytestmark = pytest.mark.filterwarnings("ignore:.*are off the chain")


def _perturbed(robot: sj.Robot) -> np.ndarray:
    """Other physically consistent parameters: each link's 10 inertial parameters scaled
    by its own positive factor (a heavier or lighter body of the same shape), friction
    changed."""
    p = np.asarray(robot.params).reshape(robot.n_joints, 12).copy()
    p[:, :10] *= np.linspace(0.7, 1.4, robot.n_joints)[:, None]
    p[:, 10] = np.linspace(0.2, 0.9, robot.n_joints)   # Coulomb
    p[:, 11] = np.linspace(1.5, 0.3, robot.n_joints)   # viscous
    return p.ravel()


def _kept(text: str) -> list[tuple]:
    """Every element but ``<inertial>`` (and what is inside) and ``<dynamics>``, in order:
    tag, attributes, text; comments too."""
    root = etree.fromstring(text.encode())
    for element in list(root.iter("inertial", "dynamics")):
        element.getparent().remove(element)
    return [(str(e.tag), sorted(e.attrib.items()), (e.text or "").strip())
            for e in root.iter() if not (isinstance(e, etree._Comment)
                                         and "identified" in (e.text or ""))]


def test_kuka_torques_are_the_fits_and_the_rest_is_kept(tmp_path):
    robot = sj.robots.kuka_lwr4()
    params = _perturbed(robot)
    with sj.robots.kuka_lwr4_urdf() as source:
        original = source.read_text()
        text = update_urdf(source, robot, params, comment="identified here")
    path = tmp_path / "kuka.urdf"
    path.write_text(text)
    q, qd, qdd = np.random.default_rng(1).standard_normal((3, 20, 7))
    ours = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd))
    np.testing.assert_allclose(pin_torques(path, q, qd, qdd), ours, atol=1e-9)
    assert _kept(text) == _kept(original)
    assert "<!-- identified here -->" in text
    back = sj.robots.from_urdf(path)  # and the package reads back what it wrote
    np.testing.assert_allclose(np.asarray(back.params), params, atol=1e-12)


GRIPPER_URDF = """<?xml version="1.0"?>
<!-- Copyright and licence of the user's model, before the root -->
<robot name="arm_with_gripper">
  <!-- a comment the user wrote -->
  <material name="blue"><color rgba="0 0 1 1"/></material>
  <link name="base"><visual><geometry><mesh filename="package://arm/base.stl"/></geometry>
    </visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.9" upper="2.9" effort="80" velocity="2"/></joint>
  <link name="l1">
    <inertial><origin xyz="0 0.02 0.1" rpy="0.1 0 0"/><mass value="3.0"/>
      <inertia ixx="0.05" ixy="0.001" ixz="0" iyy="0.04" iyz="0" izz="0.02"/></inertial>
    <visual><geometry><mesh filename="package://arm/l1.dae" scale="1 1 1"/></geometry>
      <material name="blue"/></visual>
    <collision><geometry><cylinder radius="0.05" length="0.2"/></geometry></collision>
  </link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.2" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="60" velocity="2"/>
    <dynamics damping="0.4" friction="0.2"/></joint>
  <link name="l2">
    <inertial><origin xyz="0.2 0 0" rpy="0 0 0"/><mass value="2.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.06" iyz="0" izz="0.06"/></inertial>
    <collision><geometry><mesh filename="package://arm/l2_collision.stl"/></geometry></collision>
  </link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.4 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="30" velocity="3"/></joint>
  <link name="l3">
    <inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="1.0"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="flange" type="fixed"><parent link="l3"/><child link="tool"/>
    <origin xyz="0.25 0 0" rpy="0 0.3 0"/></joint>
  <link name="tool">
    <inertial><origin xyz="0.03 0 0" rpy="0 0 0"/><mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <visual><geometry><mesh filename="package://gripper/hand.stl"/></geometry></visual>
  </link>
  <joint name="finger_left_joint" type="prismatic"><parent link="tool"/>
    <child link="finger_left"/><origin xyz="0.08 0.02 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint>
  <link name="finger_left">
    <inertial><origin xyz="0.01 0 0" rpy="0 0 0"/><mass value="0.05"/>
      <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
    <visual><geometry><mesh filename="package://gripper/finger.stl"/></geometry></visual>
  </link>
  <joint name="finger_right_joint" type="prismatic"><parent link="tool"/>
    <child link="finger_right"/><origin xyz="0.08 -0.02 0" rpy="0 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint>
  <link name="finger_right">
    <inertial><origin xyz="0.01 0 0" rpy="0 0 0"/><mass value="0.05"/>
      <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
  </link>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
    <joint name="j1"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
    <actuator name="m1"><mechanicalReduction>100</mechanicalReduction></actuator>
  </transmission>
  <gazebo reference="l1"><material>Gazebo/Blue</material></gazebo>
</robot>
"""


def test_gripper_and_geometry_kept_and_lumped_links_massless(tmp_path):
    """The tool (fixed) and the fingers (off the chain, locked) are part of the identified
    last link: their inertials go, their geometry stays, and pinocchio's torques of the
    arm's joints (fingers at 0) are the fit's."""
    source = tmp_path / "arm.urdf"
    source.write_text(GRIPPER_URDF)
    robot = sj.robots.from_urdf(source, tip="tool")
    assert robot.joint_names == ("j1", "j2", "j3")
    params = _perturbed(robot)
    text = update_urdf(source, robot, params)
    out = tmp_path / "arm_identified.urdf"
    out.write_text(text)
    root = etree.fromstring(text.encode())
    links = {link.get("name"): link for link in root.iter("link")}
    assert [name for name, link in links.items() if link.find("inertial") is not None] == [
        "l1", "l2", "l3"]
    assert _kept(text) == _kept(GRIPPER_URDF)
    assert "a comment the user wrote" in text and "package://gripper/finger.stl" in text
    assert "<!-- Copyright and licence of the user's model, before the root -->" in text
    q, qd, qdd = np.random.default_rng(2).standard_normal((3, 15, 3))
    at_zero = np.zeros((15, 2))  # the fingers
    pin = pin_torques(out, *(np.hstack([a, at_zero]) for a in (q, qd, qdd)))
    ours = np.asarray(sj.inverse_dynamics(robot, params, q, qd, qdd))
    np.testing.assert_allclose(pin[:, :3], ours, atol=1e-9)


def test_a_urdf_of_another_robot_is_refused(tmp_path):
    source = tmp_path / "arm.urdf"
    source.write_text(GRIPPER_URDF)
    with pytest.raises(ValueError, match="does not match robot 'kuka-lwr'"):
        update_urdf(source, sj.robots.kuka_lwr4(), _perturbed(sj.robots.kuka_lwr4()))


def test_urdf_out_equal_to_the_input_is_status_2_and_writes_nothing(tmp_path, capsys):
    with sj.robots.kuka_lwr4_urdf() as shipped:
        source = tmp_path / "kuka.urdf"
        shutil.copy(shipped, source)
    before = source.read_text()
    data = sj.load_kuka_lwr4(1).slice(0, 400).save(tmp_path / "m.npz")
    js = tmp_path / "out" / "r.json"
    argv = ["identify", "--robot", str(source), "--data", str(data), "--physical",
            "--method", "OLS", "--weights", "equal", "--friction", "viscous-coulomb",
            "--folds", "0", "--json", str(js), "--urdf-out"]
    for same in (str(source), str(tmp_path / "." / "kuka.urdf")):
        assert cli.main(argv + [same]) == 2
        err = capsys.readouterr().err
        assert "is the input URDF" in err and err.count("error") == 1
    assert source.read_text() == before and not js.exists() and not js.parent.exists()
