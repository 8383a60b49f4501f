"""Rigid-body transforms in NumPy (float64), used when robots are built.

Homogeneous transforms are 4x4 arrays; a twist or screw is ordered (omega, v) as in
Lynch & Park, *Modern Robotics* (2017), Sec. 3.3.
"""

from __future__ import annotations

import numpy as np


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_matrix(rpy) -> np.ndarray:
    """URDF roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z)."""
    r, p, y = (float(v) for v in rpy)
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def transform(rotation=None, translation=None) -> np.ndarray:
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


def skew(v) -> np.ndarray:
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


# Inertial parameters ---------------------------------------------------------------
# Per link, the project's 10 inertial parameters are
#   [Ixx Iyy Izz Ixy Ixz Iyz m mx my mz]
# with the inertia tensor taken about the link-frame ORIGIN and expressed in the link
# frame (tensor entries, so Ixy = -integral(x y dm)), and (mx, my, mz) = m * c.


def inertia_vector(I: np.ndarray) -> np.ndarray:
    return np.array([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])


def inertia_matrix(v) -> np.ndarray:
    xx, yy, zz, xy, xz, yz = v
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def params_from_com(mass: float, com, inertia_com: np.ndarray) -> np.ndarray:
    """10 inertial parameters from mass, centre of mass and inertia about the CoM.

    All in one frame; the inertia about the origin follows from the parallel-axis theorem
    I_o = I_c + m (|c|^2 1 - c c^T).
    """
    c = np.asarray(com, dtype=float)
    I_o = np.asarray(inertia_com, dtype=float) + mass * (c @ c * np.eye(3) - np.outer(c, c))
    return np.concatenate([inertia_vector(I_o), [mass], mass * c])


def transform_params(T: np.ndarray, params10: np.ndarray) -> np.ndarray:
    """Express a body's 10 inertial parameters, given in frame B, in frame A; T = T_AB.

    Works from the origin-referred form alone (no division by the mass), so massless
    bodies and physically inconsistent parameter sets transform exactly too.
    """
    R, p = T[:3, :3], T[:3, 3]
    I_b = inertia_matrix(params10[:6])
    m, h_b = params10[6], np.asarray(params10[7:10])
    h_r = R @ h_b  # first moment about B's origin, in A's axes
    # I about A's origin: R I_b R^T + m(|p|^2 1 - p p^T) + 2 sym(p.h 1 - p h^T) terms
    I_a = (
        R @ I_b @ R.T
        + m * (p @ p * np.eye(3) - np.outer(p, p))
        + 2.0 * (p @ h_r) * np.eye(3)
        - np.outer(p, h_r)
        - np.outer(h_r, p)
    )
    return np.concatenate([inertia_vector(I_a), [m], h_r + m * p])
