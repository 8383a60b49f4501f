"""Joint limits in SI units: positions, speeds, accelerations and efforts, from the
paper's Table 3 (RS010N), a URDF's ``<limit>`` tags or an MJCF's ranges."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Sequence
from typing import TypeAlias

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._output import PathLike
from ..paper import TABLE3_DEG
from ._mjcf import joint_limit_rows as mjcf_limit_rows
from ._robot import Robot
from ._robots import kuka_lwr4_urdf, staubli_tx40_urdf
from ._urdf import joint_limit_rows

#: One limit per joint.
_PerJoint: TypeAlias = Float[ArrayLike, " n"] | Sequence[float]


class JointLimits(eqx.Module):
    """Joint limits in SI units: positions ``q_min, q_max`` (rad or m), speeds ``qd_max``
    (rad/s, m/s), accelerations ``qdd_max`` (``inf`` when unknown) and efforts ``tau_max``
    (N m or N; ``nan`` when unknown, informative only: trajectories are not checked
    against it). ``angular[j]`` says joint ``j`` is revolute (messages add degrees)."""

    q_min: Float[Array, " n"]
    q_max: Float[Array, " n"]
    qd_max: Float[Array, " n"]
    qdd_max: Float[Array, " n"]
    tau_max: Float[Array, " n"]
    names: tuple[str, ...] = eqx.field(static=True)
    angular: tuple[bool, ...] = eqx.field(static=True)

    def __init__(self, q_min: _PerJoint, q_max: _PerJoint, qd_max: _PerJoint,
                 qdd_max: _PerJoint | None = None, tau_max: _PerJoint | None = None, *,
                 names: Sequence[str] | None = None, angular: Sequence[bool] | None = None):
        q_min = np.asarray(q_min, dtype=float)
        n = q_min.shape[0] if q_min.ndim == 1 else None
        if n is None or n < 1:
            raise ValueError(f"q_min must be 1-D with one entry per joint, got shape "
                             f"{q_min.shape}")
        qdd_max = np.full(n, np.inf) if qdd_max is None else qdd_max
        tau_max = np.full(n, np.nan) if tau_max is None else tau_max
        arrays = {}
        for name, value in (("q_min", q_min), ("q_max", q_max), ("qd_max", qd_max),
                            ("qdd_max", qdd_max), ("tau_max", tau_max)):
            arr = np.asarray(value, dtype=float)
            if arr.shape != (n,):
                raise ValueError(f"{name} must have shape ({n},) like q_min, got {arr.shape}")
            if name != "tau_max" and np.any(np.isnan(arr)):
                raise ValueError(f"{name} contains NaN (use inf for an unknown limit)")
            arrays[name] = arr
        half_open = np.isfinite(arrays["q_min"]) != np.isfinite(arrays["q_max"])
        if np.any(half_open):
            j = int(np.flatnonzero(half_open)[0])
            raise ValueError(f"joint {j + 1}: position limits must be both finite or both "
                             f"infinite, got q_min {arrays['q_min'][j]}, q_max "
                             f"{arrays['q_max'][j]}")
        bad = np.flatnonzero(~(arrays["q_min"] < arrays["q_max"]))
        if bad.size:
            j = int(bad[0])
            raise ValueError(f"joint {j + 1}: q_min {arrays['q_min'][j]} must be below q_max "
                             f"{arrays['q_max'][j]}")
        for name in ("qd_max", "qdd_max", "tau_max"):
            bad = np.flatnonzero(arrays[name] <= 0)
            if bad.size:
                j = int(bad[0])
                raise ValueError(f"joint {j + 1}: {name} must be > 0, got {arrays[name][j]}")
        self.q_min, self.q_max, self.qd_max, self.qdd_max, self.tau_max = (
            jnp.asarray(arrays[k]) for k in ("q_min", "q_max", "qd_max", "qdd_max", "tau_max"))
        names = tuple(f"J{j + 1}" for j in range(n)) if names is None else tuple(map(str, names))
        if len(names) != n:
            raise ValueError(f"names must have {n} entries, got {len(names)}: {names}")
        angular = (True,) * n if angular is None else tuple(bool(x) for x in angular)
        if len(angular) != n:
            raise ValueError(f"angular must have {n} entries, got {len(angular)}")
        self.names, self.angular = names, angular

    @property
    def n_joints(self) -> int:
        return self.q_min.shape[0]

    @property
    def torque_limits(self) -> np.ndarray | None:
        """``tau_max`` as a numpy array when every joint's effort limit is known, else
        None (what the NRMS over the limits and the 1/limit weighting need)."""
        tau_max = np.asarray(self.tau_max, dtype=float)
        return tau_max if np.all(np.isfinite(tau_max) & (tau_max > 0)) else None

    @classmethod
    def rs010n(cls) -> JointLimits:
        """The paper's Table 3 for the RS010N's first three joints, converted from deg,
        deg/s and deg/s^2. Joint 2's range (-60, 140) and joint 3's (-180, 80) are not
        symmetric. No torque limits are given (``tau_max`` is nan)."""
        deg = {key: np.array(value) * (math.pi / 180) for key, value in TABLE3_DEG.items()}
        return cls(deg["q_min"], deg["q_max"], deg["qd_max"], deg["qdd_max"],
                   names=("J1", "J2", "J3"))

    def __repr__(self) -> str:
        return f"JointLimits({self.n_joints} joints: {', '.join(self.names)})"


def joint_limits_from_urdf(path: PathLike, robot: Robot, *,
                          qdd_max: Float[ArrayLike, ""] | _PerJoint | None = None) -> JointLimits:
    """Limits of ``robot``'s joints from the ``<limit>`` tags of its URDF: ``lower,
    upper`` (a continuous joint, one without ``<limit>`` or one whose ``<limit>`` has
    neither ``lower`` nor ``upper``, or both 0: unbounded, with a warning), ``velocity``
    (missing or 0: unbounded) and ``effort`` as ``tau_max`` (missing or 0: nan). URDF has
    no acceleration limit: ``qdd_max`` (scalar or ``(n,)``) is taken from the argument,
    ``inf`` by default. The joints are found by ``robot.joint_names``."""
    rows = joint_limit_rows(path, robot.joint_names)
    return JointLimits(rows[:, 0], rows[:, 1], rows[:, 2], _accelerations(robot, qdd_max),
                       rows[:, 3],
                       names=robot.joint_names,
                       angular=[t == "revolute" for t in robot.joint_types])


def _accelerations(robot: Robot, qdd_max) -> np.ndarray:
    """``qdd_max`` (None: ``inf``; a scalar or one per joint) as one per joint."""
    n = robot.n_joints
    qdd = np.full(n, np.inf) if qdd_max is None else np.asarray(qdd_max, dtype=float)
    if qdd.shape not in ((), (n,)):
        raise ValueError(f"qdd_max must be a scalar or have shape ({n},) for robot "
                         f"{robot.name!r}, got {qdd.shape}")
    return np.broadcast_to(qdd, (n,))


def joint_limits_from_mjcf(path: PathLike, robot: Robot, *,
                           qdd_max: Float[ArrayLike, ""] | _PerJoint | None = None
                           ) -> JointLimits:
    """Limits of ``robot``'s joints from an MJCF file (compiled by MuJoCo): ``range``
    where the joint is limited (else unbounded), and as ``tau_max`` the largest force the
    joint's actuators apply: the joint's ``actuatorfrcrange``, else its actuators'
    ``forcerange`` or, for a motor, ``ctrlrange`` times ``gear`` (else nan). MJCF has no
    speed or acceleration limit: ``qd_max`` is ``inf`` and ``qdd_max`` (scalar or
    ``(n,)``) is taken from the argument, ``inf`` by default. The joints are found by
    ``robot.joint_names``."""
    rows = mjcf_limit_rows(path, robot.joint_names)
    return JointLimits(rows[:, 0], rows[:, 1], np.full(robot.n_joints, np.inf),
                       _accelerations(robot, qdd_max),
                       rows[:, 2], names=robot.joint_names,
                       angular=[t == "revolute" for t in robot.joint_types])


#: The Franka Emika Panda's joint limits from Franka's robot and interface specifications
#: (rad, rad/s, rad/s^2, N m).
FRANKA_PANDA_LIMITS = {
    "q_min": (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973),
    "q_max": (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973),
    "qd_max": (2.1750, 2.1750, 2.1750, 2.1750, 2.6100, 2.6100, 2.6100),
    "qdd_max": (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0),
    "tau_max": (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0),
}


def joint_limits(spec: str, robot: Robot) -> JointLimits:
    """The limits of a robot named as on the command line (see
    :func:`sedsabso_jax.robots.load`): ``"rs010n"`` the paper's Table 3 (no efforts),
    ``"franka_panda"`` :data:`FRANKA_PANDA_LIMITS`, ``"kuka_lwr4"`` and
    ``"staubli_tx40"`` their vendored URDFs, a ``.urdf`` or MJCF ``.xml`` path that
    file."""
    if spec == "rs010n":
        return JointLimits.rs010n()
    if spec == "franka_panda":
        # mypy sees one value type for every key of the dict, angular's included
        return JointLimits(**FRANKA_PANDA_LIMITS,  # type: ignore[arg-type]
                           names=robot.joint_names)
    if str(spec).lower().endswith(".xml"):
        return joint_limits_from_mjcf(spec, robot)
    urdf = {"kuka_lwr4": kuka_lwr4_urdf, "staubli_tx40": staubli_tx40_urdf}.get(spec)
    with urdf() if urdf else contextlib.nullcontext(spec) as path:
        return joint_limits_from_urdf(path, robot)
