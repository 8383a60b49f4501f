"""Robot -> URDF: the model's kinematics with given link parameters, for simulators.

Each movable joint becomes a URDF joint whose child link carries that link's 10 inertial
parameters (converted to mass, centre of mass and inertia about it), and whose
``<dynamics friction damping>`` are the Coulomb and viscous coefficients. A joint whose
screw does not pass through its link frame's origin (standard DH) gets a joint frame on
the axis and a fixed joint back to the link frame. Fixed joints and off-chain links of a
source URDF are not written: their inertia is part of the link they were merged into.
The written file parses back to the same dynamics (tested with pinocchio and with
:func:`~sedsabso_jax.robots.from_urdf`).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np
from jaxtyping import ArrayLike, Float

from ._inertia import inertia_matrix, is_physically_consistent
from ._robot import N_LINK_PARAMETERS, Robot
from ._spatial import rpy_from_matrix, transform


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def _origin(T) -> str:
    return (f'<origin xyz="{_vec(T[:3, 3])}" rpy="{_vec(rpy_from_matrix(T[:3, :3]))}"/>')


def _inertial(p10) -> str:
    m, h = float(p10[6]), np.asarray(p10[7:10], dtype=float)
    c = h / m
    I_c = inertia_matrix(p10[:6]) - m * (c @ c * np.eye(3) - np.outer(c, c))
    entries = " ".join(f'{k}="{float(I_c[a, b])!r}"' for k, (a, b) in (
        ("ixx", (0, 0)), ("ixy", (0, 1)), ("ixz", (0, 2)), ("iyy", (1, 1)), ("iyz", (1, 2)),
        ("izz", (2, 2))))
    return (f'<inertial><origin xyz="{_vec(c)}" rpy="0 0 0"/><mass value="{m!r}"/>'
            f'<inertia {entries}/></inertial>')


def to_urdf(robot: Robot, params: Float[ArrayLike, " p"] | None = None, *,
            comment: str | None = None) -> str:
    """URDF text of ``robot`` with ``params`` (12 per link, default ``robot.params``),
    which must be physically consistent (every link a real body: positive mass, inertia
    satisfying the triangle inequalities); ``comment`` goes into an XML comment."""
    p = np.asarray(robot.params if params is None else params, dtype=float)
    if p.shape != (robot.n_params,) or not np.all(np.isfinite(p)):
        raise ValueError(f"params must be {robot.n_params} finite numbers (12 per link) for "
                         f"robot {robot.name!r}, got shape {p.shape}")
    if not is_physically_consistent(p):
        raise ValueError("a URDF needs physically consistent link parameters (positive mass, "
                         "positive-definite pseudo-inertia per link): identify with "
                         "physical=True (--physical)")
    p = p.reshape(robot.n_joints, N_LINK_PARAMETERS)
    lines = ['<?xml version="1.0"?>', f"<robot name={quoteattr(robot.name)}>"]
    if comment:
        lines.append("  <!-- " + comment.replace("--", "- -") + " -->")
    parent = "base_link"
    lines.append(f'  <link name="{parent}"/>')
    T_fixed, screws = np.asarray(robot.T_fixed), np.asarray(robot.screws)
    for i, (jname, lname, kind) in enumerate(zip(robot.joint_names, robot.link_names,
                                                 robot.joint_types)):
        w, v = screws[i, :3], screws[i, 3:]
        if kind == "revolute":
            axis, on_axis = w, np.cross(w, v)  # the axis' point closest to the origin
        else:
            axis, on_axis = v, np.zeros(3)
        child = lname if not np.any(on_axis) else f"{lname}_joint_frame"
        lines += [f"  <joint name={quoteattr(jname)} type=\"{kind}\">",
                  f"    {_origin(T_fixed[i] @ transform(translation=on_axis))}",
                  f'    <parent link={quoteattr(parent)}/><child link={quoteattr(child)}/>',
                  f'    <axis xyz="{_vec(axis)}"/>',
                  '    <limit lower="-1e9" upper="1e9" effort="1e9" velocity="1e9"/>',
                  f'    <dynamics damping="{float(p[i, 11])!r}" friction="{float(p[i, 10])!r}"/>',
                  "  </joint>"]
        if child != lname:
            lines += [f"  <link name={quoteattr(child)}/>",
                      f"  <joint name={quoteattr(jname + '_to_link')} type=\"fixed\">",
                      f"    {_origin(transform(translation=-on_axis))}",
                      f'    <parent link={quoteattr(child)}/><child link={quoteattr(lname)}/>',
                      "  </joint>"]
        lines.append(f"  <link name={quoteattr(lname)}>{_inertial(p[i, :10])}</link>")
        parent = lname
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
