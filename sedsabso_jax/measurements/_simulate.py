"""Simulated measurements: torques of a robot model along a motion, with seeded noise and
outliers."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from ..dynamics._regressor import inverse_dynamics
from ..dynamics._robot import Robot
from ._container import Measurements, check_fields

#: Default size of a simulated outlier, in multiples of the joint's RMS torque.
DEFAULT_OUTLIER_SCALE = 10.0


def _nonnegative(label: str, value, upper: float | None = None) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{label} must be a number, got {value!r}") from err
    if not np.isfinite(value) or value < 0.0 or (upper is not None and value > upper):
        span = f"[0, {upper:g}]" if upper is not None else ">= 0"
        raise ValueError(f"{label} must be finite and in {span}, got {value!r}")
    return value


def simulate_measurements(robot: Robot, q: Float[ArrayLike, "T n"], qd: Float[ArrayLike, "T n"],
                          qdd: Float[ArrayLike, "T n"], times: Float[ArrayLike, " T"], *,
                          torque_noise: float = 0.0,
                          position_noise: float = 0.0, outlier_fraction: float = 0.0,
                          outlier_scale: float = DEFAULT_OUTLIER_SCALE,
                          seed: int | None = 0) -> Measurements:
    """Measurements of ``robot`` moving along ``q, qd, qdd (T, n)`` at ``times (T,)``.

    Torques ``inverse_dynamics(robot, robot.params, q, qd, qdd)`` (a plant of other
    parameters ``p``: ``equinox.tree_at(lambda r: r.params, robot, p)``), then, with
    ``numpy.random.default_rng`` streams spawned from ``seed`` (one each, so turning one
    kind of noise on does not change the others):

    - ``torque_noise``: Gaussian, standard deviation ``torque_noise`` times each joint's
      RMS noise-free torque (0.02 = 2 %);
    - ``position_noise``: Gaussian, standard deviation in rad (m for prismatic joints),
      added to the recorded ``q`` only; torques, ``qd`` and ``qdd`` stay those of the
      true motion;
    - ``outlier_fraction``: that fraction of the ``T n`` torque samples (rounded) get
      ``+-outlier_scale`` times the joint's RMS torque added, sign at random, on top of
      the Gaussian noise.

    The same seed gives identical data; ``seed=None`` draws fresh entropy.
    """
    torque_noise = _nonnegative("torque_noise", torque_noise)
    position_noise = _nonnegative("position_noise", position_noise)
    outlier_fraction = _nonnegative("outlier_fraction", outlier_fraction, 1.0)
    outlier_scale = _nonnegative("outlier_scale", outlier_scale)
    n = robot.n_joints
    source = "simulated"
    # torques are computed below; the positions stand in for them in the shape check
    fields = check_fields(source, {"times": times, "positions": q, "velocities": qd,
                                    "accelerations": qdd, "torques": q}, n)
    for key in ("velocities", "accelerations"):
        if fields[key] is None:
            raise ValueError(f"{source}: field {key!r}: missing")
    q, qd, qdd = fields["positions"], fields["velocities"], fields["accelerations"]
    tau = np.array(inverse_dynamics(robot, robot.params, q, qd, qdd), dtype=np.float64)
    rms = np.sqrt(np.mean(tau**2, axis=0))
    T = tau.shape[0]
    rng_tau, rng_q, rng_out = (np.random.default_rng(s)
                               for s in np.random.SeedSequence(seed).spawn(3))
    if torque_noise > 0.0:
        tau = tau + rng_tau.standard_normal(tau.shape) * (torque_noise * rms)
    q_recorded = q + rng_q.standard_normal(q.shape) * position_noise if position_noise else q
    n_outliers = int(round(outlier_fraction * T * n))
    if n_outliers:
        flat = rng_out.choice(T * n, size=n_outliers, replace=False)
        sign = rng_out.choice(np.array([-1.0, 1.0]), size=n_outliers)
        rows, cols = np.unravel_index(flat, (T, n))
        tau[rows, cols] += sign * outlier_scale * rms[cols]
    info = {"params": "robot.params",
            "torque_noise": torque_noise, "position_noise": position_noise,
            "outlier_fraction": outlier_fraction, "outlier_scale": outlier_scale,
            "n_outliers": n_outliers, "seed": seed,
            "torque_rms": [float(r) for r in rms]}
    return Measurements(fields["times"], q_recorded, qd, qdd, tau, source=source, info=info)


def simulate_measurements_along(
        robot: Robot,
        trajectory: Callable[[Float[np.ndarray, " T"]],
                             tuple[Float[ArrayLike, "T n"], Float[ArrayLike, "T n"],
                                   Float[ArrayLike, "T n"]]],
        times: Float[ArrayLike, " T"], **kwargs: Any) -> Measurements:
    """:func:`simulate_measurements` along ``trajectory``, a callable called once with the
    whole ``times`` array and returning ``(q, qd, qdd)``, each ``(T, n)``."""
    times = np.asarray(times, dtype=float)
    try:
        q, qd, qdd = trajectory(times)
    except (TypeError, ValueError) as err:
        raise ValueError(
            f"trajectory {trajectory!r}: calling it with times of shape {times.shape} must "
            f"return (q, qd, qdd), each (T, n); got the error {err}"
        ) from err
    return simulate_measurements(robot, np.asarray(q), np.asarray(qd), np.asarray(qdd), times,
                                 **kwargs)
