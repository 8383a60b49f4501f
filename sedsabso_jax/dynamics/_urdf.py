"""URDF -> :class:`Robot`, parsed with pytorch-kinematics' URDF parser.

Transforms are composed here in float64 from the parsed ``xyz``/``rpy`` (pytorch-kinematics
builds its own in float32). Fixed joints are merged into their parent link; every link off
the base-to-tip path hangs rigidly on the path (a movable joint there is locked at 0, with
a warning). URDF inertials (mass, CoM and inertia about the CoM, in the ``<inertial>``
frame) are converted to the project's convention: inertia about the link-frame origin, in
the link frame, and first moments ``m * c``. ``<dynamics friction damping>`` become the
joint's Coulomb and viscous friction.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import sys
import warnings
from collections import defaultdict
from collections.abc import Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float
from lxml import etree

from .._output import PathLike
from . import _spatial as sp
from ._inertia import params_from_com, transform_params
from ._robot import STANDARD_GRAVITY, Robot

_MOVABLE = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}


class URDFError(ValueError):
    """A URDF that cannot be turned into a serial chain."""


def read_checked(path) -> str:
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as err:
        raise URDFError(f"cannot read URDF {path!r}: {err.strerror or err}") from None
    if not raw.strip():
        raise URDFError(f"URDF {path!r} is empty")
    if re.search(rb"<!(DOCTYPE|ENTITY)", raw):
        raise URDFError(f"URDF {path!r} declares a DOCTYPE; DTDs and entities are refused")
    # Parse once with a parser that resolves no entity and loads nothing, to refuse
    # DTDs (entity expansion, external files) and to report syntax errors with a line.
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                             huge_tree=False)
    try:
        root = etree.fromstring(raw, parser)
    except etree.XMLSyntaxError as err:
        raise URDFError(f"URDF {path!r} is not well-formed XML: {err}") from None
    doc = root.getroottree().docinfo
    if doc.internalDTD is not None or doc.doctype:
        raise URDFError(f"URDF {path!r} declares a DOCTYPE; DTDs and entities are refused")
    if root.tag != "robot":
        raise URDFError(f"URDF {path!r}: root element is <{root.tag}>, expected <robot>")
    return etree.tostring(root, encoding="unicode")


#: The name pytorch-kinematics' URDF parser is imported under (:func:`_parser`).
_PARSER = "_sedsabso_jax_urdf_parser_py"


def _parser() -> tuple[Any, Any]:
    """pytorch-kinematics' URDF parser (pure Python: its ``urdf`` and ``core`` modules),
    imported without the package's ``__init__``, which imports torch (seconds to import,
    and more to exit, in every command that reads a URDF)."""
    if _PARSER not in sys.modules:
        found = importlib.util.find_spec("pytorch_kinematics")  # finds, runs nothing
        where = os.path.join(list(found.submodule_search_locations or [])[0],
                             "urdf_parser_py") if found is not None else ""
        spec = importlib.util.spec_from_file_location(
            _PARSER, os.path.join(where, "__init__.py"), submodule_search_locations=[where])
        if spec is None or spec.loader is None or not os.path.isdir(where):
            from pytorch_kinematics.urdf_parser_py import urdf
            from pytorch_kinematics.urdf_parser_py.xml_reflection import core

            return urdf, core
        module = importlib.util.module_from_spec(spec)
        sys.modules[_PARSER] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[_PARSER]
            raise
    return (importlib.import_module(f"{_PARSER}.urdf"),
            importlib.import_module(f"{_PARSER}.xml_reflection.core"))


def _parse(text: str, path: str):
    pk_urdf, core = _parser()

    messages: list[str] = []
    previous = core.on_error
    core.on_error = messages.append  # the parser prints to stderr otherwise
    try:
        model = pk_urdf.URDF.from_xml_string(text)
    except Exception as err:  # the parser raises bare AssertionError, KeyError, ...
        raise URDFError(f"URDF {path!r} could not be parsed: {type(err).__name__}: {err}") from None
    finally:
        core.on_error = previous
    serious = [m for m in messages if not m.startswith("Unknown tag")]
    if serious:
        warnings.warn(f"URDF {path!r}: " + "; ".join(serious), stacklevel=4)
    return model


def _origin(element) -> np.ndarray:
    o = getattr(element, "origin", None)
    if o is None:
        return np.eye(4)
    xyz = np.zeros(3) if o.xyz is None else np.asarray(o.xyz, float)
    rpy = np.zeros(3) if o.rpy is None else np.asarray(o.rpy, float)
    return sp.transform(sp.rpy_matrix(rpy), xyz)


def _inertial_params(link) -> np.ndarray:
    """10 inertial parameters of a URDF link about its frame origin, in its frame."""
    inertial = link.inertial
    if inertial is None:
        return np.zeros(10)
    mass = float(inertial.mass or 0.0)
    I = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia.to_matrix())
    T = _origin(inertial)  # inertial frame in the link frame
    return transform_params(T, params_from_com(mass, np.zeros(3), I))


def from_urdf(path: PathLike, tip: str | None = None, *,
              gravity: Float[ArrayLike, " 3"] | Sequence[float] = STANDARD_GRAVITY) -> Robot:
    """Serial chain from a URDF file, from its root link to ``tip`` (a link name).

    ``tip`` may be left out when the tree has one path of movable joints; a tree that
    branches into several needs it. Joint and link names are the URDF's.
    """
    path = os.fspath(path)
    model = _parse(read_checked(path), path)
    links = {link.name: link for link in model.links}
    children = defaultdict(list)
    parent_joint = {}
    for j in model.joints:
        for end in (j.parent, j.child):
            if end not in links:
                raise URDFError(f"URDF {path!r}: joint {j.name!r} refers to missing link {end!r}")
        if j.child in parent_joint:
            raise URDFError(f"URDF {path!r}: link {j.child!r} has two parent joints")
        children[j.parent].append(j)
        parent_joint[j.child] = j
    roots = [name for name in links if name not in parent_joint]
    if len(roots) != 1:
        raise URDFError(f"URDF {path!r}: expected one root link, found {roots or 'none (a loop)'}")
    root = roots[0]

    def moves(j: Any) -> bool:  # any non-fixed joint, supported or not (checked below)
        return j.type != "fixed" or any(moves(c) for c in children[j.child])

    if tip is None:
        path_joints, link = [], root
        while True:
            onward = [j for j in children[link] if moves(j)]
            if not onward:
                break
            if len(onward) > 1:
                leaves = sorted(_leaves(children, link))
                raise URDFError(
                    f"URDF {path!r} branches at link {link!r} into joints "
                    f"{[j.name for j in onward]}; choose the tip link (--tip on the command "
                    f"line, tip= in Python), one of {leaves}"
                )
            path_joints.append(onward[0])
            link = onward[0].child
    else:
        if tip not in links:
            raise URDFError(f"URDF {path!r} has no link {tip!r} (tip); links: {sorted(links)}")
        path_joints, link = [], tip
        while link in parent_joint:
            path_joints.append(parent_joint[link])
            link = parent_joint[link].parent
        path_joints.reverse()
    for j in path_joints:
        if j.type not in _MOVABLE and j.type != "fixed":
            raise URDFError(
                f"URDF {path!r}: joint {j.name!r} has type {j.type!r}; supported: revolute, "
                "continuous, prismatic, fixed"
            )
        if getattr(j, "mimic", None) is not None and j.type in _MOVABLE:
            raise URDFError(f"URDF {path!r}: joint {j.name!r} is a mimic joint (not supported)")
    on_path = {j.name for j in path_joints}
    locked = []

    def rigid_subtree(link_name: str) -> np.ndarray:
        """Parameters of a link plus everything hanging off it off-path, in its frame."""
        total = _inertial_params(links[link_name])
        for j in children[link_name]:
            if j.name in on_path:
                continue
            if j.type != "fixed":
                locked.append(j.name)
            total = total + transform_params(_origin(j), rigid_subtree(j.child))
        return total

    T_fixed, screws, types, params, jnames, lnames = [], [], [], [], [], []
    T_acc = np.eye(4)  # fixed transforms since the last movable joint
    body_params = None  # parameters of the current movable link (None before the first)
    for j in path_joints:
        T_acc = T_acc @ _origin(j)
        if j.type == "fixed":
            if body_params is not None:  # a fixed child on the path merges into the body
                body_params[:10] += transform_params(T_acc, rigid_subtree(j.child))
            continue
        if body_params is not None:
            params.append(body_params)
        axis = np.asarray(j.axis if j.axis is not None else (1.0, 0.0, 0.0), float)
        norm = np.linalg.norm(axis)
        if not np.isfinite(norm) or norm < 1e-12:
            raise URDFError(f"URDF {path!r}: joint {j.name!r} has a zero axis {axis.tolist()}")
        axis = axis / norm
        kind = _MOVABLE[j.type]
        T_fixed.append(T_acc)
        screws.append(np.r_[axis, 0, 0, 0] if kind == "revolute" else np.r_[0, 0, 0, axis])
        types.append(kind)
        jnames.append(j.name)
        lnames.append(j.child)
        dyn = getattr(j, "dynamics", None)
        friction = [float(getattr(dyn, "friction", 0.0) or 0.0),
                    float(getattr(dyn, "damping", 0.0) or 0.0)]
        body_params = np.r_[rigid_subtree(j.child), 0.0, 0.0]
        body_params[10:] = friction
        T_acc = np.eye(4)
    if body_params is None:
        raise URDFError(f"URDF {path!r} has no movable joint between {root!r} and the tip")
    params.append(body_params)
    if locked:
        warnings.warn(
            f"URDF {path!r}: joints {sorted(locked)} are off the chain {root!r} -> "
            f"{lnames[-1]!r}; they are locked at 0 and their links carried rigidly",
            stacklevel=2,
        )
    name = getattr(model, "name", None) or os.path.splitext(os.path.basename(path))[0]
    return Robot(T_fixed, screws, types, np.concatenate(params), gravity,
                 joint_names=jnames, link_names=lnames, name=name)


def _leaves(children, link_name):
    if not children[link_name]:
        return [link_name]
    return [leaf for j in children[link_name] for leaf in _leaves(children, j.child)]


def joint_limit_rows(path: PathLike, joint_names: Sequence[str]) -> Float[np.ndarray, "n 4"]:
    """``<limit>`` of the named joints as rows ``(lower, upper, velocity, effort)``.

    A joint without ``<limit>`` (or a continuous joint, whose position limits URDF
    ignores) has ``lower = -inf, upper = +inf``, and so has one whose ``<limit>`` gives no
    range: ``lower`` and ``upper`` missing (URDF reads them as 0; some manufacturers'
    files declare unlimited revolute joints so) or both 0 (exporters' placeholder), with
    a warning naming those joints. A missing or zero velocity is ``+inf`` (unknown) and a
    missing or zero effort ``nan``.
    """
    path = os.fspath(path)
    model = _parse(read_checked(path), path)
    joints = {j.name: j for j in model.joints}
    rows, no_range = [], []
    for name in joint_names:
        if name not in joints:
            raise URDFError(f"URDF {path!r} has no joint {name!r}; joints: {sorted(joints)}")
        j, lim = joints[name], joints[name].limit
        lower = upper = velocity = effort = None
        if lim is not None:
            lower, upper, velocity, effort = lim.lower, lim.upper, lim.velocity, lim.effort
        if lim is not None and j.type != "continuous" and not (lower or upper):
            no_range.append(name)  # lower = upper = 0: no range, not a locked joint
        if lim is None or j.type == "continuous" or name in no_range:
            lower = upper = None
        rows.append((
            -np.inf if lower is None else float(lower),
            np.inf if upper is None else float(upper),
            float(velocity) if velocity else np.inf,
            float(effort) if effort else np.nan,
        ))
    if no_range:
        warnings.warn(f"URDF {path!r}: joints {no_range} have a <limit> without a position "
                      "range (lower and upper missing or both 0); read without position "
                      "limits, as continuous joints", stacklevel=3)
    return np.array(rows, dtype=float).reshape(len(rows), 4)


def fixed_link_pose(path: PathLike, link: str, moving_links: Sequence[str]
                    ) -> tuple[str, Float[np.ndarray, "4 4"]]:
    """Where a URDF link sits on the chain: ``(moving link, T)`` with ``moving_links``
    the chain's (a :class:`Robot`'s ``link_names``) and ``T`` the pose of ``link``'s
    frame in that moving link's frame. A moving link is itself (``T`` the identity); a
    link fixed to one (a flange, ``tool0``), or hanging on a joint off the chain (locked
    at 0, as :func:`from_urdf` carries it), is the moving link it merges into. A
    ValueError names a link the URDF lacks or one fixed to the base."""
    path = os.fspath(path)
    model = _parse(read_checked(path), path)
    parent_joint = {j.child: j for j in model.joints}
    if link not in {x.name for x in model.links}:
        raise URDFError(f"URDF {path!r} has no link {link!r}; links: "
                        f"{sorted(x.name for x in model.links)}")
    T, at = np.eye(4), link
    while at not in moving_links:
        if at not in parent_joint:
            raise URDFError(f"link {link!r} of URDF {path!r} is fixed to the base (no moving "
                            f"link carries it); moving links: {list(moving_links)}")
        T = _origin(parent_joint[at]) @ T
        at = parent_joint[at].parent
    return at, T
