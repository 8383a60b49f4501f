"""Forward kinematics against pytorch-kinematics and against the DH closed forms."""

from __future__ import annotations

import numpy as np
import pytest
import pytorch_kinematics as pk
import torch
from conftest import random_dh, random_urdf

import sedsabso_jax as sj


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
    """Craig's modified-DH link transform, written out (Craig, 3rd ed., Eq. 3.6)."""
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    return np.array([[ct, -st, 0.0, a],
                     [st * ca, ct * ca, -sa, -sa * d],
                     [st * sa, ct * sa, ca, ca * d],
                     [0.0, 0.0, 0.0, 1.0]])


def _dh(theta, d, a, alpha):
    """The standard (distal) DH link transform, written out."""
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


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
