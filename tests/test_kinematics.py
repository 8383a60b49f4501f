"""Forward kinematics against pytorch-kinematics and against the DH closed forms."""

from __future__ import annotations

import numpy as np
import pytest
import pytorch_kinematics as pk
import torch
from conftest import random_dh, random_urdf

import sedsabso_jax as sj
from sedsabso_jax.dynamics import spatial as sp


@pytest.mark.parametrize("n,seed", [(1, 0), (3, 1), (5, 2), (7, 3)])
def test_forward_kinematics_matches_pytorch_kinematics(tmp_path, n, seed):
    rng = np.random.default_rng(seed)
    text, links = random_urdf(rng, n)
    path = tmp_path / "r.urdf"
    path.write_text(text)
    robot = sj.robots.from_urdf(path)
    chain = pk.build_chain_from_urdf(text).to(dtype=torch.float64)
    assert list(chain.get_joint_parameter_names()) == list(robot.joint_names)
    q = rng.uniform(-2, 2, (6, n))
    ours = np.asarray(sj.forward_kinematics(robot, q))
    theirs = chain.forward_kinematics(torch.as_tensor(q))
    for i, name in enumerate(robot.link_names):
        # pytorch-kinematics builds its rotations in float32: compare at 1e-5
        np.testing.assert_allclose(ours[:, i], theirs[name].get_matrix().numpy(), atol=1e-5)


def _mdh(alpha, a, theta, d):
    return (sp.transform(sp.rot_x(alpha)) @ sp.transform(translation=(a, 0, 0))
            @ sp.transform(sp.rot_z(theta)) @ sp.transform(translation=(0, 0, d)))


def _dh(theta, d, a, alpha):
    return (sp.transform(sp.rot_z(theta)) @ sp.transform(translation=(0, 0, d))
            @ sp.transform(translation=(a, 0, 0)) @ sp.transform(sp.rot_x(alpha)))


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_dh_forward_kinematics_closed_form(rng, convention):
    n = 5
    t, _ = random_dh(rng, n)
    q = rng.uniform(-2, 2, n)
    if convention == "mdh":
        robot = sj.robots.from_mdh(t["alpha"], t["a"], t["d"], t["theta"], prismatic=t["prismatic"])
    else:
        robot = sj.robots.from_dh(t["d"], t["a"], t["alpha"], t["theta"], prismatic=t["prismatic"])
    ours = np.asarray(sj.forward_kinematics(robot, q))
    T = np.eye(4)
    for i in range(n):
        theta = t["theta"][i] + (0.0 if t["prismatic"][i] else q[i])
        d = t["d"][i] + (q[i] if t["prismatic"][i] else 0.0)
        T = T @ (_mdh(t["alpha"][i], t["a"][i], theta, d) if convention == "mdh"
                 else _dh(theta, d, t["a"][i], t["alpha"][i]))
        np.testing.assert_allclose(ours[i], T, atol=1e-12)
