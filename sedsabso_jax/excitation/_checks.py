"""Limit checks: which joint limits a motion violates, named in words a user can act on."""

from __future__ import annotations

import math

import numpy as np
from jaxtyping import ArrayLike, Float

from ..dynamics._limits import JointLimits
from ._trajectory import FourierTrajectory


def _fmt(value: float, angular: bool, suffix: str) -> str:
    if angular:
        return f"{value:.6g} rad{suffix} ({math.degrees(value):.6g} deg{suffix})"
    return f"{value:.6g} m{suffix}"


def violations(limits: JointLimits, q: Float[ArrayLike, "*batch n"],
               qd: Float[ArrayLike, "*batch n"], qdd: Float[ArrayLike, "*batch n"],
               times: Float[ArrayLike, "*batch"] | None = None) -> list[str]:
    """One readable line per (joint, limit) that ``q, qd, qdd`` (each ``(..., n)``)
    violate, with the worst sample, e.g. ``"joint 2 (J2) velocity: |qd| reaches 2.1 rad/s
    (120.3 deg/s) at t = 3.2 s, above the limit 1.745 rad/s (100 deg/s); 17 of 1000
    samples"``. Empty when all samples are inside the limits (limits included)."""
    n = limits.n_joints
    arrays = []
    for name, value in (("q", q), ("qd", qd), ("qdd", qdd)):
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 0 or arr.shape[-1] != n:
            raise ValueError(f"{name} must have shape (..., {n}) for {n} joint limits, "
                             f"got {arr.shape}")
        if np.any(np.isnan(arr)):
            raise ValueError(f"{name} contains NaN")
        arrays.append(arr.reshape(-1, n))
    q, qd, qdd = arrays
    if not q.shape == qd.shape == qdd.shape:
        raise ValueError(f"q, qd, qdd must have one shape, got {q.shape}, {qd.shape}, "
                         f"{qdd.shape}")
    t = None
    if times is not None:
        t = np.asarray(times, dtype=float).reshape(-1)
        if t.shape != (q.shape[0],):
            raise ValueError(f"times must have one entry per sample ({q.shape[0]}), got "
                             f"{t.shape[0]}")
    lim = {k: np.asarray(getattr(limits, k)) for k in ("q_min", "q_max", "qd_max", "qdd_max")}
    out = []
    for j in range(n):
        label = f"joint {j + 1} ({limits.names[j]})"
        ang = limits.angular[j]
        checks = (
            ("position", "", "q", q[:, j], -q[:, j] > -lim["q_min"][j], lim["q_min"][j],
             "below the minimum", np.argmin),
            ("position", "", "q", q[:, j], q[:, j] > lim["q_max"][j], lim["q_max"][j],
             "above the maximum", np.argmax),
            ("velocity", "/s", "|qd|", np.abs(qd[:, j]), np.abs(qd[:, j]) > lim["qd_max"][j],
             lim["qd_max"][j], "above the limit", np.argmax),
            ("acceleration", "/s^2", "|qdd|", np.abs(qdd[:, j]),
             np.abs(qdd[:, j]) > lim["qdd_max"][j], lim["qdd_max"][j], "above the limit",
             np.argmax),
        )
        for kind, suffix, sym, values, bad, bound, words, worst in checks:
            count = int(np.count_nonzero(bad))
            if not count:
                continue
            i = int(worst(values))
            at = "" if t is None else f" at t = {t[i]:.6g} s"
            out.append(f"{label} {kind}: {sym} reaches {_fmt(values[i], ang, suffix)}{at}, "
                       f"{words} {_fmt(bound, ang, suffix)}; {count} of {len(values)} samples")
    return out


def check_trajectory(traj: FourierTrajectory, limits: JointLimits,
                     times: Float[ArrayLike, " T"]) -> None:
    """Raise ValueError naming the joints and limits that ``traj`` violates at ``times``."""
    if traj.n_joints != limits.n_joints:
        raise ValueError(f"trajectory has {traj.n_joints} joints, limits have "
                         f"{limits.n_joints}")
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or not np.all(np.isfinite(times)):
        raise ValueError(f"times must be a non-empty 1-D array of finite seconds, got shape "
                         f"{times.shape}")
    found = violations(limits, *traj.sample(times), times=times)
    if found:
        more = f" (and {len(found) - 5} more)" if len(found) > 5 else ""
        raise ValueError(f"trajectory violates {len(found)} joint limit(s): "
                         + "; ".join(found[:5]) + more)
