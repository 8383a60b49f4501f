"""Deprecated module path: sedsabso_jax.dynamics.robots (documented in 0.2). Its names
are public elsewhere now (each warning says where); kept with a warning through 0.3.x."""

from __future__ import annotations

from .. import _deprecation

__getattr__ = _deprecation.moved(__name__, {
    "rs010n": "sedsabso_jax.robots.rs010n",
    "kuka_lwr4": "sedsabso_jax.robots.kuka_lwr4",
    "kuka_lwr4_urdf": "sedsabso_jax.robots.kuka_lwr4_urdf",
    "staubli_tx40": "sedsabso_jax.robots.staubli_tx40",
    "staubli_tx40_urdf": "sedsabso_jax.robots.staubli_tx40_urdf",
    "franka_panda": "sedsabso_jax.robots.franka_panda",
    "FRANKA_PANDA_MDH": "sedsabso_jax.robots.FRANKA_PANDA_MDH",
    "from_urdf": "sedsabso_jax.robots.from_urdf",
    "from_mdh": "sedsabso_jax.robots.from_mdh",
    "from_dh": "sedsabso_jax.robots.from_dh",
    "load": "sedsabso_jax.robots.load",
    "BUILTIN": "sedsabso_jax.robots.BUILTIN",
}, module="sedsabso_jax.dynamics._robots")
