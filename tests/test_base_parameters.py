"""Base parameters: rank against pinocchio's regressor, exact regrouping, RS010N."""

from __future__ import annotations

import os

import numpy as np
import pinocchio as pin
import pytest
import sympy
from conftest import pin_regressor_in_our_order, random_dh, random_state, random_urdf

import sedsabso_jax as sj


def _numeric_rank(blocks):
    """Rank of stacked pinocchio regressors. Columns that are zero up to round-off are
    dropped before the others are scaled to unit norm (scaling them would turn round-off
    into a spurious independent column)."""
    W = np.concatenate(blocks, 0)
    norms = np.linalg.norm(W, axis=0)
    keep = norms > 1e-9 * norms.max()
    s = np.linalg.svd(W[:, keep] / norms[keep], compute_uv=False)
    return int(np.sum(s > 1e-8 * s[0]))


@pytest.mark.parametrize("n,seed", [(1, 0), (2, 1), (3, 2), (4, 3), (6, 4), (7, 5)])
def test_rank_equals_pinocchio_rank_plus_friction(tmp_path, n, seed):
    rng = np.random.default_rng(seed)
    text, _ = random_urdf(rng, n)
    path = os.path.join(tmp_path, "r.urdf")
    with open(path, "w") as fh:
        fh.write(text)
    robot = sj.robots.from_urdf(path)
    model = pin.buildModelFromXML(text)
    blocks = [pin_regressor_in_our_order(model, *random_state(rng, robot)) for _ in range(200)]
    base = sj.base_parameters(robot)
    assert base.rank == _numeric_rank(blocks) + 2 * n


def test_rank_of_the_kuka():
    robot = sj.robots.kuka_lwr4()
    from importlib import resources

    model = pin.buildModelFromUrdf(str(resources.files("sedsabso_jax") / "data" / "kuka_lwr4"
                                       / "kuka_lwr4.urdf"))
    rng = np.random.default_rng(0)
    blocks = [pin_regressor_in_our_order(model, *random_state(rng, robot)) for _ in range(200)]
    assert sj.base_parameters(robot).rank == _numeric_rank(blocks) + 14


def test_rs010n_has_21_of_36():
    base = sj.base_parameters(sj.robots.rs010n())
    assert base.rank == 21 and base.matrix.shape == (21, 36)
    # the vertical first joint sees only ZZ1 of link 1, and Khalil's regrouping appears
    assert base.names[0] == "ZZ1R"
    assert base.expressions[0] == "ZZ1 + YY2 + 0.1225*M2 + YY3 + 1.193725*M3"
    assert "XX2 - YY2 - 1.071225*M3" in base.expressions
    # ZZ1R from Table 2 by hand:
    # 36.33 + 7.05 + 0.35^2 * 25.18 + 1.02 + (0.35^2 + 1.035^2) * 20.47
    expected = 36.33 + 7.05 + 0.1225 * 25.18 + 1.02 + 1.193725 * 20.47
    np.testing.assert_allclose(base.values[0], expected, rtol=1e-14)


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_base_regressor_reproduces_full_torques(rng, convention):
    table, params = random_dh(rng, 5)
    make = sj.robots.from_mdh if convention == "mdh" else None
    if make:
        robot = make(table["alpha"], table["a"], table["d"], table["theta"],
                     prismatic=table["prismatic"], params=params)
    else:
        robot = sj.robots.from_dh(table["d"], table["a"], table["alpha"], table["theta"],
                                  prismatic=table["prismatic"], params=params)
    base = sj.base_parameters(robot)
    q, qd, qdd = random_state(rng, robot, 40)
    p = rng.normal(size=(3, robot.n_params))  # any parameters, not only the robot's
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    Yb = np.asarray(base.regressor(q, qd, qdd))
    assert Yb.shape == (40, 5, base.rank)
    pb = np.asarray(base.project(p))
    assert pb.shape == (3, base.rank)
    for k in range(3):
        np.testing.assert_allclose(Yb @ pb[k], Y @ p[k], rtol=1e-9, atol=1e-9)
    # the base regressor has full column rank on these states
    assert np.linalg.matrix_rank(Yb.reshape(-1, base.rank)) == base.rank


def test_symbolic_expressions_match_the_matrix():
    base = sj.base_parameters(sj.robots.rs010n())
    names = base.robot.param_names
    symbols = [sympy.Symbol(n) for n in names]
    rng = np.random.default_rng(0)
    p = rng.normal(size=len(names))
    subs = dict(zip(symbols, p))
    values = [float(e.subs(subs)) for e in base.symbolic]
    np.testing.assert_allclose(values, base.project(p), rtol=1e-12)
    # the readable strings parse to the same expressions
    for text, expr in zip(base.expressions, base.symbolic):
        parsed = sympy.sympify(text, locals={n: s for n, s in zip(names, symbols)})
        assert float((parsed - expr).subs(subs)) == pytest.approx(0.0, abs=1e-12)


def test_seed_and_samples_do_not_change_the_set():
    robot = sj.robots.rs010n()
    a = sj.base_parameters(robot)
    b = sj.base_parameters(robot, seed=5, n_samples=120)
    assert a.indices == b.indices and a.expressions == b.expressions
    np.testing.assert_array_equal(a.matrix, b.matrix)
