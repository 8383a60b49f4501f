"""A result a simulator can use: the identified robot written as URDF, read back by
pinocchio (an independent parser and dynamics) and by the package, gives the same torques
as the fit."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from conftest import random_dh

import sedsabso_jax as sj
from sedsabso_jax import cli
from sedsabso_jax.dynamics._urdf_writer import to_urdf


def pin_torques(path, q, qd, qdd):
    """RNEA of pinocchio's model of ``path`` plus the URDF's joint friction."""
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    return np.array([pin.rnea(model, data, a, b, c) + model.friction * np.sign(b)
                     + model.damping * b for a, b, c in zip(q, qd, qdd)])


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_written_urdf_has_the_same_dynamics(rng, tmp_path, convention):
    """Standard DH puts the joint axis off the link origin: the writer adds a joint frame
    on the axis; prismatic joints too. pinocchio and the package's reader agree."""
    t, params = random_dh(rng, 4, prismatic_prob=0.3)
    if convention == "mdh":
        robot = sj.robots.from_mdh(t["alpha"], t["a"], t["d"], t["theta"],
                                   prismatic=t["prismatic"], params=params)
    else:
        robot = sj.robots.from_dh(t["d"], t["a"], t["alpha"], t["theta"],
                                  prismatic=t["prismatic"], params=params)
    path = tmp_path / "r.urdf"
    path.write_text(to_urdf(robot))
    q, qd, qdd = rng.standard_normal((3, 20, 4))
    ours = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    np.testing.assert_allclose(pin_torques(path, q, qd, qdd), ours, atol=1e-10)
    back = sj.robots.from_urdf(path)
    np.testing.assert_allclose(np.asarray(sj.inverse_dynamics(back, back.params, q, qd, qdd)),
                               ours, atol=1e-10)


def test_inconsistent_parameters_are_refused():
    robot = sj.robots.rs010n()  # Table 2: Ixx2 = -10.02
    with pytest.raises(ValueError, match="physically consistent link parameters"):
        to_urdf(robot)


def test_identify_urdf_out(tmp_path, capsys):
    """`identify --physical --urdf-out`: pinocchio's torques of the written URDF are the
    fit's rigid-body and friction torques; the torque offsets, which a URDF cannot hold,
    are named in a comment (the fit = URDF torques + offsets)."""
    m = sj.load_kuka_lwr4(1).slice(0, 2000)
    data = m.save(tmp_path / "m.npz")
    urdf, js = tmp_path / "out" / "kuka.urdf", tmp_path / "r.json"
    argv = ["identify", "--robot", "kuka_lwr4", "--data", str(data), "--physical",
            "--method", "WLS", "--weights", "limits", "--friction", "viscous-coulomb+offset",
            "--folds", "0", "--urdf-out", str(urdf), "--json", str(js)]
    assert cli.main(argv) == 0
    text = urdf.read_text()
    assert "physically consistent" in text and "OFF1 = " in text
    doc = json.loads(js.read_text())
    names, values = doc["base_parameters"]["names"], np.array(doc["base_parameters"]["values"])
    offsets = values[[names.index(f"OFF{j}") for j in range(1, 8)]]
    robot = sj.robots.kuka_lwr4()
    base = sj.base_parameters(robot)
    q, qd, qdd = m.q[::100], m.qd[::100], m.qdd[::100]
    predicted = np.asarray(base.regressor(q, qd, qdd)) @ values[:base.rank] + offsets
    np.testing.assert_allclose(pin_torques(urdf, q, qd, qdd) + offsets, predicted, atol=1e-6)
    capsys.readouterr()
    urdf.unlink()
    # --urdf-out alone keeps only physically consistent candidates; --no-physical
    # contradicts it: exit 2, nothing written
    assert cli.main([a if a != "--physical" else "--no-physical" for a in argv]) == 2
    assert "--urdf-out needs physically consistent link parameters" in capsys.readouterr().err
    assert not urdf.exists()
    assert cli.main([a for a in argv if a != "--physical"]) == 0
    assert "physically consistent" in urdf.read_text()
