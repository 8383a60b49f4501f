"""Identified parameters written into the robot's own MJCF (``mujoco`` extra).

:func:`update_mjcf` edits the file's XML text (lxml), not MuJoCo's ``MjSpec.to_xml()``:
the spec's writer keeps 6 significant digits (``mass="1.23457"``), writes the compiled
form (inertias diagonalised into ``quat`` + ``diaginertia``, ``<motor>`` as
``<general>``, default sizes expanded, a welded body's geom masses set to 0), so the
written dynamics would be off by 1e-6 and the file no longer the user's. Editing the
text keeps everything that is not replaced byte for byte: comments, defaults, classes,
includes, asset and mesh paths (relative paths stay relative: write the result in the
source's directory, or make ``meshdir``/``texturedir``/``<include file>`` absolute).
MuJoCo compiles the source first (the chain is checked against ``robot``), and the
result is compiled and read back with :func:`~sedsabso_jax.robots.from_mjcf` before it
is returned (a temporary file next to the source, else in the temporary directory).
"""

from __future__ import annotations

import os
import tempfile
import warnings
from os import PathLike

import numpy as np
from jaxtyping import ArrayLike, Float

from ._inertia import inertia_matrix
from ._mjcf import JOINT_KIND, compiled, from_mjcf, joint_side_armature, object_name
from ._mjcf_writer import FRICTION_SOLIMP
from ._robot import Robot
from ._urdf_writer import checked_params

#: The mass (kg) and principal inertias (kg m^2) a body that moves on its own joint off
#: the chain keeps, at its frame's origin: MuJoCo refuses a moving body without mass
#: ("mass and inertia of moving bodies must be larger than mjMINVAL"). It is subtracted
#: from the identified link the body hangs on (at that joint's ``qpos = 0``).
NEGLIGIBLE = 1e-9
#: The agreement (relative to the largest parameter) the written file's parameters, read
#: back, must have with the identified ones.
READ_BACK_RTOL = 1e-10


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in np.atleast_1d(v))


def _inertial_attributes(p10) -> dict[str, str]:
    """``<inertial>`` attributes of 10 origin-referenced parameters: the centre of mass
    and the inertia about it, in the body frame (as the writer's ``_inertial``)."""
    m, h = float(p10[6]), np.asarray(p10[7:10], dtype=float)
    c = h / m
    I_c = inertia_matrix(p10[:6]) - m * (c @ c * np.eye(3) - np.outer(c, c))
    full = [I_c[0, 0], I_c[1, 1], I_c[2, 2], I_c[0, 1], I_c[0, 2], I_c[1, 2]]
    return {"pos": _vec(c), "mass": repr(m), "fullinertia": _vec(full)}


def _owner(element):
    """The nearest ``<body>`` (or ``<worldbody>``) above ``element``."""
    parent = element.getparent()
    while parent is not None and parent.tag not in ("body", "worldbody"):
        parent = parent.getparent()
    return parent


def _set_inertial(body, attributes: dict[str, str]) -> None:
    """Replace ``body``'s ``<inertial>`` elements by one with ``attributes``, where the
    first was (else first in the body)."""
    from lxml import etree

    old = body.findall("inertial")
    at = body.index(old[0]) if old else 0
    tail = old[0].tail if old else (body.text if len(body) else None)
    for element in old:
        body.remove(element)
    new = etree.Element("inertial", attributes)
    new.tail = tail
    body.insert(at, new)


def _read_back(text: str, source: str, tip: str) -> np.ndarray:
    """The parameters :func:`from_mjcf` reads from ``text``, compiled as a file next to
    ``source`` (relative assets resolve) or, where that directory is not writable, in the
    temporary directory."""
    for directory in (os.path.dirname(os.path.abspath(source)), None):
        try:
            fd, path = tempfile.mkstemp(suffix=".xml", prefix=".update_mjcf_", dir=directory)
        except OSError:
            continue
        try:
            with os.fdopen(fd, "w") as fh:
                fh.write(text)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # armature, locked joints: as the source
                return np.asarray(from_mjcf(path, tip=tip).params, dtype=float)
        finally:
            os.remove(path)
    raise OSError(f"no writable directory to compile the updated {source!r} in")


def update_mjcf(source: str | PathLike[str], robot: Robot,
                params: Float[ArrayLike, " p"] | None = None, *,
                armature: Float[ArrayLike, " n"] | None = None,
                comment: str | None = None) -> str:
    """The MJCF ``source`` (the file ``robot`` was read from with
    :func:`~sedsabso_jax.robots.from_mjcf`) with ``params`` (12 per link, default
    ``robot.params``, physically consistent) written into it.

    Each link's body gets the link's identified ``<inertial>`` (``pos`` the centre of
    mass, ``fullinertia`` about it, in the body frame; an ``<inertial>`` is explicit, so
    geoms add no mass), its joint ``damping`` (viscous, the only damping term),
    ``frictionloss`` (Coulomb) and ``solimpfriction`` =
    :data:`~sedsabso_jax.dynamics._mjcf_writer.FRICTION_SOLIMP` (the dry-friction
    constraint nearly hard, so that ``frictionloss`` acts as Coulomb friction). The
    robot's link frame is MuJoCo's body frame (from_mjcf folds a joint's ``ref`` into
    ``T_fixed`` so that ``q = qpos``; the body frame moves with the body), so the
    parameters go in as they are, ``ref`` or not.

    The bodies from_mjcf merged into a link (welded bodies below it, bodies off the chain
    hanging on it) get an ``<inertial mass="0">``: the identified body already holds
    them. A body among them that has its own joint (locked at 0 in the robot, free in
    MuJoCo) cannot be massless; it keeps :data:`NEGLIGIBLE` mass and principal inertias at
    its origin, subtracted from the link's, so the file's dynamics are the identified ones
    with those joints at ``qpos = 0``. ``armature`` (joint side, as
    :func:`~sedsabso_jax.robots.armature_from_mjcf` gives it: an actuator's armature,
    MuJoCo >= 4, counts and is kept) sets the joints' ``armature``; default: the file's.
    Everything else is the file's text, comments included; ``comment`` is added as an XML
    comment first in ``<mujoco>``. The result is compiled and read back: its parameters
    are ``params`` to :data:`READ_BACK_RTOL` (compiler settings such as ``settotalmass``,
    ``boundmass`` or ``inertiafromgeom="true"`` that change them are refused).

    Raises ValueError if the file's chain (body and joint names, joint kinds) is not
    ``robot``'s, or a link's body or joint is not in the file's own text (an
    ``<include>``d file).
    """
    from lxml import etree

    p = checked_params(robot, params, "an MJCF")
    mujoco, m, where = compiled(source)
    n = robot.n_joints
    # --- the chain as MuJoCo compiles it: the movable bodies from the world to the tip
    bodies = []
    for i, (jname, lname) in enumerate(zip(robot.joint_names, robot.link_names)):
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, lname)
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jname)
        if b < 1 or j < 0 or m.jnt_bodyid[j] != b or m.body_jntnum[b] != 1 or \
                JOINT_KIND.get(int(m.jnt_type[j])) != robot.joint_types[i]:
            raise ValueError(f"MJCF {where!r} does not match robot {robot.name!r}: no "
                             f"{robot.joint_types[i]} joint {jname!r} alone in body {lname!r}")
        bodies.append(b)
    on_path, b = [], bodies[-1]
    while b:
        if m.body_jntnum[b]:
            on_path.append(object_name(mujoco, m, "body", b))
        b = int(m.body_parentid[b])
    if on_path[::-1] != list(robot.link_names):
        raise ValueError(f"MJCF {where!r} does not match robot {robot.name!r}: the movable "
                         f"bodies from the world to {robot.link_names[-1]!r} are "
                         f"{on_path[::-1]}, the robot's links {list(robot.link_names)}")
    joint_armature: np.ndarray | None = None
    if armature is not None:
        given = np.asarray(armature, dtype=float)
        if given.shape != (n,) or not np.all(np.isfinite(given)):
            raise ValueError(f"armature must be {n} finite numbers (one per joint), got "
                             f"shape {given.shape}")
        dofs = [m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)]
                for jn in robot.joint_names]
        # the actuators' share stays where it is: the joints get the rest
        actuators = joint_side_armature(mujoco, m, where, robot.joint_names) \
            - np.asarray(m.dof_armature[dofs], dtype=float)
        joint_armature = given - actuators
        if np.any(joint_armature < 0):
            raise ValueError(f"armature must be >= 0 (beyond the actuators' armature), "
                             f"got joint armature {joint_armature}")
    # --- the file's own text
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                             remove_blank_text=False, remove_comments=False)
    with open(where, "rb") as fh:
        root = etree.fromstring(fh.read(), parser)
    xml_bodies = {e.get("name"): e for e in root.iter("body") if e.get("name")}
    xml_joints = {e.get("name"): e for e in root.iter("joint") if e.get("name")}
    for jname, lname in zip(robot.joint_names, robot.link_names):
        if lname not in xml_bodies or jname not in xml_joints or \
                _owner(xml_joints[jname]) is not xml_bodies[lname]:
            raise ValueError(f"MJCF {where!r}: body {lname!r} with joint {jname!r} of robot "
                             f"{robot.name!r} is not in the file's own text (in an "
                             "<include>d file?); update that file")
    negligible = {"pos": "0 0 0", "mass": repr(NEGLIGIBLE),
                  "diaginertia": _vec([NEGLIGIBLE] * 3)}
    links = [xml_bodies[name] for name in robot.link_names]
    for i, link in enumerate(links):
        below = links[i + 1] if i + 1 < n else None
        stack = [c for c in link.iter("body") if c is not link and _owner(c) is link]
        while stack:  # the bodies merged into this link
            body = stack.pop()
            if body is below:
                continue
            moves = any(_owner(e) is body for e in body.iter("joint", "freejoint"))
            _set_inertial(body, negligible if moves else
                          {"pos": "0 0 0", "mass": "0", "diaginertia": "0 0 0"})
            stack += [c for c in body.iter("body") if c is not body and _owner(c) is body]
        joint = xml_joints[robot.joint_names[i]]
        joint.set("damping", repr(float(p[i, 11])))
        joint.set("frictionloss", repr(float(p[i, 10])))
        joint.set("solimpfriction", _vec(FRICTION_SOLIMP))
        if joint_armature is not None:
            joint.set("armature", repr(float(joint_armature[i])))
    if comment:
        note = etree.Comment(" " + comment.replace("--", "- -") + " ")
        note.tail = root.text
        root.insert(0, note)

    def text(link_params: np.ndarray) -> str:
        for link, p10 in zip(links, link_params):
            _set_inertial(link, _inertial_attributes(p10))
        return etree.tostring(root.getroottree(), encoding="unicode") + "\n"

    tip = robot.link_names[-1]
    # the bodies left with a negligible mass are read into the links: subtract them
    # (from_mjcf's parameters are linear in the bodies' inertials)
    target = p[:, :10]
    extra = _read_back(text(target), where, tip).reshape(n, 12)[:, :10] - target
    if np.max(np.abs(extra) / np.max(np.abs(target), axis=1, keepdims=True)) > 1e-6:
        raise ValueError(
            f"MJCF {where!r}: MuJoCo compiles the updated file to other inertials than "
            "written; its <compiler> changes them (inertiafromgeom=\"true\", "
            "settotalmass, boundmass, boundinertia, balanceinertia?)")
    written = target - extra
    out = text(written)
    got = _read_back(out, where, tip).reshape(n, 12)
    scale = np.max(np.abs(p), axis=1, keepdims=True)
    error = np.max(np.abs(got - p) / scale)
    if error > READ_BACK_RTOL:
        raise ValueError(
            f"MJCF {where!r}: MuJoCo compiles the updated file to parameters off by "
            f"{error:.2g} (relative) from the identified ones; its <compiler> changes "
            "inertials (inertiafromgeom=\"true\", settotalmass, boundmass, boundinertia, "
            "balanceinertia?)")
    return out
