"""Robot -> URDF: the model's kinematics with given link parameters, for simulators.

Each movable joint becomes a URDF joint whose child link carries that link's 10 inertial
parameters (converted to mass, centre of mass and inertia about it), and whose
``<dynamics friction damping>`` are the Coulomb and viscous coefficients. A joint whose
screw does not pass through its link frame's origin (standard DH) gets a joint frame on
the axis and a fixed joint back to the link frame. Fixed joints and off-chain links of a
source URDF are not written: their inertia is part of the link they were merged into.
The written file parses back to the same dynamics (tested with pinocchio and with
:func:`~sedsabso_jax.robots.from_urdf`).

:func:`update_urdf` instead rewrites the robot's own URDF: only the identified links'
``<inertial>`` and the movable joints' ``<dynamics>`` change; names, limits, geometry,
materials, transmissions, simulator elements and comments stay as they were.
"""

from __future__ import annotations

import os
from collections import defaultdict
from os import PathLike
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
    p = checked_params(robot, params, "a URDF")
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


def checked_params(robot: Robot, params: Float[ArrayLike, " p"] | None,
                   what: str) -> np.ndarray:
    """``params`` (default ``robot.params``) as ``(n, 12)``, finite and physically
    consistent, for ``what`` (``"a URDF"``) to hold."""
    p = np.asarray(robot.params if params is None else params, dtype=float)
    if p.shape != (robot.n_params,) or not np.all(np.isfinite(p)):
        raise ValueError(f"params must be {robot.n_params} finite numbers (12 per link) for "
                         f"robot {robot.name!r}, got shape {p.shape}")
    if not is_physically_consistent(p):
        raise ValueError(f"{what} needs physically consistent link parameters (positive mass, "
                         "positive-definite pseudo-inertia per link): identify with "
                         "physical=True (--physical)")
    return p.reshape(robot.n_joints, N_LINK_PARAMETERS)


def update_urdf(source: str | PathLike[str], robot: Robot,
                params: Float[ArrayLike, " p"] | None = None, *,
                comment: str | None = None) -> str:
    """The URDF ``source`` (the file ``robot`` was read from) with ``params`` (12 per link,
    default ``robot.params``, physically consistent) written into it.

    Each movable joint's child link gets the link's identified ``<inertial>`` (centre of
    mass as the origin, ``rpy="0 0 0"``, the inertia about the centre of mass); the
    joint's ``<dynamics>`` gets ``friction`` (Coulomb) and ``damping`` (viscous), made if
    missing. A link :func:`~sedsabso_jax.robots.from_urdf` merged into an identified one
    (a fixed child, a tool, a gripper's fingers off the chain) loses its ``<inertial>``:
    the identified body already holds it, so the file's dynamics (at the off-chain joints'
    zero) are the fit's. Everything else, comments included (whitespace inside the replaced
elements aside), is kept; ``comment`` is added
    as an XML comment first in ``<robot>``. Raises ValueError if the file's joints are not
    ``robot``'s."""
    from lxml import etree

    from ._urdf import read_checked

    p = checked_params(robot, params, "a URDF")
    read_checked(source)  # well-formed, no DTD or entity
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                             remove_blank_text=False, remove_comments=False)
    with open(source, "rb") as fh:
        root = etree.fromstring(fh.read(), parser)
    joints = {j.get("name"): j for j in root.findall("joint")}
    links = {link.get("name"): link for link in root.findall("link")}
    children: defaultdict[str, list] = defaultdict(list)
    for j in joints.values():
        parent, child = j.find("parent"), j.find("child")
        if parent is not None and child is not None:
            children[parent.get("link")].append(j)
    where = os.fspath(source)
    identified = set(robot.joint_names)
    for i, (jname, lname) in enumerate(zip(robot.joint_names, robot.link_names)):
        joint = joints.get(jname)
        child = None if joint is None else joint.find("child")
        if joint is None or child is None or child.get("link") != lname or lname not in links:
            raise ValueError(f"URDF {where!r} does not match robot {robot.name!r}: no joint "
                             f"{jname!r} moving link {lname!r}")
        link = links[lname]
        before = link.find("inertial")
        at, tail = (0, link.text) if before is None else (link.index(before), before.tail)
        stack = [lname]
        while stack:  # the links merged into this one: all below it up to the next joint
            name = stack.pop()
            for old in links[name].findall("inertial"):
                links[name].remove(old)
            stack += [c.find("child").get("link") for c in children[name]
                      if c.get("name") not in identified]
        new = etree.fromstring(_inertial(p[i, :10]))
        indent = (link.text or "\n").rsplit("\n", 1)[-1] if "\n" in (link.text or "") else ""
        if indent:  # one element a line, as the file has them
            new.text = "\n" + indent + "  "
            for k, element in enumerate(new):
                element.tail = "\n" + indent + ("  " if k < len(new) - 1 else "")
        new.tail = tail
        link.insert(at, new)
        dynamics = joint.find("dynamics")
        if dynamics is None:
            dynamics = etree.SubElement(joint, "dynamics")
        dynamics.set("damping", repr(float(p[i, 11])))
        dynamics.set("friction", repr(float(p[i, 10])))
    if comment:
        note = etree.Comment(" " + comment.replace("--", "- -") + " ")
        note.tail = root.text
        root.insert(0, note)
    # the whole document: comments before and after <robot> too
    return '<?xml version="1.0"?>\n' + etree.tostring(root.getroottree(),
                                                       encoding="unicode") + "\n"
