"""Property tests (hypothesis) over random robots, parameters and states.

* The torque is linear in the parameters: ``tau(a p1 + b p2) = a tau(p1) + b tau(p2)``, and
  the regressor does not depend on the parameters the robot carries.
* The base reduction loses nothing: ``base.regressor @ base.project(p) = Y @ p`` for every
  ``p``, not only the robot's own.

Robots are drawn from a small set of structures (joint count, joint types) so the compiled
regressor is reused; geometry, parameters and states vary freely.
"""

from __future__ import annotations

import numpy as np
from conftest import random_dh, random_state
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import sedsabso_jax as sj

SETTINGS = settings(max_examples=8, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


def _robot(seed: int, n: int, convention: str):
    rng = np.random.default_rng(seed)
    table, params = random_dh(rng, n, prismatic_prob=0.0)  # revolute: one structure per n
    if convention == "mdh":
        robot = sj.robots.from_mdh(table["alpha"], table["a"], table["d"], table["theta"],
                                   params=params)
    else:
        robot = sj.robots.from_dh(table["d"], table["a"], table["alpha"], table["theta"],
                                  params=params)
    return robot, rng


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 3),
       convention=st.sampled_from(["mdh", "dh"]),
       a=st.floats(-10, 10, allow_nan=False), b=st.floats(-10, 10, allow_nan=False))
def test_torque_is_linear_in_the_parameters(seed, n, convention, a, b):
    robot, rng = _robot(seed, n, convention)
    q, qd, qdd = random_state(rng, robot, 40)
    p1, p2 = rng.normal(size=(2, robot.n_params))
    tau = lambda p: np.asarray(sj.inverse_dynamics(robot, p, q, qd, qdd))  # noqa: E731
    lhs, rhs = tau(a * p1 + b * p2), a * tau(p1) + b * tau(p2)
    scale = 1.0 + np.abs(a * tau(p1)).max() + np.abs(b * tau(p2)).max()
    np.testing.assert_allclose(lhs, rhs, rtol=0, atol=1e-12 * scale)
    # the regressor itself ignores the parameters the robot carries
    Y1 = np.asarray(sj.regressor(robot, q, qd, qdd))
    Y2 = np.asarray(sj.regressor(robot.with_params(p1), q, qd, qdd))
    np.testing.assert_array_equal(Y1, Y2)


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 3),
       convention=st.sampled_from(["mdh", "dh"]), scale=st.floats(1e-3, 1e3))
@example(seed=1022, n=1, convention="dh", scale=2.0)  # a base parameter of 5.5e5
def test_base_regressor_times_projection_is_invariant(seed, n, convention, scale):
    robot, rng = _robot(seed, n, convention)
    base = sj.base_parameters(robot, n_samples=40)  # one compiled shape
    q, qd, qdd = random_state(rng, robot, 40)
    p = scale * rng.normal(size=robot.n_params)
    Y = np.asarray(sj.regressor(robot, q, qd, qdd))
    Yb = np.asarray(base.regressor(q, qd, qdd))
    full, reduced = Y @ p, Yb @ np.asarray(base.project(p))
    np.testing.assert_allclose(reduced, full, rtol=0, atol=1e-9 * (1 + np.abs(full).max()))
    # adding any combination of the null space changes nothing
    null = np.linalg.svd(Y.reshape(-1, robot.n_params))[2][base.rank:]
    if null.shape[0]:
        p_moved = p + scale * rng.normal(size=null.shape[0]) @ null
        projected = np.asarray(base.project(p))
        # equal to rounding: of the moves (scale) and of the base values themselves, which
        # regrouping can make large (5.5e5 from parameters of size 2 in the example above)
        np.testing.assert_allclose(np.asarray(base.project(p_moved)), projected, rtol=0,
                                   atol=1e-8 * (1 + scale) + 1e-12 * np.abs(projected).max())
