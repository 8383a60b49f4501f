"""The joint data every identification reads, checked once: one recording (a
:class:`~sedsabso_jax.Measurements`, or its arrays), or several fitted together
(:data:`Data`, :func:`recordings_of`), and their samples one after the other
(:func:`stacked`, :func:`joined`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeAlias

import numpy as np
from jaxtyping import ArrayLike, Float

from ..dynamics._robot import Robot
from ..measurements._container import Measurements

#: Joint data: a :class:`~sedsabso_jax.Measurements`, several of them (recordings fitted
#: together), or one recording's arrays ``(q, qd, qdd, tau)`` or ``(times, q, qd, qdd,
#: tau)``, each ``(samples, n)`` (times ``(samples,)``; without them, the sample numbers).
Data: TypeAlias = Measurements | Sequence[Measurements] | Sequence[ArrayLike]
#: Recordings fitted together may differ in rate by this fraction.
RATE_TOLERANCE = 0.01
#: The arrays of one recording, as :data:`Data` may give them.
FIELDS = ("q", "qd", "qdd", "tau")


def check_data(robot: Robot, q: Float[ArrayLike, "samples n"], qd: Float[ArrayLike, "samples n"],
               qdd: Float[ArrayLike, "samples n"], tau: Float[ArrayLike, "samples n"]
               ) -> list[Float[np.ndarray, "samples n"]]:
    """``q, qd, qdd, tau`` as float arrays ``(samples, n)`` of one length, finite."""
    n = robot.n_joints
    arrays = []
    for name, a in zip(FIELDS, (q, qd, qdd, tau)):
        a = np.asarray(a, dtype=float)
        if a.ndim != 2 or a.shape[1] != n:
            raise ValueError(f"{name} must have shape (samples, {n}) for robot {robot.name!r}, "
                             f"got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} contains NaN or Inf")
        arrays.append(a)
    lengths = {a.shape[0] for a in arrays}
    if len(lengths) != 1:
        raise ValueError(f"q, qd, qdd and tau need the same number of samples, got "
                         f"{[a.shape[0] for a in arrays]}")
    if arrays[0].shape[0] == 0:
        raise ValueError("no samples")
    return arrays


def _arrays(data: object) -> list:
    """The arrays of a tuple ``(q, qd, qdd, tau)`` or ``(times, q, qd, qdd, tau)``."""
    try:
        arrays = [] if isinstance(data, (np.ndarray, str)) else list(data)  # type: ignore
    except TypeError:
        arrays = []
    if len(arrays) not in (4, 5):
        what = (f"a tuple of {len(arrays)}" if isinstance(data, (tuple, list))
                else type(data).__name__)
        raise ValueError(f"data must be a Measurements, several, or one recording's arrays "
                         f"(q, qd, qdd, tau) or (times, q, qd, qdd, tau), got {what}")
    return arrays


def one_recording(robot: Robot, data: Measurements | Sequence[ArrayLike]) -> Measurements:
    """``data`` (a :class:`~sedsabso_jax.Measurements`, or its arrays with or without the
    times) as one checked recording of ``robot``."""
    if isinstance(data, Measurements):
        check_data(robot, data.q, data.qd, data.qdd, data.tau)  # the robot's joints
        return data
    arrays = _arrays(data)
    q, qd, qdd, tau = check_data(robot, *arrays[-4:])
    if len(arrays) == 4:
        return Measurements(np.arange(q.shape[0], dtype=float), q, qd, qdd, tau,
                            source="arrays (no times: sample numbers)")
    t = np.asarray(arrays[0], dtype=float)
    if t.shape != (q.shape[0],):
        raise ValueError(f"times must have one entry per sample ({q.shape[0]}), got shape "
                         f"{t.shape}")
    return Measurements(t, q, qd, qdd, tau)


def is_several(data: object) -> bool:
    """Whether ``data`` is a sequence of :class:`~sedsabso_jax.Measurements`."""
    return (isinstance(data, (list, tuple)) and len(data) > 0
            and all(isinstance(d, Measurements) for d in data))


def recordings_of(robot: Robot, data: Data) -> list[Measurements]:
    """``data`` (:data:`Data`) as a list of checked recordings of ``robot``. Several must
    have the robot's joints and one sampling rate (within :data:`RATE_TOLERANCE`); a
    ValueError names the recording that does not."""
    if not is_several(data):
        return [one_recording(robot, data)]  # type: ignore[arg-type]
    found: list[Measurements] = list(data)  # type: ignore[arg-type]  # is_several
    rates = []
    for k, d in enumerate(found):
        if d.n_joints != robot.n_joints:
            raise ValueError(f"recording {k + 1} ({d.source}) has {d.n_joints} joints, robot "
                             f"{robot.name!r} has {robot.n_joints}")
        rates.append(d.rate)
    if max(rates) > (1 + RATE_TOLERANCE) * min(rates):
        listed = ", ".join(f"{d.source}: {r:.4g} Hz" for d, r in zip(found, rates))
        raise ValueError(f"the recordings have different sampling rates ({listed}): load "
                         f"them at one rate (load_measurements(..., resample_hz=...))")
    return found


def stacked(recordings: Sequence[Measurements]) -> tuple[np.ndarray, ...]:
    """``(q, qd, qdd, tau, recording index)`` of ``recordings``, concatenated."""
    arrays = [np.concatenate([getattr(d, f) for d in recordings]) for f in FIELDS]
    index = np.concatenate([np.full(d.n_samples, k) for k, d in enumerate(recordings)])
    return (*arrays, index)


def joined(recordings: Sequence[Measurements]) -> Measurements:
    """One :class:`~sedsabso_jax.Measurements` of ``recordings`` one after the other (each
    later one's times shifted to start a sample step after the previous one's end), for
    reports and figures; one recording is returned as it is."""
    if len(recordings) == 1:
        return recordings[0]
    times, start = [], 0.0
    for d in recordings:
        t = d.times - d.times[0] + start
        times.append(t)
        start = float(t[-1]) + 1.0 / d.rate
    q, qd, qdd, tau, _ = stacked(recordings)
    return Measurements(np.concatenate(times), q, qd, qdd, tau,
                        source=" + ".join(d.source for d in recordings),
                        info={"recordings": [{"source": d.source, "samples": d.n_samples,
                                              **d.info} for d in recordings]})
