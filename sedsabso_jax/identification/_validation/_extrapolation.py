"""How far held-out data go beyond the data a model was identified on, per joint.

A torque model is fitted where the identification data moved: its friction terms on the
speeds seen, its gravity and inertia terms on the positions and accelerations seen.
Cross-validation over the motion's phase predicts the error on motions *like* the fitted
one; on faster motions it is too optimistic (docs/results/extrapolation.md).
:func:`extrapolation` measures, per joint, how far new data go beyond the
fitted data, on the joint-side :class:`~sedsabso_jax.Measurements` the identification
uses:

- ``position_beyond``: how far the positions go past the fitted range, in units of the
  fitted range's width (0: inside; 0.33: a third of the width past one end);
- ``speed_ratio``, ``acceleration_ratio``: peak |qd| (|qdd|) over the fitted peak.

Extremes are the 0.5 % and 99.5 % quantiles (``quantile``), on both data sets alike: the
derived velocities and accelerations carry filter edge transients and single-sample spikes
that would set true extremes; a motion time-scaled by s still gives exactly s (and s^2).
``quantile=0`` uses true extremes.

Beyond :data:`SPEED_THRESHOLD`, :data:`ACCELERATION_THRESHOLD` or
:data:`POSITION_THRESHOLD` the held-out data are flagged (where they come from:
docs/explanation/identification-defaults.md)."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence

import numpy as np

from ... import _deprecation
from ..._output import columns_note, markdown_table
from ...measurements._container import Measurements

#: Peak |qd| over the fitted peak above which a joint is reported as extrapolating.
SPEED_THRESHOLD = 1.25
#: Peak |qdd| over the fitted peak above which a joint is reported (accelerations are
#: derived by filtering and noisier, so a wider margin than speed).
ACCELERATION_THRESHOLD = 1.5
#: Positions past the fitted range, in its widths, above which a joint is reported.
POSITION_THRESHOLD = 0.10
#: The lower quantile taken as a signal's extreme (the upper is 1 - this).
QUANTILE = 0.005


def _ratio(new: np.ndarray, fitted: np.ndarray) -> np.ndarray:
    """``new / fitted``; inf where ``fitted`` is 0 and ``new`` is not, 0 where both are."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = new / fitted
    return np.where(fitted > 0, r, np.where(new > 0, np.inf, 0.0))


@dataclasses.dataclass(frozen=True)
class Extrapolation:
    """Per joint, how far held-out data go beyond the identification data (see
    :func:`extrapolation`). Arrays have one entry per joint; ``fitted_range`` and
    ``new_range`` are ``(n, 2)`` position extremes (low, high) of the identification and
    the held-out data, ``fitted_peak_speed`` and ``new_peak_speed`` the peaks of |qd|."""

    joint_names: tuple[str, ...]
    position_beyond: np.ndarray
    speed_ratio: np.ndarray
    acceleration_ratio: np.ndarray
    fitted_range: np.ndarray
    new_range: np.ndarray
    fitted_peak_speed: np.ndarray
    new_peak_speed: np.ndarray
    quantile: float = QUANTILE

    def flagged(self) -> list[int]:
        """Indices of the joints beyond a threshold (:data:`POSITION_THRESHOLD`,
        :data:`SPEED_THRESHOLD`, :data:`ACCELERATION_THRESHOLD`)."""
        return [j for j in range(len(self.joint_names))
                if self.position_beyond[j] > POSITION_THRESHOLD
                or self.speed_ratio[j] > SPEED_THRESHOLD
                or self.acceleration_ratio[j] > ACCELERATION_THRESHOLD]

    def message(self) -> str | None:
        """One line naming the joints beyond a threshold and by how much, or None."""
        parts = []
        for j in self.flagged():
            what = []
            if self.position_beyond[j] > POSITION_THRESHOLD:
                what.append(f"position {self.position_beyond[j]:.2f} of the fitted range "
                            f"past it")
            if self.speed_ratio[j] > SPEED_THRESHOLD:
                what.append(f"speed {self.speed_ratio[j]:.2f}x")
            if self.acceleration_ratio[j] > ACCELERATION_THRESHOLD:
                what.append(f"acceleration {self.acceleration_ratio[j]:.2f}x")
            parts.append(f"{self.joint_names[j]} {', '.join(what)}")
        if not parts:
            return None
        return ("held-out data go beyond the identification data (x: peak over the fitted "
                "peak), where the fit extrapolates and its predicted error may be too low: "
                + "; ".join(parts))

    def warn(self) -> None:
        """A ``UserWarning`` with :meth:`message`, if any joint is beyond a threshold."""
        text = self.message()
        if text is not None:
            warnings.warn(text, UserWarning, stacklevel=_deprecation.caller_stacklevel())

    def table(self) -> str:
        """Markdown table, one row per joint (columns in :meth:`note`)."""
        flagged = set(self.flagged())
        rows = [[name, f"{self.fitted_range[j, 0]:.3f}", f"{self.fitted_range[j, 1]:.3f}",
                 f"{self.new_range[j, 0]:.3f}", f"{self.new_range[j, 1]:.3f}",
                 f"{self.position_beyond[j]:.3f}", f"{self.speed_ratio[j]:.3f}",
                 f"{self.acceleration_ratio[j]:.3f}", "yes" if j in flagged else "no"]
                for j, name in enumerate(self.joint_names)]
        return markdown_table(["joint", "fitted min", "fitted max", "new min", "new max",
                               "position beyond", "speed ratio", "acceleration ratio",
                               "beyond"], rows, align=["left"] + ["right"] * 7 + ["left"])

    def note(self) -> str:
        """The note under :meth:`table` that defines its columns."""
        q = 100 * self.quantile
        ext = (f"the {q:g} % and {100 - q:g} % quantiles" if self.quantile > 0
               else "the true extremes")
        peak = (f"the {100 - q:g} % quantile of the absolute value" if self.quantile > 0
                else "the largest absolute value")
        return columns_note(
            ("joint", "one row per joint"),
            (("fitted min", "fitted max"), f"position extremes of the identification data "
             f"({ext}) [rad, m on a prismatic joint]"),
            (("new min", "new max"), "the same of the held-out data"),
            ("position beyond", "how far the held-out positions go past the fitted range, "
             "in units of its width (0: inside, 0.5: half the width past one end)"),
            ("speed ratio", "peak velocity of the held-out data over peak velocity of the "
             f"identification data (peak: {peak})"),
            ("acceleration ratio", "the same for the acceleration"),
            ("beyond", f"`yes` where position beyond is above {POSITION_THRESHOLD:g}, speed "
             f"ratio above {SPEED_THRESHOLD:g} or acceleration ratio above "
             f"{ACCELERATION_THRESHOLD:g} (the joints the warning names)"))

    def as_dict(self) -> dict:
        """The numbers, for JSON (lists per joint)."""
        return {"joint_names": list(self.joint_names),
                "position_beyond": self.position_beyond.tolist(),
                "speed_ratio": self.speed_ratio.tolist(),
                "acceleration_ratio": self.acceleration_ratio.tolist(),
                "fitted_range": self.fitted_range.tolist(),
                "new_range": self.new_range.tolist(),
                "fitted_peak_speed": self.fitted_peak_speed.tolist(),
                "new_peak_speed": self.new_peak_speed.tolist(),
                "beyond": [self.joint_names[j] for j in self.flagged()],
                "quantile": self.quantile,
                "thresholds": {"position_beyond": POSITION_THRESHOLD,
                               "speed_ratio": SPEED_THRESHOLD,
                               "acceleration_ratio": ACCELERATION_THRESHOLD}}


def _extremes(x: np.ndarray, quantile: float) -> tuple[np.ndarray, np.ndarray]:
    if quantile > 0:
        return np.quantile(x, quantile, axis=0), np.quantile(x, 1 - quantile, axis=0)
    return x.min(axis=0), x.max(axis=0)


def _peak(x: np.ndarray, quantile: float) -> np.ndarray:
    return np.quantile(np.abs(x), 1 - quantile, axis=0) if quantile > 0 else np.abs(x).max(0)


def joint_names_of(data: Measurements, held_out: Measurements,
                   joint_names: Sequence[str] | None) -> tuple[str, ...]:
    """``joint_names`` (default ``q1, q2, ...``), checked against the joints of ``data``
    and ``held_out``, which must have as many."""
    n = data.q.shape[1]
    if held_out.q.shape[1] != n:
        raise ValueError(f"data have {n} joints, held_out {held_out.q.shape[1]}")
    names = tuple(joint_names) if joint_names is not None else tuple(
        f"q{j + 1}" for j in range(n))
    if len(names) != n:
        raise ValueError(f"{len(names)} joint names for {n} joints")
    return names


def extrapolation(data: Measurements, held_out: Measurements, *,
                  joint_names: Sequence[str] | None = None, quantile: float = QUANTILE,
                  warn: bool = False) -> Extrapolation:
    """How far ``held_out`` goes beyond ``data`` (both joint-side
    :class:`~sedsabso_jax.Measurements`, e.g. after
    :meth:`~sedsabso_jax.Transmission.to_joint_side`), per joint.

    Per joint ``j``, with ``lo, hi`` the ``quantile`` and ``1 - quantile`` quantiles of
    ``q[:, j]`` (``quantile=0``: min and max) and peaks the ``1 - quantile`` quantile of
    the absolute value: ``position_beyond = max(lo_data - lo_new, hi_new - hi_data, 0) /
    (hi_data - lo_data)`` (inf if the joint did not move in ``data`` but does beyond),
    ``speed_ratio = peak|qd_new| / peak|qd_data|``, ``acceleration_ratio`` likewise for
    ``qdd`` (inf over a zero peak, 0 if both are 0). ``joint_names``: default ``q1, q2,
    ...``; ``warn``: a ``UserWarning`` naming the joints beyond the thresholds
    (:meth:`Extrapolation.warn`)."""
    if not 0 <= quantile < 0.5:
        raise ValueError(f"quantile must be in [0, 0.5), got {quantile!r}")
    names = joint_names_of(data, held_out, joint_names)
    lo, hi = _extremes(np.asarray(data.q, float), quantile)
    lo_new, hi_new = _extremes(np.asarray(held_out.q, float), quantile)
    past = np.maximum(np.maximum(lo - lo_new, hi_new - hi), 0.0)
    beyond = _ratio(past, hi - lo)
    speed, speed_new = (_peak(np.asarray(m.qd, float), quantile) for m in (data, held_out))
    acc, acc_new = (_peak(np.asarray(m.qdd, float), quantile) for m in (data, held_out))
    result = Extrapolation(names, beyond, _ratio(speed_new, speed), _ratio(acc_new, acc),
                           np.stack([lo, hi], 1), np.stack([lo_new, hi_new], 1),
                           speed, speed_new, quantile)
    if warn:
        result.warn()
    return result
