"""Deprecations: the warning a deprecated name gives (DeprecationWarning at the caller's
line, "will be removed after sedsabso-jax X.Y", the release given), and what 0.5 removed
of 0.3's deprecations: 0.2's call forms, the moved-name tables and the old module paths
are gone, each an ordinary error. (0.5's own: the swarms' population argument,
``tests/test_solver_paths.py``.)"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax import _deprecation


def test_a_deprecation_names_its_release_and_points_at_the_caller():
    with pytest.deprecated_call(match=r"^old\(\) is deprecated and will be removed after "
                                      r"sedsabso-jax 0\.5; use new\(\)$") as record:
        _deprecation.warn("old()", "new()", removed_after="0.5")
    assert record[0].filename == __file__

    class Thing:
        def __init__(self, size=1):
            self.size = size

    _deprecation.renamed(Thing, {"n": "size"}, removed_after="0.6")
    with pytest.deprecated_call(match=r"^Thing\(n=\.\.\.\) is deprecated and will be removed "
                                      r"after sedsabso-jax 0\.6; use size=\.\.\.$"):
        thing = Thing(n=3)
    assert thing.size == 3
    with pytest.deprecated_call(match=r"^Thing\.n is deprecated .* 0\.6; use Thing\.size$"):
        assert thing.n == 3
    with pytest.raises(TypeError, match=r"both n= \(deprecated\) and size="):
        Thing(n=3, size=4)


@pytest.mark.parametrize("module, name", [
    ("sedsabso_jax", "metrics"), ("sedsabso_jax.robots", "KUKA_LWR4_URDF"),
    ("sedsabso_jax.robots", "RS010N_TABLE2"), ("sedsabso_jax.dynamics", "Robot"),
    ("sedsabso_jax.dynamics", "robots"), ("sedsabso_jax.measurements", "Measurements"),
    ("sedsabso_jax.excitation", "search_box"), ("sedsabso_jax.excitation", "JointLimits"),
    ("sedsabso_jax.identification", "identify"), ("sedsabso_jax.identification", "Model"),
    ("sedsabso_jax.identification", "METHODS"), ("sedsabso_jax.optim", "minimise"),
    ("sedsabso_jax.optim", "SEDSABSO"), ("sedsabso_jax.optim", "baselines"),
])
def test_moved_names_of_0_3_are_gone(module, name):
    with pytest.raises(AttributeError):
        getattr(importlib.import_module(module), name)


@pytest.mark.parametrize("path", ["sedsabso_jax.dynamics.robots",
                                  "sedsabso_jax.identification.validation",
                                  "sedsabso_jax.reproduce.experiment",
                                  "sedsabso_jax.measurements.transmission",
                                  "sedsabso_jax.identification._legacy"])
def test_old_module_paths_are_gone(path):
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(path)


def test_0_2_call_forms_are_gone():
    robot = sj.robots.rs010n()
    z = np.zeros((20, 3))
    with pytest.raises(TypeError):
        sj.identify(robot, z, z, z, z)  # (robot, q, qd, qdd, tau)
    with pytest.raises(TypeError):
        sj.identify(robot, (z, z, z, z), method="OLS", friction="offset")
    with pytest.raises(TypeError):
        sj.select_model(robot, (z[:, 0], z, z, z, z), weightings=(("OLS", None),))
    with pytest.raises(TypeError):
        sj.select_and_identify(robot, (z[:, 0], z, z, z, z), frictions=("offset",))


def test_0_3_solver_names_are_gone():
    for old in ("q", "f_min", "f_max"):  # renamed in 0.3: n_trials, exponent_start, ..._end
        with pytest.raises(TypeError):
            sj.SEDSABSO(**{old: 1})
    assert not hasattr(sj.SEDSABSO(), "check")  # hyperparameters are checked when built


def test_signals_xp_is_jax_numpy_and_deprecated():
    """Terms compute with ``jax.numpy`` only: a term of one's own that still reads
    ``s.xp`` gets ``jax.numpy``, with the warning pointing at its line."""
    import jax.numpy as jnp

    from sedsabso_jax.identification import Signals

    s = Signals(np.zeros((2, 3)), np.zeros((2, 3)), np.zeros((2, 3)), None, None)
    with pytest.deprecated_call(match=r"^Signals\.xp is deprecated .* use jax\.numpy$") as w:
        assert s.xp is jnp
    assert w[0].filename == __file__
