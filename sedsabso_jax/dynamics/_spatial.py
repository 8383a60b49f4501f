"""Rigid-body transforms in NumPy (float64), used when robots are built.

Homogeneous transforms are 4x4 arrays; a twist or screw is ordered (omega, v) as in
Lynch & Park, *Modern Robotics* (2017), Sec. 3.3.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from jaxtyping import ArrayLike, Float


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_matrix(rpy: Float[np.ndarray, " 3"] | Sequence[float]) -> Float[np.ndarray, "3 3"]:
    """URDF roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z)."""
    r, p, y = (float(v) for v in rpy)
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def rpy_from_matrix(R: Float[ArrayLike, "3 3"]) -> Float[np.ndarray, " 3"]:
    """The URDF roll-pitch-yaw of a rotation matrix (inverse of :func:`rpy_matrix`); at
    pitch +-pi/2 (gimbal lock) the roll is set to 0."""
    R = np.asarray(R, dtype=float)
    pitch = np.arcsin(np.clip(-R[2, 0], -1.0, 1.0))
    if abs(R[2, 0]) < 1.0 - 1e-12:
        roll, yaw = np.arctan2(R[2, 1], R[2, 2]), np.arctan2(R[1, 0], R[0, 0])
    else:
        roll, yaw = 0.0, np.arctan2(-R[0, 1], R[1, 1])
    return np.array([roll, pitch, yaw])


def transform(rotation: Float[ArrayLike, "3 3"] | None = None,
              translation: Float[ArrayLike, " 3"] | Sequence[float] | None = None
              ) -> Float[np.ndarray, "4 4"]:
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = rotation
    if translation is not None:
        T[:3, 3] = translation
    return T


def inverse(T: np.ndarray) -> np.ndarray:
    R, p = T[:3, :3], T[:3, 3]
    return transform(R.T, -R.T @ p)


def adjoint(T: np.ndarray, screw: np.ndarray) -> np.ndarray:
    """Ad_T applied to a twist (omega, v): (R omega, p x R omega + R v)."""
    R, p = T[:3, :3], T[:3, 3]
    w = R @ screw[:3]
    return np.concatenate([w, np.cross(p, w) + R @ screw[3:]])
