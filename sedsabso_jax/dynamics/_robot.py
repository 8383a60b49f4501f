"""The serial-chain model: a JAX pytree holding geometry, inertial parameters and gravity."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax.typing import DTypeLike
from jaxtyping import Array, ArrayLike, Float

from .. import _x64

#: Per-link parameter order (the paper's Eq. 3 order), suffixed by the link number.
LINK_PARAMETERS = ("XX", "YY", "ZZ", "XY", "XZ", "YZ", "M", "MX", "MY", "MZ", "FC", "FV")
#: Number of parameters per link: 10 inertial + Coulomb + viscous friction.
N_LINK_PARAMETERS = len(LINK_PARAMETERS)
JOINT_TYPES = ("revolute", "prismatic")
STANDARD_GRAVITY = (0.0, 0.0, -9.81)


def _f64(x) -> Array:
    _x64.require("a robot model (its geometry and parameters)")
    return jnp.asarray(x, dtype=jnp.float64)


class Robot(eqx.Module):
    """A serial chain of ``n`` revolute or prismatic joints with a fixed base.

    Link ``i`` (1-based in names, 0-based in arrays) is the body moved by joint ``i``. Its
    frame relative to the parent link's frame is

        ``T_{i-1,i}(q_i) = T_fixed[i] @ exp([screws[i]] * q_i)``

    (product of exponentials, Lynch & Park 2017, Eq. 4.16, with body-frame screws), so
    ``T_fixed[i]`` is the link frame at ``q_i = 0`` and ``screws[i] = (omega, v)`` is the
    joint's unit screw in the link frame: ``(axis, 0)`` for a revolute joint whose axis
    passes through the link-frame origin (URDF, modified DH), ``(0, axis)`` for a prismatic
    joint. Standard DH puts the link frame at the link's far end; its screw then has a
    non-zero ``v``.

    ``params`` holds 12 numbers per link, in the order of the paper's Eq. 3::

        [Ixx Iyy Izz Ixy Ixz Iyz m mx my mz Fc Fv]

    inertia tensor entries about the link-frame ORIGIN, in the link frame (the SymPyBotics
    convention of the paper's Table 2); first moments ``m * c`` with ``c`` the centre of
    mass in the link frame; joint friction ``Fc * sign(qd) + Fv * qd``. Names are
    ``XX1 YY1 ... FC1 FV1 XX2 ...`` (:attr:`param_names`). Gravity is a vector in the base
    frame (default 9.81 m/s^2 along -z).

    Build robots with :mod:`sedsabso_jax.robots` (``sedsabso_jax/dynamics/_robots.py``)
    rather than by hand.
    """

    T_fixed: Float[Array, "n 4 4"]
    screws: Float[Array, "n 6"]
    params: Float[Array, " p"]
    gravity: Float[Array, 3]
    joint_types: tuple[str, ...] = eqx.field(static=True)
    joint_names: tuple[str, ...] = eqx.field(static=True)
    link_names: tuple[str, ...] = eqx.field(static=True)
    name: str = eqx.field(static=True)

    def __init__(
        self,
        T_fixed: Float[ArrayLike, "n 4 4"] | Sequence[Any],
        screws: Float[ArrayLike, "n 6"] | Sequence[Any],
        joint_types: Sequence[str],
        params: Float[ArrayLike, " p"] | Sequence[float] | None = None,
        gravity: Float[ArrayLike, " 3"] | Sequence[float] = STANDARD_GRAVITY,
        *,
        joint_names: Sequence[str] | None = None,
        link_names: Sequence[str] | None = None,
        name: str = "robot",
    ):
        joint_types = tuple(str(t) for t in joint_types)
        n = len(joint_types)
        if n < 1:
            raise ValueError("a robot needs at least one movable joint; got joint_types=()")
        for i, t in enumerate(joint_types):
            if t not in JOINT_TYPES:
                raise ValueError(
                    f"joint {i + 1}: unsupported joint type {t!r}; expected one of {JOINT_TYPES}"
                )
        T_fixed = np.asarray(T_fixed, dtype=float)
        screws = np.asarray(screws, dtype=float)
        gravity = np.asarray(gravity, dtype=float)
        params = np.zeros(N_LINK_PARAMETERS * n) if params is None else np.asarray(params, float)
        _expect_shape("T_fixed", T_fixed, (n, 4, 4))
        _expect_shape("screws", screws, (n, 6))
        _expect_shape("params", params, (N_LINK_PARAMETERS * n,))
        _expect_shape("gravity", gravity, (3,))
        for label, arr in (("T_fixed", T_fixed), ("screws", screws), ("params", params),
                           ("gravity", gravity)):
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{label} contains NaN or Inf")
        for i, (T, s, t) in enumerate(zip(T_fixed, screws, joint_types)):
            R = T[:3, :3]
            if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
                raise ValueError(f"joint {i + 1}: T_fixed[{i}] is not a rigid transform")
            direction = s[:3] if t == "revolute" else s[3:]
            if t == "prismatic" and np.any(s[:3] != 0.0):
                raise ValueError(f"joint {i + 1}: a prismatic screw must have omega = 0, got {s}")
            if abs(np.linalg.norm(direction) - 1.0) > 1e-9:
                raise ValueError(
                    f"joint {i + 1}: the {t} screw's axis must be a unit vector, got {s}"
                )
        self.T_fixed = _f64(T_fixed)
        self.screws = _f64(screws)
        self.params = _f64(params)
        self.gravity = _f64(gravity)
        self.joint_types = joint_types
        self.joint_names = _names(joint_names, n, "joint")
        self.link_names = _names(link_names, n, "link")
        self.name = str(name)

    @property
    def n_joints(self) -> int:
        return len(self.joint_types)

    @property
    def n_params(self) -> int:
        return N_LINK_PARAMETERS * self.n_joints

    @property
    def param_names(self) -> tuple[str, ...]:
        """``("XX1", "YY1", ..., "FV<n>")``, matching :attr:`params`."""
        return tuple(f"{p}{i + 1}" for i in range(self.n_joints) for p in LINK_PARAMETERS)

    def with_params(self, params: Float[ArrayLike, " p"]) -> Robot:
        """A copy of this robot with other parameters (same order as :attr:`params`)."""
        params = np.asarray(params, dtype=float)
        _expect_shape("params", params, (self.n_params,))
        return eqx.tree_at(lambda r: r.params, self, _f64(params))

    def __repr__(self) -> str:
        kinds = "".join("R" if t == "revolute" else "P" for t in self.joint_types)
        return f"Robot({self.name!r}, n_joints={self.n_joints}, joints={kinds})"


def _expect_shape(label: str, arr: np.ndarray, shape: tuple[int, ...]) -> None:
    if arr.shape != shape:
        raise ValueError(f"{label} must have shape {shape}, got {arr.shape}")


def _names(names, n: int, kind: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{kind}{i + 1}" for i in range(n))
    names = tuple(str(x) for x in names)
    if len(names) != n:
        raise ValueError(f"expected {n} {kind} names, got {len(names)}: {names}")
    return names


def joint_arrays(robot: Robot, *named_arrays: tuple[str, object], dtype: DTypeLike = jnp.float64
                 ) -> list[Array]:
    """Convert joint-space arrays to ``dtype`` and check each ends in ``robot.n_joints``:
    a clear error before anything compiles.

    Leading (batch) axes must broadcast against each other; the broadcast arrays are
    returned.
    """
    if jnp.dtype(dtype) == jnp.float64:
        _x64.require("the regressor in float64 (its default)")
    n = robot.n_joints
    arrays = []
    for name, value in named_arrays:
        try:
            arr = jnp.asarray(value, dtype=dtype)
        except (TypeError, ValueError) as err:
            raise TypeError(f"{name} must be a numeric array, got {type(value).__name__}") from err
        if arr.ndim == 0 or arr.shape[-1] != n:
            raise ValueError(
                f"{name} must have shape (..., {n}) for robot {robot.name!r} with {n} joints, "
                f"got shape {arr.shape}"
            )
        arrays.append(arr)
    try:
        shape = jnp.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError as err:
        shapes = ", ".join(f"{name} {a.shape}" for (name, _), a in zip(named_arrays, arrays))
        raise ValueError(f"batch shapes do not broadcast: {shapes}") from err
    return [jnp.broadcast_to(a, shape) for a in arrays]
