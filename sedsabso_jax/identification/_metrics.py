"""Validation metrics: how well predicted torques match measured ones on held-out data.

With ``e = tau_measured - tau_predicted`` over ``T`` samples and ``n`` joints, per joint
``j`` (``RMS(x) = sqrt(mean over samples of x^2)``):

- ``rms[j] = RMS(e_j)``, in the torque unit;
- ``relative_rms_percent[j] = 100 RMS(e_j) / RMS(tau_measured_j)``;
- ``nrms_range_percent[j] = 100 RMS(e_j) / (max - min of tau_measured_j)``;
- ``nrms_limits_percent_per_joint[j] = 100 RMS(e_j) / (2 limit_j)``: the error against the
  joint's whole torque range ``[-limit, +limit]``;

and overall:

- ``rms_overall = RMS`` of all ``T n`` errors;
- ``relative_rms_percent_overall = 100 ||e|| / ||tau_measured||`` (Frobenius norms);
- ``nrms_range_percent_mean``: mean over joints of ``nrms_range_percent``;
- ``nrms_limits_percent``: mean over joints of ``nrms_limits_percent_per_joint``, the
  figure FloBaRoID publishes for its KUKA LWR4+ data (None without limits).

A ratio whose denominator is zero (a joint whose measured torque is identically zero, or
constant for the range) is NaN, written as ``null`` by :meth:`Metrics.as_dict`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from .._output import columns_note, jsonable, markdown_table

_PER_JOINT = ("rms", "relative_rms_percent", "nrms_range_percent",
              "nrms_limits_percent_per_joint")


@dataclasses.dataclass(frozen=True, eq=False)
class Metrics:
    """Result of :func:`validation_metrics` (definitions in the module docstring).

    Per-joint fields are numpy arrays ``(n,)``; overall ones are floats. Also readable
    like a dict (``m["nrms_limits_percent"]``); :meth:`as_dict` gives plain lists and
    floats for JSON.
    """

    rms: np.ndarray
    relative_rms_percent: np.ndarray
    nrms_range_percent: np.ndarray
    nrms_limits_percent_per_joint: np.ndarray | None
    rms_overall: float
    relative_rms_percent_overall: float
    nrms_range_percent_mean: float
    nrms_limits_percent: float | None
    n_samples: int
    n_joints: int

    def __getitem__(self, key: str) -> Any:
        if key not in self.keys():
            raise KeyError(key)
        return getattr(self, key)

    def keys(self) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(self))

    def as_dict(self) -> dict:
        """Plain Python values (lists of floats, floats, ints, None for NaN or absent)."""
        return jsonable({key: getattr(self, key) for key in self.keys()})

    def table(self, joint_names: Sequence[str] | None = None) -> str:
        """A small text table: one line per joint and one for the overall figures."""
        names = list(joint_names) if joint_names is not None else [
            f"joint {j + 1}" for j in range(self.n_joints)]
        limits = self.nrms_limits_percent_per_joint
        width = max(7, *(len(s) for s in names))
        lines = [f"{'':<{width}}  {'RMS err':>10}  {'rel RMS %':>10}  {'NRMS range %':>12}"
                 f"  {'NRMS limits %':>13}"]
        for j, name in enumerate(names):
            lim = f"{limits[j]:13.4f}" if limits is not None else f"{'-':>13}"
            lines.append(f"{name:<{width}}  {self.rms[j]:10.4g}  "
                         f"{self.relative_rms_percent[j]:10.3f}  "
                         f"{self.nrms_range_percent[j]:12.3f}  {lim}")
        lim = (f"{self.nrms_limits_percent:13.4f}" if self.nrms_limits_percent is not None
               else f"{'-':>13}")
        lines.append(f"{'overall':<{width}}  {self.rms_overall:10.4g}  "
                     f"{self.relative_rms_percent_overall:10.3f}  "
                     f"{self.nrms_range_percent_mean:12.3f}  {lim}")
        return "\n".join(lines)


def _torques(name: str, value) -> np.ndarray:
    try:
        arr = np.asarray(value)
    except Exception as err:  # any conversion failure is bad input
        raise ValueError(f"{name}: not an array ({err})") from err
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {arr.dtype}")
    arr = arr.astype(np.float64)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{name}: expected shape (T, n_joints) with T, n >= 1, got "
                         f"{np.shape(value)}")
    bad = ~np.isfinite(arr)
    if bad.any():
        t, j = np.argwhere(bad)[0]
        raise ValueError(f"{name}: expected finite numbers, got {int(bad.sum())} NaN/Inf "
                         f"value(s), the first at sample {t + 1} of {arr.shape[0]}, joint {j + 1}")
    return arr


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0.0, 100.0 * num / np.where(den > 0.0, den, 1.0), np.nan)


def nrms_over_limits(rms: Float[ArrayLike, " n"], limits: Float[ArrayLike, " n"] | Sequence[float]
                     ) -> Float[np.ndarray, " n"]:
    """Per joint ``100 RMS(e_j) / (2 limit_j)`` [%], the error against the joint's whole
    torque range ``[-limit, +limit]``; its mean over the joints is the figure FloBaRoID
    publishes."""
    return 100.0 * np.asarray(rms, dtype=float) / (2.0 * np.asarray(limits, dtype=float))


def validation_metrics(tau_measured: Float[ArrayLike, "T ..."],
                       tau_predicted: Float[ArrayLike, "T ..."],
                       torque_limits: Float[ArrayLike, " n"] | Sequence[float] | None = None
                       ) -> Metrics:
    """Compare predicted with measured torques, ``(T, n)`` each (``(T,)``: one joint).

    ``torque_limits`` ``(n,)``, positive (e.g. the URDF efforts): adds the NRMS over the
    limits. Raises ValueError for mismatched shapes, NaN/Inf or bad limits.
    """
    measured = _torques("tau_measured", tau_measured)
    predicted = _torques("tau_predicted", tau_predicted)
    if measured.shape != predicted.shape:
        raise ValueError(f"tau_predicted: expected the shape of tau_measured "
                         f"{measured.shape}, got {predicted.shape}")
    T, n = measured.shape
    err = measured - predicted
    rms = np.sqrt(np.mean(err**2, axis=0))
    relative = _ratio(rms, np.sqrt(np.mean(measured**2, axis=0)))
    nrms_range = _ratio(rms, measured.max(axis=0) - measured.min(axis=0))
    per_limit = mean_limit = None
    if torque_limits is not None:
        limits = np.asarray(torque_limits)
        if limits.dtype.kind not in "biuf" or limits.shape != (n,):
            raise ValueError(f"torque_limits: expected {n} numbers (one per joint), got "
                             f"shape {limits.shape}, dtype {limits.dtype}")
        limits = limits.astype(np.float64)
        if not (np.all(np.isfinite(limits)) and np.all(limits > 0.0)):
            raise ValueError(f"torque_limits: expected finite positive limits, got "
                             f"{limits.tolist()}")
        per_limit = nrms_over_limits(rms, limits)
        mean_limit = float(np.mean(per_limit))
    norm = float(np.linalg.norm(measured))
    overall = 100.0 * float(np.linalg.norm(err)) / norm if norm > 0.0 else math.nan
    return Metrics(
        rms=rms,
        relative_rms_percent=relative,
        nrms_range_percent=nrms_range,
        nrms_limits_percent_per_joint=per_limit,
        rms_overall=float(np.sqrt(np.mean(err**2))),
        relative_rms_percent_overall=overall,
        nrms_range_percent_mean=float(np.mean(nrms_range)),
        nrms_limits_percent=mean_limit,
        n_samples=int(T),
        n_joints=int(n),
    )


def mean_metrics(metrics: Sequence[Metrics]) -> Metrics:
    """Each figure of ``metrics`` (several recordings' :class:`Metrics`, of one robot)
    averaged over them, each recording weighed alike whatever its length; ``n_samples``
    their total. The NRMS over the limits is None unless every one has it."""
    if not metrics or len({m.n_joints for m in metrics}) != 1:
        raise ValueError(f"mean_metrics needs metrics of one joint count, got "
                         f"{[m.n_joints for m in metrics]}")

    def mean(key: str) -> Any:
        values = [getattr(m, key) for m in metrics]
        if any(v is None for v in values):
            return None
        return np.mean(values, axis=0) if key in _PER_JOINT else float(np.mean(values))

    return Metrics(**{key: mean(key) for key in Metrics.__dataclass_fields__
                      if key not in ("n_samples", "n_joints")},
                   n_samples=sum(m.n_samples for m in metrics), n_joints=metrics[0].n_joints)


#: The note under the report's first metrics table (the module docstring defines the
#: figures).
METRICS_NOTE = columns_note(
    ("joint", "one row per joint, `overall` for all joints together"),
    ("RMS error [N m]", "root mean square over the samples of measured - predicted torque "
     "(N on a prismatic joint)"),
    ("relative RMS [%]", "100 RMS error / RMS of the measured torque (overall: 100 norm(e) / "
     "norm(tau), Frobenius norms)"),
    ("NRMS range [%]", "100 RMS error / (max - min of the measured torque), overall the "
     "mean over the joints"),
    ("NRMS limits [%]", "100 RMS error / (2 torque limit), the error against the whole "
     "range [-limit, limit], overall the mean over the joints (FloBaRoID's figure), `-` "
     "without limits"))
#: The note under a later metrics table.
SAME_COLUMNS = "Columns as in the fit table above."


def metrics_table(metrics: Metrics, joint_names: Sequence[str]) -> str:
    """Markdown table of ``metrics``: one row per joint and one for the overall figures
    (the numbers of :meth:`~sedsabso_jax.Metrics.table`; columns in :data:`METRICS_NOTE`)."""
    limits = metrics.nrms_limits_percent_per_joint
    rows = [[name, f"{metrics.rms[j]:.4g}", f"{metrics.relative_rms_percent[j]:.3f}",
             f"{metrics.nrms_range_percent[j]:.3f}",
             "-" if limits is None else f"{limits[j]:.4f}"]
            for j, name in enumerate(joint_names)]
    rows.append(["overall", f"{metrics.rms_overall:.4g}",
                 f"{metrics.relative_rms_percent_overall:.3f}",
                 f"{metrics.nrms_range_percent_mean:.3f}",
                 "-" if metrics.nrms_limits_percent is None
                 else f"{metrics.nrms_limits_percent:.4f}"])
    return markdown_table(["joint", "RMS error [N m]", "relative RMS [%]", "NRMS range [%]",
                           "NRMS limits [%]"], rows, align=["left"] + ["right"] * 4)
