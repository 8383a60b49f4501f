"""MuJoCo MJCF -> :class:`Robot`, read from the model MuJoCo compiles (``mujoco`` extra).

The compiled model is what MuJoCo simulates: defaults applied, angles in radians,
inertias from geoms where a body has no ``<inertial>``, and (where the file asks for
``fusestatic``) static bodies already fused. A body's frame is MuJoCo's body frame: its
hinge turns it about ``jnt_axis`` through the anchor ``jnt_pos`` (both in the body frame),
so the body-frame screw is ``(w, -w x p)``; a slide moves it along ``jnt_axis``. ``q = 0``
is ``qpos = 0`` (a joint's ``ref`` is folded into ``T_fixed``). Bodies without a joint
(welded) merge into the movable body above; bodies off the base-to-tip path hang rigidly
on it (a joint there is locked at 0, with a warning); bodies hanging on the world off the
path (a table, a free object) are left out. ``dof_damping`` and ``dof_frictionloss``
become the joint's viscous and Coulomb friction; ``dof_armature`` has no place in the
rigid-body model (:func:`armature_from_mjcf`).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from jaxtyping import Float

from .._output import PathLike
from . import _spatial as sp
from ._inertia import params_from_com, transform_params
from ._robot import Robot

_INSTALL = "MJCF needs the mujoco extra: pip install 'sedsabso-jax[mujoco]'"
#: MuJoCo's ``mjtJoint`` values.
_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3
JOINT_KIND = {_SLIDE: "prismatic", _HINGE: "revolute"}
_MJ_NAME = {_FREE: "free", _BALL: "ball", _SLIDE: "slide", _HINGE: "hinge"}


class MJCFError(ValueError):
    """An MJCF file that cannot be turned into a serial chain."""


def compiled(path: PathLike) -> tuple[Any, Any, str]:
    """``(mujoco, compiled model, path)``; an MJCFError when MuJoCo cannot compile it."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise MJCFError(f"cannot read MJCF {path!r}: no such file")
    if not os.access(path, os.R_OK):
        raise MJCFError(f"cannot read MJCF {path!r}: permission denied")
    try:
        import mujoco
    except ImportError:
        raise ImportError(_INSTALL) from None
    try:
        model = mujoco.MjModel.from_xml_path(path)
    except ValueError as err:  # mujoco's parse and compile errors, with line numbers
        raise MJCFError(f"MJCF {path!r} could not be compiled by MuJoCo: {err}") from None
    return mujoco, model, path


def object_name(mujoco: Any, m: Any, kind: str, i: int) -> str:
    obj = getattr(mujoco.mjtObj, f"mjOBJ_{kind.upper()}")
    return mujoco.mj_id2name(m, obj, i) or f"{kind}{i}"


def _rotation(quat: np.ndarray) -> np.ndarray:
    """The rotation matrix of MuJoCo's ``(w, x, y, z)`` quaternion."""
    w, x, y, z = np.asarray(quat, float) / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _screw(m: Any, j: int) -> np.ndarray:
    """Joint ``j``'s unit screw ``(w, v)`` in its body's frame."""
    axis = np.asarray(m.jnt_axis[j], float)
    axis = axis / np.linalg.norm(axis)
    if m.jnt_type[j] == _SLIDE:
        return np.r_[0.0, 0.0, 0.0, axis]
    return np.r_[axis, -np.cross(axis, np.asarray(m.jnt_pos[j], float))]


def _motion(screw: np.ndarray, q: float) -> np.ndarray:
    """``exp([screw] q)`` for a unit revolute or prismatic screw."""
    w, v = screw[:3], screw[3:]
    if not np.any(w):
        return sp.transform(None, v * q)
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    R = np.eye(3) + np.sin(q) * K + (1 - np.cos(q)) * K @ K
    # a rotation about the axis through p, with v = -w x p: p - R p (w.v = 0)
    p = np.cross(w, v)
    return sp.transform(R, p - R @ p)


def _body_params(m: Any, b: int) -> np.ndarray:
    """10 inertial parameters of body ``b`` about its frame origin, in its frame."""
    T = sp.transform(_rotation(m.body_iquat[b]), m.body_ipos[b])
    com = params_from_com(float(m.body_mass[b]), np.zeros(3), np.diag(m.body_inertia[b]))
    return transform_params(T, com)


def _at_zero(m: Any, b: int) -> np.ndarray:
    """Body ``b``'s frame in its parent's with its hinge and slide joints at ``qpos = 0``
    (ball and free joints at their reference)."""
    T = sp.transform(_rotation(m.body_quat[b]), m.body_pos[b])
    for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]):
        if m.jnt_type[j] in JOINT_KIND:
            T = T @ _motion(_screw(m, j), -float(m.qpos0[m.jnt_qposadr[j]]))
    return T


def _chain(mujoco: Any, m: Any, path: str, tip: str | None) -> list[int]:
    """The bodies from the world (left out) to the tip, in order."""
    children: dict[int, list[int]] = {b: [] for b in range(m.nbody)}
    for b in range(1, m.nbody):
        children[int(m.body_parentid[b])].append(b)
    names = {object_name(mujoco, m, "body", b): b for b in range(m.nbody)}

    def moves(b: int) -> bool:
        return bool(m.body_jntnum[b]) or any(moves(c) for c in children[b])

    def leaves(b: int) -> list[str]:
        return ([object_name(mujoco, m, "body", b)] if not children[b]
                else [x for c in children[b] for x in leaves(c)])

    if tip is None:
        bodies, b = [], 0
        while True:
            onward = [c for c in children[b] if moves(c)]
            if not onward:
                break
            if len(onward) > 1:
                raise MJCFError(
                    f"MJCF {path!r} branches at body {object_name(mujoco, m, 'body', b)!r} into "
                    f"bodies {[object_name(mujoco, m, 'body', c) for c in onward]}; choose the tip "
                    f"body (--tip on the command line, tip= in Python), one of "
                    f"{sorted(x for c in onward for x in leaves(c))}")
            bodies.append(onward[0])
            b = onward[0]
        return bodies
    if tip not in names or names[tip] == 0:
        raise MJCFError(f"MJCF {path!r} has no body {tip!r} (tip); bodies: "
                        f"{sorted(n for n, b in names.items() if b)}")
    bodies, b = [], names[tip]
    while b:
        bodies.append(b)
        b = int(m.body_parentid[b])
    return bodies[::-1]


def from_mjcf(path: PathLike, *, tip: str | None = None, name: str | None = None) -> Robot:
    """Serial chain from an MJCF file (compiled by MuJoCo), from the world to body ``tip``.

    Every body on the path has at most one joint, a hinge or a slide (free and ball
    joints are refused); ``tip`` may be left out when the tree has one path of movable
    bodies. Joint and link names are the MJCF's joint and body names, the robot's name
    the model's (``name`` to override); gravity is the model's ``<option gravity>``.
    Friction is ``dof_frictionloss`` (Coulomb) and ``dof_damping`` (viscous); joint
    stiffness, armature and gravity compensation are not part of the model (armature:
    :func:`armature_from_mjcf`). An MJCFError (a ValueError) says what cannot be read.
    """
    mujoco, m, path = compiled(path)
    bodies = _chain(mujoco, m, path, tip)
    on_path = set(bodies)
    for b in bodies:
        if m.body_jntnum[b] > 1:
            js = range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b])
            raise MJCFError(
                f"MJCF {path!r}: body {object_name(mujoco, m, 'body', b)!r} has "
                f"{m.body_jntnum[b]} joints {[object_name(mujoco, m, 'joint', j) for j in js]}; "
                "expected at most one per body on the chain (a serial chain)")
        j = m.body_jntadr[b]
        if m.body_jntnum[b] and m.jnt_type[j] not in JOINT_KIND:
            raise MJCFError(
                f"MJCF {path!r}: joint {object_name(mujoco, m, 'joint', j)!r} of body "
                f"{object_name(mujoco, m, 'body', b)!r} is a {_MJ_NAME[int(m.jnt_type[j])]} joint; "
                "supported on the chain: hinge, slide (and bodies without a joint)")
    children: dict[int, list[int]] = {b: [] for b in range(m.nbody)}
    for b in range(1, m.nbody):
        children[int(m.body_parentid[b])].append(b)
    locked: list[str] = []

    def rigid_subtree(b: int) -> np.ndarray:
        """Parameters of body ``b`` plus everything hanging off it off the path, in its
        frame."""
        total = _body_params(m, b)
        for c in children[b]:
            if c in on_path:
                continue
            locked.extend(object_name(mujoco, m, "joint", j) for j in
                          range(m.body_jntadr[c], m.body_jntadr[c] + m.body_jntnum[c]))
            total = total + transform_params(_at_zero(m, c), rigid_subtree(c))
        return total

    T_fixed, screws, types, params, jnames, lnames = [], [], [], [], [], []
    T_acc = np.eye(4)  # welded transforms since the last movable body
    body_params = None  # parameters of the current movable link (None before the first)
    for b in bodies:
        T_acc = T_acc @ _at_zero(m, b)
        if not m.body_jntnum[b]:
            if body_params is not None:  # a welded body on the path merges into the link
                body_params[:10] += transform_params(T_acc, rigid_subtree(b))
            continue
        if body_params is not None:
            params.append(body_params)
        j, d = m.body_jntadr[b], m.jnt_dofadr[m.body_jntadr[b]]
        T_fixed.append(T_acc)
        screws.append(_screw(m, j))
        types.append(JOINT_KIND[int(m.jnt_type[j])])
        jnames.append(object_name(mujoco, m, "joint", j))
        lnames.append(object_name(mujoco, m, "body", b))
        body_params = np.r_[rigid_subtree(b), float(m.dof_frictionloss[d]),
                            float(m.dof_damping[d])]
        T_acc = np.eye(4)
    if body_params is None:
        raise MJCFError(f"MJCF {path!r} has no hinge or slide joint between the world and "
                        "the tip")
    params.append(body_params)
    if locked:
        warnings.warn(f"MJCF {path!r}: joints {sorted(locked)} are off the chain world -> "
                      f"{lnames[-1]!r}; they are locked at 0 and their bodies carried rigidly",
                      stacklevel=2)
    armed = [jn for jn, a in zip(jnames, joint_side_armature(mujoco, m, path, jnames)) if a]
    if armed:
        warnings.warn(f"MJCF {path!r}: joints {armed} have an armature, which the rigid-body "
                      "Robot leaves out; armature_from_mjcf(path, robot) gives it (the "
                      "Armature term's IA, joint side)", stacklevel=2)
    gravity = np.array(m.opt.gravity, dtype=float)
    if m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_GRAVITY):
        gravity = np.zeros(3)
    model_name = bytes(m.names).split(b"\0", 1)[0].decode() or os.path.splitext(
        os.path.basename(path))[0]
    return Robot(T_fixed, screws, types, np.concatenate(params), gravity,
                 joint_names=jnames, link_names=lnames,
                 name=model_name if name is None else name)


def _joint_ids(mujoco: Any, m: Any, path: str, joint_names: Sequence[str]) -> list[int]:
    ids = []
    for jn in joint_names:
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)
        if j < 0:
            raise MJCFError(f"MJCF {path!r} has no joint {jn!r}; joints: "
                            f"{sorted(object_name(mujoco, m, 'joint', k) for k in range(m.njnt))}")
        ids.append(j)
    return ids


def joint_side_armature(mujoco: Any, m: Any, path: str, joint_names: Sequence[str]
                        ) -> np.ndarray:
    ids = _joint_ids(mujoco, m, path, joint_names)
    armature = np.array([float(m.dof_armature[m.jnt_dofadr[j]]) for j in ids])
    # MuJoCo >= 4: an actuator's armature too, motor side
    rotor: Any = getattr(m, "actuator_armature", np.zeros(m.nu))
    for a in range(m.nu):
        if m.actuator_trntype[a] == int(mujoco.mjtTrn.mjTRN_JOINT) and \
                m.actuator_trnid[a, 0] in ids:
            k = ids.index(int(m.actuator_trnid[a, 0]))
            armature[k] += float(m.actuator_gear[a, 0]) ** 2 * float(rotor[a])
    return armature


def armature_from_mjcf(path: PathLike, robot: Robot) -> Float[np.ndarray, " n"]:
    """The armature of ``robot``'s joints in an MJCF file (kg m^2 or kg, joint side): the
    joint's ``armature`` plus, for each actuator driving it directly (MuJoCo >= 4), its
    ``armature`` times ``gear^2``. MuJoCo adds ``armature * qdd`` to the rigid body's
    torque, as the :class:`~sedsabso_jax.Armature` term does with ``IA`` and no
    transmission. The joints are found by ``robot.joint_names``."""
    mujoco, m, path = compiled(path)
    return joint_side_armature(mujoco, m, path, robot.joint_names)


def joint_limit_rows(path: PathLike, joint_names: Sequence[str]) -> Float[np.ndarray, "n 3"]:
    """Rows ``(lower, upper, effort)`` of the named joints: ``jnt_range`` where the joint
    is limited (else ``-inf, inf``), and the largest force its actuators can apply
    (``nan`` when unknown): the joint's ``actuatorfrcrange`` where limited, else the sum
    over the actuators driving the joint of ``forcerange`` where force-limited or, for a
    plain motor (fixed gain, no bias), ``|gain * gear| * max|ctrlrange|`` where
    control-limited."""
    mujoco, m, path = compiled(path)
    rows = []
    for j in _joint_ids(mujoco, m, path, joint_names):
        lower, upper = (m.jnt_range[j] if m.jnt_limited[j] else (-np.inf, np.inf))
        effort = np.nan
        if m.jnt_actfrclimited[j]:
            effort = float(np.max(np.abs(m.jnt_actfrcrange[j])))
        else:
            total, known, any_actuator = 0.0, True, False
            for a in range(m.nu):
                if m.actuator_trntype[a] != int(mujoco.mjtTrn.mjTRN_JOINT) or \
                        m.actuator_trnid[a, 0] != j:
                    continue
                any_actuator = True
                gear = abs(float(m.actuator_gear[a, 0]))
                motor = (m.actuator_gaintype[a] == int(mujoco.mjtGain.mjGAIN_FIXED)
                         and m.actuator_biastype[a] == int(mujoco.mjtBias.mjBIAS_NONE))
                if m.actuator_forcelimited[a]:
                    total += gear * float(np.max(np.abs(m.actuator_forcerange[a])))
                elif motor and m.actuator_ctrllimited[a]:
                    total += gear * abs(float(m.actuator_gainprm[a, 0])) * float(
                        np.max(np.abs(m.actuator_ctrlrange[a])))
                else:
                    known = False
            if any_actuator and known and total > 0:
                effort = total
        rows.append((float(lower), float(upper), effort))
    return np.array(rows, dtype=float).reshape(len(rows), 3)
