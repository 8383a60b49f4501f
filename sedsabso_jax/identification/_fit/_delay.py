"""The time shift between the torques and the motion (:func:`estimate_delay`): the delay
``d`` at which the torques ``tau(t + d)`` are best explained by a torque model at the
motion ``(q, qd, qdd)(t)``, one per robot, in seconds (sub-sample).

A bus, a filter or a current loop can put the torque signal behind the positions (or
ahead of them: a position filter), by amounts that differ per robot and whose sign
differs between robots. The model is linear in its values, so for each trial shift the
fit is a projection of the shifted torques on the regressor's columns: the regressor is
computed and orthonormalised once (pivoted QR, the columns the data determine), each
trial costs one product. The trials are every whole-sample shift within
``+-largest_s`` (the torques at other samples, exact), the delay the vertex of the
parabola through the best one and its two neighbours (sub-sample), all on the samples
every trial has (``ceil(largest_s * rate) + 1`` dropped at each recording's ends).
Apply it with :meth:`~sedsabso_jax.Measurements.delayed`.

The delay is confounded with what the model leaves out: a presliding state lags the
velocity much as a delay does, so estimate it with the model the fit will use and judge
it on held-out data (what it did on the shipped robots: docs/explanation/
identification-defaults.md, "A delay between torques and positions"). The default
identification does not search it yet.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from ...dynamics._robot import Robot
from .._estimators._estimator import Limits, per_joint
from .._model._offset import Offset
from .._model._torque_model import TorqueModel
from .._recordings import Data
from ._samples import Samples, recorded

#: The largest delay tried by default [s], either sign.
LARGEST_DELAY_S = 0.02


@dataclasses.dataclass(frozen=True, eq=False)
class DelayEstimate:
    """What :func:`estimate_delay` found: the delay in ``seconds`` (positive: the torques
    lag the motion) and in ``samples``; ``shifts`` (whole samples) and ``losses`` (the
    weighted mean square residual at each); ``at_bound``: the best whole-sample shift is
    the largest tried (the delay may lie beyond: widen ``largest_s``); ``rate`` the
    samples' rate [Hz]; ``residuals`` and ``columns`` how many rows and fitted columns the
    losses are of."""

    seconds: float
    samples: float
    shifts: np.ndarray
    losses: np.ndarray
    at_bound: bool
    rate: float = float("nan")
    residuals: int = 0
    columns: int = 0

    @property
    def standard_error_s(self) -> float:
        """The delay's standard error [s] from the losses' curvature at the vertex, as for
        white residuals: ``sqrt(2 s^2 / S'')``, ``S`` the residual sum of squares, ``s^2``
        its minimum over the degrees of freedom. Residuals correlated in time (a model's
        error is) make the true error larger. NaN at the bound or where the losses do not
        curve up."""
        best = int(np.argmin(self.losses))
        if self.at_bound or not 0 < best < self.losses.size - 1:
            return float("nan")
        down, here, up = self.losses[best - 1:best + 2]
        curvature = (down - 2 * here + up) * self.residuals  # S'' per sample^2
        s2 = max(here, 0.0) * self.residuals / max(self.residuals - self.columns, 1)
        return float(np.sqrt(2 * s2 / curvature) / self.rate) if curvature > 0 else float("nan")


def estimate_delay(robot: Robot, data: Data, model: TorqueModel | None = None, *,
                   largest_s: float = LARGEST_DELAY_S, limits: Limits = None
                   ) -> DelayEstimate:
    """The delay of the torques behind the motion in ``data`` (module docstring) for
    ``model`` (None: the base regressor's rigid body, viscous and Coulomb friction and a
    torque offset), trying whole-sample shifts up to ``largest_s`` seconds either way;
    each joint's rows weighted by ``1 / limits`` (None: equally). Several recordings share
    one delay."""
    largest = float(largest_s)
    if not (np.isfinite(largest) and largest > 0):
        raise ValueError(f"largest_s must be a number of seconds > 0, got {largest_s!r}")
    recordings, samples = recorded(robot, data)
    model = TorqueModel.of(robot, [Offset()]) if model is None else model
    rate = float(np.median([r.rate for r in recordings]))
    m = shifts_within(largest, rate)
    if any(r.n_samples <= 2 * (m + 1) for r in recordings):
        raise ValueError(f"a delay of up to {largest:g} s ({m} samples) needs recordings of "
                         f"more than {2 * (m + 1)} samples")
    given = per_joint("limits", limits, robot.n_joints)
    return delay_of(samples, model, rate, m, None if given is None else np.asarray(given))


def shifts_within(largest_s: float, rate: float) -> int:
    """The whole-sample shifts tried each way for delays up to ``largest_s`` at ``rate``
    (``ceil``: the bound is at least ``largest_s``)."""
    return max(1, int(np.ceil(largest_s * rate)))


def delay_of(samples: Samples, model: TorqueModel, rate: float, m: int,
             limits: np.ndarray | None, train: np.ndarray | None = None) -> DelayEstimate:
    """:func:`estimate_delay` on ``samples`` (whole recordings, their rows of ``model``
    kept), shifts up to ``m`` samples, rows weighted by ``1 / limits``; ``train``: only
    the samples this mask keeps, each with the ``m + 1`` around it (a validation's
    training samples: no torque of a tested sample is read)."""
    n_samples = samples.q.shape[0]
    index = np.arange(n_samples)
    recording = np.zeros(n_samples, int) if samples.recording is None else samples.recording
    # a sample whose shifted neighbours all lie in its recording (and in ``train``)
    inside = np.ones(n_samples, bool)
    usable = np.ones(n_samples, bool) if train is None else np.asarray(train, bool)
    for step in range(-m - 1, m + 2):
        j = np.clip(index + step, 0, n_samples - 1)
        inside &= (index + step >= 0) & (index + step < n_samples) & (recording[j] == recording)
        inside &= usable[j]
    rows = index[inside]
    if rows.size == 0:
        raise ValueError(f"no sample has {m + 1} neighbours each side to shift the torques by")
    n = samples.q.shape[1]
    w = np.ones(n) if limits is None else 1.0 / np.asarray(limits, dtype=float)
    Y = (samples.rows(model)[rows] * w[:, None]).reshape(-1, model.dim)
    Q, R, _ = scipy.linalg.qr(Y, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    Q = Q[:, :int(np.sum(diag > diag[0] * max(Y.shape) * np.finfo(float).eps))]
    shifts = np.arange(-m, m + 1)
    losses = np.empty(shifts.size)
    for i, k in enumerate(shifts):
        b = (samples.tau[rows + k] * w).reshape(-1)
        losses[i] = (b @ b - np.sum((Q.T @ b) ** 2)) / b.size
    best = int(np.argmin(losses))
    vertex = float(shifts[best])
    if 0 < best < shifts.size - 1:
        down, here, up = losses[best - 1:best + 2]
        curvature = down - 2 * here + up
        if curvature > 0:
            vertex += 0.5 * (down - up) / curvature
    return DelayEstimate(float(vertex / rate), float(vertex), shifts, losses,
                         best in (0, shifts.size - 1), rate, b.size, Q.shape[1])
