"""Motor side to joint side: gear ratios, a coupled transmission, drive gains.

Industrial arms often record MOTOR encoder angles and motor currents or torques. With the
transmission matrix ``K`` (``n x n``, motor angles from joint angles)::

    theta_motor = K (q + offset)          q = K^-1 theta_motor - offset
    tau_joint = K^T tau_motor              (power balance: tau_m . theta_m' = tau . q')
    tau_motor = g * current                (per-motor drive gains g, when currents are given)

Plain gear ratios give a diagonal ``K = diag(N)``; a coupled wrist adds off-diagonal terms,
e.g. on the Staubli TX40 motor 6 turns with joints 5 and 6: ``K[5, 4] = N[5]``.
``offset`` moves the encoder zero to the kinematic model's zero (per joint, rad).

The motor side also has its own dynamics, identified with the joint-side model:
the rotor inertia (armature) of motor ``m`` adds ``K[m]^T I_m (K[m] . qdd)`` to the joint
torques, and a coupled motor's friction ``K[m]^T (Fv_m K[m] . qd + Fc_m sign(K[m] . qd))``
(see :class:`~sedsabso_jax.TorqueModel`'s ``armature`` and ``coupling``
terms).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TypeAlias

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float

from ._container import Measurements


def coupled_motors(K: Float[ArrayLike, "n n"]) -> tuple[int, ...]:
    """The motors (0-based rows of the transmission matrix ``K``) that turn with more than
    one joint."""
    return tuple(int(m) for m in np.flatnonzero(np.count_nonzero(np.asarray(K), axis=1) > 1))


def _square(name: str, value, n: int | None = None) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or (n is not None and arr.shape[0] != n):
        want = f"({n}, {n})" if n is not None else "(n, n)"
        raise ValueError(f"{name} must be a square matrix {want}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or Inf")
    return arr


def _per_motor(name: str, value, n: int, *, nonzero: bool) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n,):
        raise ValueError(f"{name} must have {n} entries (one per motor, as the transmission), "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or (nonzero and np.any(arr == 0)):
        what = "finite and non-zero" if nonzero else "finite"
        raise ValueError(f"{name} must be {what}, got {arr.tolist()}")
    return arr


class Transmission(eqx.Module):
    """Motor side to joint side (module docstring). ``matrix`` is ``K``, ``offset`` the
    joint position of each encoder zero, ``drive_gains`` the motor torque per unit of the
    recorded current (None: the file records motor torques). Checked and converted when
    built (a ValueError naming what is wrong)."""

    matrix: np.ndarray
    offset: np.ndarray
    drive_gains: np.ndarray | None = None

    def __init__(self, matrix: Float[ArrayLike, "n n"], offset: Float[ArrayLike, " n"],
                 drive_gains: Float[ArrayLike, " n"] | None = None):
        K = _square("the transmission matrix", matrix)
        n = K.shape[0]
        cond = np.linalg.cond(K)
        if not cond < 1e12:
            raise ValueError(f"the transmission matrix is singular (condition number "
                             f"{cond:.3g}): motor angles do not determine the joints")
        self.matrix = K
        self.offset = _per_motor("offset", offset, n, nonzero=False)
        self.drive_gains = None if drive_gains is None else _per_motor(
            "drive gains", drive_gains, n, nonzero=True)

    @classmethod
    def from_gear_ratios(cls, ratios: Float[ArrayLike, " n"] | Sequence[float], *,
                         coupling: Mapping[tuple[int, int], float] | None = None,
                         offset: Float[ArrayLike, " n"] | Sequence[float] | None = None,
                         drive_gains: Float[ArrayLike, " n"] | Sequence[float] | None = None
                         ) -> Transmission:
        """``K = diag(ratios)`` plus ``coupling``: ``{(motor, joint): ratio}`` with motors
        and joints numbered from 1, e.g. ``{(6, 5): 32.0}`` for the TX40's wrist."""
        N = np.atleast_1d(np.asarray(ratios, dtype=float))
        if N.ndim != 1 or N.size < 1:
            raise ValueError(f"gear ratios must be a list of numbers, one per joint, got "
                             f"{ratios!r}")
        if not np.all(np.isfinite(N)) or np.any(N == 0):
            raise ValueError(f"gear ratios must be finite and non-zero, got {N.tolist()}")
        n = N.size
        K = np.diag(N)
        for (motor, joint), value in (coupling or {}).items():
            if not (1 <= int(motor) <= n and 1 <= int(joint) <= n) or motor == joint:
                raise ValueError(f"coupling ({motor}, {joint}): expected a motor and another "
                                 f"joint, both numbered 1..{n}")
            K[int(motor) - 1, int(joint) - 1] = float(value)
        # offset and drive_gains may be array-likes: __post_init__ converts them
        return cls(K, np.zeros(n) if offset is None else offset, drive_gains)  # type: ignore[arg-type]

    @property
    def n_joints(self) -> int:
        return self.matrix.shape[0]

    @property
    def coupled_motors(self) -> tuple[int, ...]:
        """Motors (0-based) that turn with more than one joint."""
        return coupled_motors(self.matrix)

    def to_joint_side(self, data: Measurements) -> Measurements:
        """Joint-side measurements from motor-side ones: positions, velocities and
        accelerations through ``K^-1`` (minus the offset), torques ``K^T (g current)``."""
        if data.n_joints != self.n_joints:
            raise ValueError(f"{data.source}: {data.n_joints} motors recorded, the transmission "
                             f"has {self.n_joints}")
        Kinv_T = np.linalg.inv(self.matrix).T
        tau_m = data.tau if self.drive_gains is None else data.tau * self.drive_gains
        info = dict(data.info, transmission={
            "matrix": self.matrix.tolist(), "offset": self.offset.tolist(),
            "drive_gains": None if self.drive_gains is None else self.drive_gains.tolist()})
        gains = np.ones(self.n_joints) if self.drive_gains is None else self.drive_gains
        recorded = None if data.recorded is None else data.recorded.linear(
            Kinv_T, self.offset, gains[:, None] * self.matrix,
            dict(data.recorded.info, transmission=info["transmission"]))
        return Measurements(data.times, data.q @ Kinv_T - self.offset, data.qd @ Kinv_T,
                            data.qdd @ Kinv_T, tau_m @ self.matrix, source=data.source,
                            info=info, recorded=recorded)


#: A transmission as the identification takes it: a :class:`Transmission`, its matrix ``K``
#: ``(n, n)``, or None (none: ``K = 1``).
TransmissionLike: TypeAlias = Transmission | Float[ArrayLike, "n n"] | None
