"""Names renamed in 0.2 keep working for one release: each warns (DeprecationWarning, at the
caller's line) and does what the new name does."""

from __future__ import annotations

import numpy as np
import pytest

import sedsabso_jax as sj


def test_sedsabso_renamed_hyperparameters():
    with pytest.deprecated_call() as record:
        old = sj.SEDSABSO(q=2, f_min=0.2, f_max=0.8)
    assert sorted(str(w.message).split(" is ")[0] for w in record) == [
        "SEDSABSO(f_max=...)", "SEDSABSO(f_min=...)", "SEDSABSO(q=...)"]
    assert "use n_trials=..." in str(record[0].message)
    assert old == sj.SEDSABSO(n_trials=2, exponent_start=0.2, exponent_end=0.8)
    with pytest.deprecated_call(match=r"SEDSABSO\.q is deprecated"):
        assert old.q == 2
    with pytest.raises(TypeError, match="both q= .deprecated. and n_trials="):
        sj.SEDSABSO(q=2, n_trials=3)


def test_warnings_point_at_the_caller():
    with pytest.deprecated_call() as record:
        sj.SEDSABSO(q=1)
    assert record[0].filename == __file__


def test_identify_weights_is_sigma(rng):
    robot = sj.robots.rs010n()
    base = sj.base_parameters(robot)
    q, qd, qdd = rng.standard_normal((3, 200, 3))
    tau = np.asarray(sj.inverse_dynamics(robot, robot.params, q, qd, qdd))
    tau = tau + 0.1 * rng.standard_normal(tau.shape)
    new = sj.identify(robot, q, qd, qdd, tau, method="WLS", sigma=[1.0, 2.0, 3.0], base=base)
    with pytest.deprecated_call(match=r"identify\(weights=\.\.\.\).*use sigma="):
        old = sj.identify(robot, q, qd, qdd, tau, method="WLS", weights=[1.0, 2.0, 3.0],
                          base=base)
    np.testing.assert_array_equal(old.values, new.values)


@pytest.mark.parametrize("module, old, new", [
    ("sedsabso_jax.excitation", "search_box", "coefficient_box"),
    ("sedsabso_jax.dynamics.robots", "KUKA_LWR4_URDF", "kuka_lwr4_urdf"),
    ("sedsabso_jax.dynamics.robots", "RS010N_TABLE2", None),
    ("sedsabso_jax.identification", "Model", "TorqueModel"),
])
def test_moved_module_names(module, old, new):
    import importlib

    mod = importlib.import_module(module)
    with pytest.deprecated_call(match=f"{module}.{old} is deprecated"):
        value = getattr(mod, old)
    assert value is (getattr(mod, new) if new else sj.paper.TABLE2)
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        mod.no_such_name  # noqa: B018
