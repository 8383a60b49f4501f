"""Robot -> MJCF: the chain with given link parameters as a MuJoCo model that loads as
written and can be simulated.

Each link becomes a ``<body>`` at its frame at ``q = 0`` (``T_fixed``), with one joint
(``hinge`` about the screw's axis through its point closest to the link origin, or
``slide``), the link's 10 inertial parameters as ``<inertial>`` (mass, centre of mass,
``fullinertia`` about it), the joint's Coulomb and viscous friction as ``frictionloss``
and ``damping``, and an optional rotor inertia as ``armature``. Each joint gets one
actuator of torque (force for a slide): ``ctrl`` is the joint torque a torque sensor
reads, so a torque offset (the sensor's zero) is the actuator's bias,
``force = ctrl - offset``. A thin capsule from each link's origin to the next shows the
chain; it has no mass and takes part in no contact.

MuJoCo's ``frictionloss`` is dry friction held by a soft constraint, whose torque grows
with the velocity up to ``Fc`` over a scale set by the constraint's impedance and the
joint's inverse weight at ``qpos0``. With MuJoCo's default impedance (0.9-0.95) that scale
reaches rad/s on a joint that moves much of the arm, and the friction is mostly lost; the
writer makes the constraint nearly hard (:data:`FRICTION_SOLIMP`) so that the torque is
``Fc sign(qd)`` but within a few mrad/s of rest, as the package's Coulomb column
(docs/explanation/mujoco.md).
"""

from __future__ import annotations

from xml.sax.saxutils import escape, quoteattr

import numpy as np
from jaxtyping import ArrayLike, Float
from scipy.spatial.transform import Rotation

from ._inertia import inertia_matrix
from ._limits import JointLimits
from ._robot import Robot
from ._urdf_writer import checked_params

#: The dry-friction constraint's impedance (MuJoCo's ``solimpfriction``: dmin, dmax,
#: width): nearly hard, so that ``frictionloss`` acts as Coulomb friction.
FRICTION_SOLIMP = (0.999, 0.999, 0.001)
#: MuJoCo integrators the writer accepts (``<option integrator>``).
INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in np.atleast_1d(v))


def _quat(R) -> str:
    x, y, z, w = Rotation.from_matrix(np.asarray(R, float)).as_quat()
    return _vec([w, x, y, z])


def _inertial(p10) -> str:
    m, h = float(p10[6]), np.asarray(p10[7:10], dtype=float)
    c = h / m
    I_c = inertia_matrix(p10[:6]) - m * (c @ c * np.eye(3) - np.outer(c, c))
    full = [I_c[0, 0], I_c[1, 1], I_c[2, 2], I_c[0, 1], I_c[0, 2], I_c[1, 2]]
    return f'<inertial pos="{_vec(c)}" mass="{m!r}" fullinertia="{_vec(full)}"/>'


def _per_joint(label: str, values, n: int) -> np.ndarray:
    out = np.zeros(n) if values is None else np.asarray(values, dtype=float)
    if out.shape != (n,) or not np.all(np.isfinite(out)):
        raise ValueError(f"{label} must be {n} finite numbers (one per joint), got "
                         f"shape {out.shape}")
    return out


def to_mjcf(robot: Robot, params: Float[ArrayLike, " p"] | None = None, *,
            armature: Float[ArrayLike, " n"] | None = None,
            offset: Float[ArrayLike, " n"] | None = None,
            limits: JointLimits | None = None, timestep: float = 0.002,
            integrator: str = "implicitfast", comment: str | None = None) -> str:
    """MJCF text of ``robot`` with ``params`` (12 per link, default ``robot.params``,
    physically consistent).

    Args:
        armature: each joint's rotor inertia seen at the joint (kg m^2 or kg), ``>= 0``;
            default 0.
        offset: each joint's torque offset (N m or N): the actuators' bias, so that
            ``ctrl`` is the torque as measured; default 0.
        limits: the joints' position ranges, written where finite; default none. Torque
            limits are not written: the actuators pass any torque (measured torques may
            exceed a datasheet's), MuJoCo's ``forcerange`` clips them if a user adds it.
        timestep: MuJoCo's ``<option timestep>`` (s).
        integrator: MuJoCo's ``<option integrator>``, one of :data:`INTEGRATORS`.
        comment: an XML comment at the top of the model.
    """
    p = checked_params(robot, params, "an MJCF")
    n = robot.n_joints
    armature = _per_joint("armature", armature, n)
    offset = _per_joint("offset", offset, n)
    if np.any(armature < 0):
        raise ValueError(f"armature must be >= 0, got {armature}")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if not (np.isfinite(timestep) and timestep > 0):
        raise ValueError(f"timestep must be a positive number of seconds, got {timestep!r}")
    if limits is not None and len(limits.names) != n:
        raise ValueError(f"limits are for {len(limits.names)} joints, the robot has {n}")
    T_fixed, screws = np.asarray(robot.T_fixed), np.asarray(robot.screws)
    lines = [f"<mujoco model={quoteattr(robot.name)}>"]
    if comment:
        lines.append("  <!-- " + escape(comment).replace("--", "- -") + " -->")
    lines += ['  <compiler angle="radian" autolimits="true"/>',
              f'  <option gravity="{_vec(robot.gravity)}" timestep="{timestep!r}" '
              f'integrator="{integrator}"/>',
              f'  <default><joint solimpfriction="{_vec(FRICTION_SOLIMP)}"/>',
              '    <geom type="capsule" size="0.02" contype="0" conaffinity="0" mass="0" '
              'group="1"/></default>',
              "  <worldbody>"]
    for i in range(n):
        indent = "  " * (i + 2)
        w, v = screws[i, :3], screws[i, 3:]
        revolute = robot.joint_types[i] == "revolute"
        axis, anchor = (w, np.cross(w, v)) if revolute else (v, np.zeros(3))
        joint = (f"<joint name={quoteattr(robot.joint_names[i])} "
                 f'type="{"hinge" if revolute else "slide"}" pos="{_vec(anchor)}" '
                 f'axis="{_vec(axis)}" armature="{float(armature[i])!r}" '
                 f'damping="{float(p[i, 11])!r}" frictionloss="{float(p[i, 10])!r}"')
        if limits is not None:
            lo, hi = float(limits.q_min[i]), float(limits.q_max[i])
            if np.isfinite(lo) and np.isfinite(hi):
                joint += f' range="{lo!r} {hi!r}"'
        lines += [f"{indent}<body name={quoteattr(robot.link_names[i])} "
                  f'pos="{_vec(T_fixed[i][:3, 3])}" quat="{_quat(T_fixed[i][:3, :3])}">',
                  f"{indent}  {joint}/>", f"{indent}  {_inertial(p[i, :10])}"]
        tip = T_fixed[i + 1][:3, 3] if i + 1 < n else np.zeros(3)
        if np.linalg.norm(tip) > 1e-6:
            lines.append(f'{indent}  <geom fromto="0 0 0 {_vec(tip)}"/>')
    lines += ["  " * (i + 2) + "</body>" for i in reversed(range(n))]
    lines += ["  </worldbody>", "  <actuator>"]
    for i, name in enumerate(robot.joint_names):
        lines.append(f"    <general name={quoteattr(name)} joint={quoteattr(name)} "
                     f'gainprm="1" biastype="affine" biasprm="{-float(offset[i])!r} 0 0"/>')
    lines += ["  </actuator>", "</mujoco>"]
    return "\n".join(lines) + "\n"
