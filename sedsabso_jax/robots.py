"""The built-in robots and the robot constructors: ``sj.robots.rs010n()``,
``sj.robots.from_urdf("arm.urdf", tip="tool0")``, ``sj.robots.from_mjcf("arm.xml")``,
``sj.robots.from_mdh(alpha, a, d)``, ``sj.robots.from_dh(d, a, alpha)``,
``sj.robots.kuka_lwr4()``, ... Each returns a
:class:`~sedsabso_jax.Robot` (float64: turn on JAX's 64-bit mode first)."""

from __future__ import annotations

from .dynamics._mjcf import armature_from_mjcf as armature_from_mjcf
from .dynamics._mjcf import from_mjcf as from_mjcf
from .dynamics._robots import BUILTIN as BUILTIN
from .dynamics._robots import FRANKA_PANDA_MDH as FRANKA_PANDA_MDH
from .dynamics._robots import franka_panda as franka_panda
from .dynamics._robots import from_dh as from_dh
from .dynamics._robots import from_mdh as from_mdh
from .dynamics._robots import kuka_lwr4 as kuka_lwr4
from .dynamics._robots import kuka_lwr4_urdf as kuka_lwr4_urdf
from .dynamics._robots import load as load
from .dynamics._robots import rs010n as rs010n
from .dynamics._robots import staubli_tx40 as staubli_tx40
from .dynamics._robots import staubli_tx40_urdf as staubli_tx40_urdf
from .dynamics._urdf import from_urdf as from_urdf

__all__ = [
    "rs010n", "kuka_lwr4", "kuka_lwr4_urdf", "staubli_tx40", "staubli_tx40_urdf",
    "franka_panda", "FRANKA_PANDA_MDH", "from_urdf", "from_mjcf",
    "armature_from_mjcf", "from_mdh", "from_dh", "load", "BUILTIN",
]
