"""What a model computes once is keyed by its structure and values, never by identity or
by what a term's ``settings()`` says: a planted term whose ``settings()`` leaves out the
field that sets its columns gets its own columns, model after model."""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification import AbstractTerm, diagonal


class Power(AbstractTerm):
    """``FP_j qd_j |qd_j|^(power - 1)``; its ``settings()`` forget ``power`` (planted):
    ``power = 1`` is the viscous column (the base spans it), ``power = 3`` is not."""

    power: float = 1.0
    name: ClassVar[str] = "power"
    nonnegative: ClassVar[bool] = False

    def names(self, model):
        return tuple(f"FP{j + 1}" for j in range(model.robot.n_joints))

    def columns(self, model, s):
        return diagonal(s.qd * jnp.abs(s.qd) ** (self.power - 1), model.robot.n_joints)

    def settings(self):
        return {}


def test_a_term_whose_settings_omit_a_field_gets_its_own_columns():
    robot = sj.robots.rs010n()
    n = robot.n_joints
    linear = sj.TorqueModel.of(robot, Power(1.0))
    assert linear.regrouped == tuple(f"FP{j + 1}" for j in range(n))  # = FV_j
    # the same base, the same settings(), other columns
    cubic = sj.TorqueModel.of(robot, Power(3.0), base=linear.base)
    assert cubic.regrouped == ()  # its own columns, not the linear model's
    assert cubic.structure != linear.structure
    assert cubic.names[-n:] == tuple(f"FP{j + 1}" for j in range(n))
    qd = np.random.default_rng(0).standard_normal((5, n))
    Y = cubic.regressor(np.zeros((5, n)), qd, np.zeros((5, n)))
    np.testing.assert_array_equal(Y[..., -n:], diagonal(qd * np.abs(qd) ** 2, n))
    # equal values are one structure, whatever the instance
    assert sj.TorqueModel.of(robot, Power(3.0)).structure == cubic.structure  # a new base


def test_a_scale_term_declares_its_scale_field():
    """An ``AbstractScale`` declares its scale with ``scale(...)``: the declaration gives
    the field, its default, bounds, unit and the searched values' names; a class that
    declares none (0.5's class variables) is refused when built, by name."""
    from sedsabso_jax.identification import AbstractScale, scale

    class Wobble(AbstractScale):
        period: float | tuple[float, ...] = scale(0.3, bounds=(0.1, 2.0), unit="rad",
                                                  symbol="p")
        fitted: bool = True
        name: ClassVar[str] = "wobble"
        nonnegative: ClassVar[bool] = False

        def names(self, model):
            return tuple(f"W{j + 1}" for j in range(model.robot.n_joints))

        def columns(self, model, s):
            return diagonal(jnp.sin(s.q / self.per_joint(model.robot.n_joints)),
                            model.robot.n_joints)

    found = Wobble().nonlinear(sj.TorqueModel.of(sj.robots.rs010n()))
    assert found.names == ("p1", "p2", "p3") and found.unit == "rad"
    np.testing.assert_array_equal(found.values, [0.3] * 3)
    np.testing.assert_array_equal(found.upper, [2.0] * 3)
    assert Wobble.parse("0.5").period == 0.5
    assert Wobble(period=0.5, fitted=False).text == "wobble:0.5"

    class Undeclared(AbstractScale):
        period: float = 0.3
        fitted: bool = False
        name: ClassVar[str] = "undeclared"
        nonnegative: ClassVar[bool] = False

        def names(self, model):
            return ()

        def columns(self, model, s):
            return None

    with pytest.raises(TypeError, match=r"Undeclared must declare one scale field with "
                                        r"scale\(\.\.\.\), found 0"):
        Undeclared()


def test_which_columns_a_term_keeps_does_not_depend_on_the_values_it_reads():
    """The load term reads the model's rigid-body values; whether the base spans its
    columns is found at a random point of them (no probe in the terms' signals): a zero
    load (columns of zeros), a unit load, the robot's own and a found one keep the same
    columns, every one of the term's."""
    robot = sj.robots.rs010n()
    waiting = sj.TorqueModel.of(robot, sj.LoadFriction(viscous=True))
    size = len(waiting.rigid_columns)
    assert waiting.regrouped == ()
    for point in (np.zeros(size), np.ones(size),
                  np.random.default_rng(5).standard_normal(size)):
        model = sj.TorqueModel.of(robot, sj.LoadFriction(viscous=True, load_point=point),
                                  base=waiting.base)
        np.testing.assert_array_equal(model.kept, waiting.kept)
        assert model.names == waiting.names
    zero = sj.TorqueModel.of(robot, sj.LoadFriction(load_point=np.zeros(size)),
                             base=waiting.base)
    q = np.random.default_rng(0).standard_normal((4, robot.n_joints))
    assert not np.any(zero.regressor(q, q, q)[..., -robot.n_joints:])  # yet kept
