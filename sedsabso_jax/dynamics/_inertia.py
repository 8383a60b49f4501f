"""A rigid body's inertial parameters: conversions, change of frame, physical consistency.

Per link, the package's 10 inertial parameters are ``[Ixx Iyy Izz Ixy Ixz Iyz m mx my mz]``:
inertia tensor entries about the link-frame ORIGIN, expressed in the link frame (tensor
entries, so ``Ixy = -integral(x y dm)``), the mass, and the first moments ``m c``. NumPy,
float64: used when robots are built and when fits are checked.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from jaxtyping import ArrayLike, Float


def inertia_vector(I: np.ndarray) -> np.ndarray:
    """The 6 entries ``[Ixx Iyy Izz Ixy Ixz Iyz]`` of a symmetric 3x3 inertia tensor."""
    return np.array([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])


def inertia_matrix(v: Float[np.ndarray, " 6"] | Sequence[float]) -> Float[np.ndarray, "3 3"]:
    """The symmetric 3x3 tensor of ``[Ixx Iyy Izz Ixy Ixz Iyz]``."""
    xx, yy, zz, xy, xz, yz = v
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def params_from_com(mass: float, com: Float[ArrayLike, " 3"] | Sequence[float],
                    inertia_com: np.ndarray) -> Float[np.ndarray, " 10"]:
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


def pseudo_inertia(params10: Float[ArrayLike, "*batch 10"]) -> Float[np.ndarray, "*batch 4 4"]:
    """``(..., 10)`` link parameters -> ``(..., 4, 4)`` pseudo-inertia matrices
    ``J = [[tr(I)/2 1 - I, h], [h^T, m]]`` (Wensing, Kim & Slotine, "Linear matrix
    inequalities for physically consistent inertial parameter identification", IEEE RA-L
    2017), ``I`` about the origin and ``h = m c``. ``J`` is linear in the parameters,
    and a body is physically realisable exactly when ``J`` is positive semidefinite."""
    p = np.asarray(params10, dtype=float)
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz, m, mx, my, mz = np.moveaxis(p, -1, 0)
    I = np.stack([np.stack([Ixx, Ixy, Ixz], -1), np.stack([Ixy, Iyy, Iyz], -1),
                  np.stack([Ixz, Iyz, Izz], -1)], -2)
    J = np.zeros(p.shape[:-1] + (4, 4))
    J[..., :3, :3] = 0.5 * np.trace(I, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - I
    J[..., :3, 3] = J[..., 3, :3] = np.stack([mx, my, mz], -1)
    J[..., 3, 3] = m
    return J


def from_pseudo_inertia(J: Float[ArrayLike, "*batch 4 4"]) -> Float[np.ndarray, "*batch 10"]:
    """``(..., 4, 4)`` pseudo-inertia -> ``(..., 10)`` link parameters (the inverse of
    :func:`pseudo_inertia`)."""
    J = np.asarray(J, dtype=float)
    S = J[..., :3, :3]
    I = np.trace(S, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - S
    return np.stack([I[..., 0, 0], I[..., 1, 1], I[..., 2, 2], I[..., 0, 1], I[..., 0, 2],
                     I[..., 1, 2], J[..., 3, 3], J[..., 0, 3], J[..., 1, 3], J[..., 2, 3]], -1)


def is_physically_consistent(params: Float[ArrayLike, " p"], margin: float = 0.0) -> bool:
    """Whether every link of a full parameter vector (12 per link, the robot's order) has
    a pseudo-inertia with eigenvalues > ``margin``: positive mass, a positive-definite
    inertia satisfying the triangle inequalities, the centre of mass inside the body."""
    p = np.asarray(params, dtype=float).reshape(-1, 12)
    return bool(np.all(np.linalg.eigvalsh(pseudo_inertia(p[:, :10])) > margin))
