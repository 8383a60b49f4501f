"""Robot constructors: the paper's RS010N, DH chains (modified and standard), any URDF, the
vendored KUKA LWR4+, and :func:`load` for a robot named on the command line."""

from __future__ import annotations

import os
from collections.abc import Sequence
from contextlib import AbstractContextManager
from importlib import resources
from pathlib import Path
from typing import TypeAlias

import numpy as np
from jaxtyping import ArrayLike, Bool, Float

from ..paper import TABLE2
from . import _spatial as sp
from ._mjcf import from_mjcf
from ._robot import N_LINK_PARAMETERS, STANDARD_GRAVITY, Robot
from ._urdf import from_urdf

__all__ = ["BUILTIN", "franka_panda", "from_dh", "from_mdh", "from_urdf", "kuka_lwr4",
           "kuka_lwr4_urdf", "load", "rs010n", "staubli_tx40", "staubli_tx40_urdf"]

#: One DH column: a value per joint, or one value for every joint.
_Column: TypeAlias = Float[ArrayLike, " n"] | Sequence[float]


def _dh_columns(**columns):
    arrays = {}
    for key, value in columns.items():
        arr = np.atleast_1d(np.asarray(value, dtype=float))
        if arr.ndim != 1:
            raise ValueError(f"{key} must be a 1-D sequence (one value per joint), got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{key} contains NaN or Inf: {arr}")
        arrays[key] = arr
    n = max(len(a) for a in arrays.values())
    for key, arr in arrays.items():
        if len(arr) == 1 and n > 1:
            arrays[key] = np.full(n, arr[0])
        elif len(arr) != n:
            lengths = {k: len(a) for k, a in arrays.items()}
            raise ValueError(f"DH columns must all have one entry per joint; got lengths {lengths}")
    return n, arrays


def _joint_types(prismatic, n) -> tuple[str, ...]:
    if prismatic is None:
        return ("revolute",) * n
    flags = [bool(x) for x in np.atleast_1d(prismatic)]
    if len(flags) != n:
        raise ValueError(f"prismatic must have one flag per joint ({n}), got {len(flags)}")
    return tuple("prismatic" if f else "revolute" for f in flags)


def from_mdh(alpha: _Column, a: _Column, d: _Column, theta: _Column = 0.0,
             *, prismatic: Bool[ArrayLike, " n"] | Sequence[bool] | None = None,
             params: Float[ArrayLike, " p"] | Sequence[float] | None = None,
             gravity: Float[ArrayLike, " 3"] | Sequence[float] = STANDARD_GRAVITY,
             name: str = "mdh", joint_names: Sequence[str] | None = None) -> Robot:
    """A chain from modified Denavit-Hartenberg parameters (Craig, 3rd ed., Sec. 3.4).

    Row ``i`` gives ``alpha_{i-1}, a_{i-1}, d_i, theta_i`` (rad, m), so that

        ``T_{i-1,i} = RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i) TransZ(d_i)``.

    For a revolute joint ``theta_i = q_i + theta[i]``; for a prismatic joint
    (``prismatic[i]`` true) ``d_i = q_i + d[i]``. The link frame is Craig's frame ``i``, on
    the joint axis; ``params`` (12 per link, see :class:`Robot`) are expressed in it.
    """
    n, c = _dh_columns(alpha=alpha, a=a, d=d, theta=theta)
    types = _joint_types(prismatic, n)
    T_fixed, screws = [], []
    for i, t in enumerate(types):
        T = sp.transform(sp.rot_x(c["alpha"][i])) @ sp.transform(translation=(c["a"][i], 0, 0))
        T = T @ sp.transform(sp.rot_z(c["theta"][i]), (0.0, 0.0, c["d"][i]))
        T_fixed.append(T)
        screws.append([0, 0, 1, 0, 0, 0] if t == "revolute" else [0, 0, 0, 0, 0, 1])
    return Robot(T_fixed, screws, types, params, gravity, name=name, joint_names=joint_names)


def from_dh(d: _Column, a: _Column, alpha: _Column, theta: _Column = 0.0,
            *, prismatic: Bool[ArrayLike, " n"] | Sequence[bool] | None = None,
            params: Float[ArrayLike, " p"] | Sequence[float] | None = None,
            gravity: Float[ArrayLike, " 3"] | Sequence[float] = STANDARD_GRAVITY,
            name: str = "dh", joint_names: Sequence[str] | None = None) -> Robot:
    """A chain from standard (distal) Denavit-Hartenberg parameters.

    Row ``i`` gives ``d_i, a_i, alpha_i, theta_i`` (m, rad):

        ``T_{i-1,i} = RotZ(theta_i) TransZ(d_i) TransX(a_i) RotX(alpha_i)``,

    joint ``i`` moving about (or along) ``z_{i-1}``; ``theta_i = q_i + theta[i]`` for a
    revolute joint, ``d_i = q_i + d[i]`` for a prismatic one. The link frame is DH frame
    ``i`` at the link's far end, as in the Robotics Toolbox; ``params`` are expressed in it,
    and the joint's screw, seen from that frame, does not pass through its origin.
    """
    n, c = _dh_columns(d=d, a=a, alpha=alpha, theta=theta)
    types = _joint_types(prismatic, n)
    T_fixed, screws = [], []
    z_rot, z_lin = np.array([0, 0, 1, 0, 0, 0.0]), np.array([0, 0, 0, 0, 0, 1.0])
    for i, t in enumerate(types):
        M = sp.transform(sp.rot_z(c["theta"][i]), (0.0, 0.0, c["d"][i]))
        M = M @ sp.transform(sp.rot_x(c["alpha"][i]), (c["a"][i], 0.0, 0.0))
        T_fixed.append(M)
        # RotZ(q) M = M exp(Ad_{M^-1} [z] q): the joint screw seen from the distal frame.
        screws.append(sp.adjoint(sp.inverse(M), z_rot if t == "revolute" else z_lin))
    return Robot(T_fixed, screws, types, params, gravity, name=name, joint_names=joint_names)


def rs010n() -> Robot:
    """The paper's robot: first three joints of the Kawasaki RS010N (Section 2, Tables 1-2).

    Modified DH as read in ``docs/explanation/paper-notes.md`` Sec. 1: joint 1 vertical,
    ``alpha = (0, -pi/2, 0)``, ``a = (0, 0.350, 1.035)`` m, ``d = 0``. Table 1 lists
    ``alpha_{i-1}, a_{i-1}`` one row early; read literally, joint 1 would be horizontal.
    Parameters: Table 2 (:data:`sedsabso_jax.paper.TABLE2`), first moments ``m * (x, y, z)``
    with the CoM converted to metres.
    Table 2 is kept as published although some of its inertias are not physically
    consistent (``Ixx2 = -10.02``).
    """
    t = TABLE2
    params = []
    for i in range(3):
        m = t["m"][i]
        com = np.array([t["x_mm"][i], t["y_mm"][i], t["z_mm"][i]]) / 1000.0
        params += [t[k][i] for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")]
        params += [m, *(m * com), t["Fc"][i], t["Fv"][i]]
    assert len(params) == 3 * N_LINK_PARAMETERS
    return from_mdh(alpha=(0.0, -np.pi / 2, 0.0), a=(0.0, 0.350, 1.035), d=(0.0, 0.0, 0.0),
                    params=params, name="RS010N", joint_names=("J1", "J2", "J3"))


def kuka_lwr4_urdf() -> AbstractContextManager[Path]:
    """Context manager giving a file path of the vendored KUKA LWR4+ URDF."""
    path = resources.files("sedsabso_jax") / "data" / "kuka_lwr4" / "kuka_lwr4.urdf"
    return resources.as_file(path)


def staubli_tx40_urdf() -> AbstractContextManager[Path]:
    """Context manager giving a file path of the vendored Staubli TX40 URDF (FIGAROH,
    Apache-2.0; modified-DH link frames and a-priori inertials)."""
    path = (resources.files("sedsabso_jax") / "data" / "staubli_tx40"
            / "tx40_mdh_modified.urdf")
    return resources.as_file(path)


def staubli_tx40() -> Robot:
    """The Staubli TX40 (6 revolute joints, coupled wrist) from its URDF, with its
    a-priori inertials. Its encoders and torques are motor side: see
    :class:`~sedsabso_jax.measurements._transmission.Transmission`."""
    with staubli_tx40_urdf() as p:
        return from_urdf(p)


#: The Franka Emika Panda's kinematics, modified DH (Craig): per joint ``alpha_{i-1}``
#: [rad], ``a_{i-1}`` [m], ``d_i`` [m] (Franka's published table, as used by Gaz et al.,
#: IEEE RA-L 4(4), 2019); the flange (``d = 0.107`` m) carries no moving joint.
FRANKA_PANDA_MDH = {
    "alpha": (0.0, -np.pi / 2, np.pi / 2, np.pi / 2, -np.pi / 2, np.pi / 2, np.pi / 2),
    "a": (0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088),
    "d": (0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0),
}


def franka_panda() -> Robot:
    """The Franka Emika Panda's 7 joints (modified DH, :data:`FRANKA_PANDA_MDH`). Franka
    publishes no inertial parameters: ``params`` are zero (no prior)."""
    t = FRANKA_PANDA_MDH
    return from_mdh(t["alpha"], t["a"], t["d"], name="franka_panda",
                    joint_names=tuple(f"panda_joint{i}" for i in range(1, 8)))


def kuka_lwr4() -> Robot:
    """The KUKA LWR4+ from its URDF (FloBaRoID, LGPL-3.0), with its a-priori inertials."""
    with kuka_lwr4_urdf() as p:
        return from_urdf(p)


#: The robots :func:`load` knows by name.
BUILTIN = {"rs010n": rs010n, "kuka_lwr4": kuka_lwr4, "staubli_tx40": staubli_tx40,
           "franka_panda": franka_panda}


def load(spec: str, tip: str | None = None) -> Robot:
    """A robot named as on the command line: one of :data:`BUILTIN`, a ``.urdf`` file or
    a MuJoCo MJCF ``.xml`` file (``tip``: the file's tip link or body, for trees that
    branch)."""
    if spec in BUILTIN:
        if tip is not None:
            raise ValueError(f"--tip applies to URDF files (and MJCF files), not to the "
                             f"built-in robot {spec!r}")
        return BUILTIN[spec]()
    if not str(spec).lower().endswith((".urdf", ".xml")):
        raise ValueError(f"--robot must be one of {tuple(BUILTIN)}, a .urdf file or an MJCF "
                         f".xml file, got {spec!r}")
    if not os.path.isfile(spec):
        raise ValueError(f"--robot: no such file {spec!r}")
    if str(spec).lower().endswith(".xml"):
        return from_mjcf(spec, tip=tip)  # imports mujoco
    return from_urdf(spec, tip=tip)

