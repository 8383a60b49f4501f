"""The held-out recordings of a report (``select_and_identify(..., held_out=...)``,
``identify --validate FILE [FILE ...]``): each judged alone against the fit, never fitted
to and never choosing (:func:`judge`: its metrics, how far it goes beyond the
identification data, how much more it rests and the validated error weighed to its
speeds), and, for several, their mean (each recording weighed alike); their text
(:func:`held_out_lines`) and JSON (:func:`held_out_document`)."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping, Sequence
from typing import TypeAlias

import numpy as np

from ... import _deprecation
from ..._output import columns_note, markdown_table
from ...dynamics._robot import Robot
from ...measurements._container import Measurements
from .._estimators._estimator import Limits
from .._fit._identify import Identification
from .._metrics import SAME_COLUMNS, Metrics, mean_metrics, metrics_table, validation_metrics
from .._recordings import Data, one_recording
from .._validation._cross_validation import CrossValidation, score_of
from .._validation._extrapolation import Extrapolation, extrapolation
from .._validation._rests import Rests, rests

#: What ``held_out`` may be: one recording (a Measurements or its arrays), a list or
#: tuple of Measurements, or a mapping name -> Measurements.
HeldOutData: TypeAlias = Data | Mapping[str, Measurements]


@dataclasses.dataclass(frozen=True, eq=False)
class HeldOut:
    """One held-out recording judged against a fit: its ``name`` (the file given to
    ``--validate``; in Python the mapping's key, else its ``source``), the recording
    ``data``, its :class:`~sedsabso_jax.Metrics`, the ``predicted`` torques, how far it
    goes beyond the identification data (:class:`~sedsabso_jax.identification.Extrapolation`)
    and how much more it rests, with the validated error weighed to its speeds
    (:class:`~sedsabso_jax.identification.Rests`)."""

    name: str
    data: Measurements
    metrics: Metrics
    predicted: np.ndarray
    extrapolation: Extrapolation
    rests: Rests

    @property
    def measured(self) -> float:
        """Its error in the validation's measure: NRMS over the limits %, else relative
        RMS % (the measure :attr:`Rests.predicted` predicts)."""
        return score_of(self.metrics)

    def as_dict(self) -> dict:
        return {"name": self.name, "source": self.data.source,
                "samples": self.data.n_samples, "measured_percent": self.measured,
                "predicted_percent": self.rests.predicted, "metrics": self.metrics.as_dict(),
                "extrapolation": self.extrapolation.as_dict(), "rests": self.rests.as_dict()}


def named_recordings(robot: Robot, held_out: HeldOutData | None
                     ) -> tuple[tuple[str, Measurements], ...]:
    """``held_out`` as ``(name, recording)`` pairs, each a recording of ``robot``: None
    (none); one recording (a :class:`~sedsabso_jax.Measurements` or its arrays); a list or
    tuple of Measurements; a mapping name -> Measurements. Names: the mapping's keys, else
    each recording's ``source`` (a loaded file's path), ``held-out k`` (k from 1) for
    recordings whose source another shares. A ValueError names the entry that is not a
    recording of ``robot``."""
    if held_out is None:
        return ()
    if isinstance(held_out, Mapping):
        entries = list(held_out.items())
        for name, _ in entries:
            if not isinstance(name, str) or not name.strip():
                raise ValueError(f"held_out: a mapping's keys name its recordings, got "
                                 f"{name!r}: give non-empty strings")
        labels = [f"held_out[{name!r}]" for name, _ in entries]
    elif isinstance(held_out, (list, tuple)) and (
            len(held_out) not in (4, 5) or any(isinstance(h, Measurements) for h in held_out)):
        entries = [("", h) for h in held_out]  # several: their names below
        labels = [f"held_out[{k}]" for k in range(len(held_out))]
    else:
        one = one_recording(robot, held_out)  # type: ignore[arg-type]
        return ((one.source, one),)
    if not entries:
        raise ValueError("held_out: empty; give None for no held-out data")
    found = []
    for label, (name, h) in zip(labels, entries):
        if not isinstance(h, Measurements):
            raise ValueError(f"{label}: expected a Measurements (sj.load_measurements(path) "
                             f"reads a file), got {type(h).__name__}")
        try:
            found.append((name, one_recording(robot, h)))
        except ValueError as err:
            raise ValueError(f"{label} ({h.source}): {err}") from None
    if isinstance(held_out, Mapping):
        return tuple(found)
    sources = [d.source for _, d in found]
    names = [s if sources.count(s) == 1 else f"held-out {k}" for k, s in enumerate(sources, 1)]
    if len(set(names)) < len(names):
        names = [f"held-out {k}" for k in range(1, len(found) + 1)]
    return tuple(zip(names, (d for _, d in found)))


def _warn(name: str | None, message: str | None) -> None:
    if message is not None:
        warnings.warn(message if name is None else f"{name}: {message}", UserWarning,
                      stacklevel=_deprecation.caller_stacklevel())


def judge(ident: Identification, data: Measurements,
          named: Sequence[tuple[str, Measurements]], limits: Limits = None,
          cross_validation: CrossValidation | None = None) -> tuple[HeldOut, ...]:
    """Each of ``named`` (:func:`named_recordings`) judged against ``ident``, fitted to
    ``data`` (the recordings joined): its torques predicted and compared, how far it goes
    beyond ``data`` (:func:`~sedsabso_jax.identification.extrapolation`) and how much
    more it rests (:func:`~sedsabso_jax.identification.rests`, with ``cross_validation``
    where it kept its residuals: the validated error weighed to its speeds); a
    ``UserWarning`` for each where a joint is beyond the thresholds or rests more,
    starting with the recording's name when there are several."""
    joints = ident.model.robot.joint_names
    cv = (cross_validation if cross_validation is not None
          and cross_validation.residuals is not None else None)
    scale = None if limits is None else np.asarray(limits, dtype=float)
    judged = []
    for name, held in named:
        beyond = extrapolation(data, held, joint_names=joints)
        at_rest = rests(data, held, cross_validation=cv, limits=scale, joint_names=joints)
        for found in (beyond, at_rest):
            _warn(name if len(named) > 1 else None, found.message())
        predicted = np.asarray(ident.predict(held.q, held.qd, held.qdd))
        judged.append(HeldOut(name, held, validation_metrics(held.tau, predicted, limits),
                              predicted, beyond, at_rest))
    return tuple(judged)


def mean_predicted(judged: Sequence[HeldOut]) -> float | None:
    """The mean of the recordings' predicted errors (:attr:`Rests.predicted`), None
    unless each has one."""
    predicted = [p for h in judged if (p := h.rests.predicted) is not None]
    return float(np.mean(predicted)) if len(predicted) == len(judged) else None


def held_out_document(judged: Sequence[HeldOut]) -> dict | None:
    """The JSON's ``validations``: each recording's figures (``recordings``, in the order
    given) and their ``mean``; None without held-out data."""
    if not judged:
        return None
    return {"measure": ("nrms_limits_percent" if judged[0].metrics.nrms_limits_percent
                        is not None else "relative_rms_percent"),
            "recordings": [h.as_dict() for h in judged],
            "mean": {"measured_percent": float(np.mean([h.measured for h in judged])),
                     "predicted_percent": mean_predicted(judged),
                     "metrics": mean_metrics([h.metrics for h in judged]).as_dict()}}


def _recording_lines(h: HeldOut, joints: Sequence[str], first: bool, several: bool,
                     ) -> list[str]:
    """One recording's section: its metrics, extrapolation and rests tables (their notes
    under the first only), the weighed prediction and the warnings."""
    about = f" on {h.name}" if several else ""
    what = (f"{h.data.source}, " if not several or h.data.source != h.name else "")
    data = h.name if several else "the validation data"
    lines = ["", f"validation{about} ({what}{h.data.n_samples} samples):", "",
             metrics_table(h.metrics, joints), "", SAME_COLUMNS,
             "", f"extrapolation (how far {data} go{'es' * several} beyond the "
                 f"identification data, per joint):", "", h.extrapolation.table(), "",
             h.extrapolation.note() if first else "Columns as in the first extrapolation "
                                                  "table above."]
    if h.extrapolation.message() is not None:
        lines += ["", f"warning: {h.extrapolation.message()}"]
    lines += ["", f"rests{about} (the share of its samples at rest and slow, per joint):"
              if several else "rests (the share of samples at rest and slow, per joint):", "",
              h.rests.table(), "", h.rests.note() if first else "Columns as in the first "
                                                                "rests table above."]
    if h.rests.predicted is not None:
        lines += ["", f"predicted error on {data}, the validated error weighed to "
                      f"{'its' if several else 'their'} speeds: {h.rests.predicted:.4f} % "
                      f"({h.rests.factor:.2f} x the validated error)"]
    if h.rests.message() is not None:
        lines += ["", f"warning: {h.rests.message()}"]
    return lines


def _summary(judged: Sequence[HeldOut]) -> list[str]:
    """The table of every recording's overall figures and their mean, with its note."""
    def row(name: str, samples: str, m: Metrics, predicted: float | None,
            beyond: str, more: str) -> list[str]:
        return [name, samples, f"{m.rms_overall:.4g}", f"{m.relative_rms_percent_overall:.3f}",
                f"{m.nrms_range_percent_mean:.3f}",
                "-" if m.nrms_limits_percent is None else f"{m.nrms_limits_percent:.4f}",
                "-" if predicted is None else f"{predicted:.4f}", beyond, more]

    rows = [row(h.name, str(h.data.n_samples), h.metrics, h.rests.predicted,
                ", ".join(h.extrapolation.as_dict()["beyond"]) or "-",
                ", ".join(h.rests.as_dict()["rests_more"]) or "-") for h in judged]
    mean = mean_metrics([h.metrics for h in judged])
    rows.append(row("mean", str(mean.n_samples), mean, mean_predicted(judged), "", ""))
    measured = ("NRMS limits [%]" if mean.nrms_limits_percent is not None
                else "relative RMS [%]")
    return ["", f"the {len(judged)} held-out recordings and their mean (each judged alone, "
                f"never fitted to nor chosen by):", "",
            markdown_table(["recording", "samples", "RMS error [N m]", "relative RMS [%]",
                            "NRMS range [%]", "NRMS limits [%]", "predicted [%]", "beyond",
                            "rests more"], rows, align=["left"] + ["right"] * 6 + ["left"] * 2),
            "", columns_note(
                ("recording", "the held-out recording (the file given to `--validate`), "
                 "`mean` the mean of each column over them, each recording weighed alike"),
                ("samples", "its samples (the mean's: all of them)"),
                (("RMS error [N m]", "relative RMS [%]", "NRMS range [%]", "NRMS limits [%]"),
                 "its overall figures, as in its table above"),
                ("predicted [%]", f"the validated error weighed to its speeds (its rests "
                 f"table), the error predicted for it, to compare with its {measured}; `-`: "
                 f"no validation"),
                ("beyond", "the joints where it goes beyond the identification data (its "
                 "extrapolation table)"),
                ("rests more", "the joints where it rests or moves slowly more than the "
                 "identification data (its rests table)"))]


def held_out_lines(judged: Sequence[HeldOut], joints: Sequence[str]) -> list[str]:
    """The report's text on its held-out data: each recording's section (for one, as it
    has always been), then, for several, the table of each and their mean."""
    several = len(judged) > 1
    lines = [line for k, h in enumerate(judged)
             for line in _recording_lines(h, joints, k == 0, several)]
    return lines + (_summary(judged) if several else [])
