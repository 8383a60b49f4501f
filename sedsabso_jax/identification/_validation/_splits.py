"""Validations: how an identification is judged on samples it was not fitted to.

A :class:`Validation` cuts the samples of one or several recordings into splits, each a
set of samples to fit and a set to predict (:class:`Splits`);
:func:`~sedsabso_jax.cross_validate` fits and predicts each split, and the mean error over
the splits is the validation's score.

- :class:`PhaseFolds`: folds of the motion's phase (:func:`~._phase.phase_folds`). Every
  fold is a stretch of the same trajectory, inside the region of joint states the others
  cover: it measures how well a model interpolates, and predicts motions like the one
  fitted.
- :class:`SpeedSplits`: for each joint, fit the samples where it moves slower than
  ``fit_below`` of its peak speed and predict those where it moves faster than
  ``predict_above``: the model must extrapolate in speed, as it must on a new motion that
  is faster than the one fitted (friction at speeds never fitted).
- :class:`RecordingFolds`: leave one recording out, for several recordings.
- :class:`GivenFolds`: fold labels of the user's, one per sample.
- :class:`Pooled`: the splits of several of these together. ``sedsabso-jax identify``
  chooses by ``Pooled((PhaseFolds(), SpeedSplits()))`` (leave one recording out instead
  of the phase folds for several recordings; why:
  docs/explanation/identification-defaults.md).
"""

from __future__ import annotations

import abc
import dataclasses
from collections.abc import Sequence
from typing import ClassVar

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Int

from ...measurements._container import Measurements
from .._default._policy import DEFAULT
from .._options import as_float
from ._phase import DEFAULT_FOLDS, phase_folds

#: :class:`SpeedSplits`' default thresholds, as fractions of each joint's peak speed, and
#: the quantile of ``|qd|`` called its peak (the default's,
#: :class:`~.._default._policy.Default`).
FIT_BELOW, PREDICT_ABOVE = DEFAULT.fit_below, DEFAULT.predict_above
PEAK_QUANTILE = DEFAULT.peak_quantile


def peak_speed(qd: np.ndarray) -> np.ndarray:
    """Each joint's peak speed: the :data:`PEAK_QUANTILE` quantile of ``|qd|``."""
    return np.quantile(np.abs(qd), PEAK_QUANTILE, axis=0)


@dataclasses.dataclass(frozen=True, eq=False)
class Splits:
    """Which samples each split fits (``train``) and predicts (``test``): boolean masks
    over the samples of the recordings, concatenated; ``names`` one per split; ``labels``
    the fold of each sample where the splits are a partition (else None); ``period_s``
    the repeat period phase folds follow (None: contiguous, or not phase folds);
    ``parts`` the kind of validation of each split."""

    train: tuple[np.ndarray, ...]
    test: tuple[np.ndarray, ...]
    names: tuple[str, ...]
    labels: np.ndarray | None = None
    period_s: float | None = None
    #: the kind of validation each split came from (one kind but for pooled splits)
    parts: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.train)


class Validation(eqx.Module):
    """A way to cut recordings into fit-and-predict splits (module docstring): an
    immutable object carrying its options, converted and checked when built (an
    ``equinox.Module``, abstract or final, as the estimators are)."""

    #: What the reports call it.
    kind: eqx.AbstractClassVar[str]
    #: The fewest recordings it can split.
    min_recordings: ClassVar[int] = 1

    def of(self, recordings: Sequence[Measurements]) -> Validation:
        """The validation to split ``recordings`` by: itself (a recipe such as
        :class:`~sedsabso_jax.identification.DefaultValidation` makes one for the recordings)."""
        return self

    @abc.abstractmethod
    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        """The splits of ``recordings`` (masks over their samples, concatenated)."""

    @abc.abstractmethod
    def describe(self) -> str:
        """One sentence for the report: what is fitted and what predicted."""

    def settings(self) -> dict:
        """The options, JSON-ready, with ``kind``."""
        own = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)  # type: ignore[arg-type]
               if f.name != "labels"}
        return {"kind": self.kind, **own}


def _partition(labels: np.ndarray, names: Sequence[str], period: float | None = None
               ) -> Splits:
    k = int(labels.max()) + 1
    for i in range(k):
        if not np.any(labels == i):
            raise ValueError(f"fold {i + 1} of {k} is empty: the recording is too short for "
                             f"{k} folds")
    return Splits(tuple(labels != i for i in range(k)), tuple(labels == i for i in range(k)),
                  tuple(names), labels, period)


class PhaseFolds(Validation):
    """``folds`` folds of each recording's phase (:func:`~._phase.phase_folds`); fold
    ``k`` of every recording together is split ``k``."""

    folds: int = DEFAULT_FOLDS
    kind: ClassVar[str] = "phase folds"

    def __check_init__(self):
        if not isinstance(self.folds, (int, np.integer)) or isinstance(self.folds, bool) \
                or self.folds < 2:
            raise ValueError(f"folds must be an integer >= 2, got {self.folds!r}")

    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        found = [phase_folds(r.times, r.q, int(self.folds)) for r in recordings]
        labels = np.concatenate([f[0] for f in found])
        periods = {f[1] for f in found}
        period = periods.pop() if len(periods) == 1 else None
        return _partition(labels, [f"phase {k + 1}/{self.folds}" for k in range(self.folds)],
                          period)

    def describe(self) -> str:
        return (f"{self.folds} folds of the motion's phase, each predicted by a fit to the "
                f"others (a model interpolating inside the fitted motion)")


def _as_labels(value: object) -> object:
    """Fold labels as an array (anything else as given, for the check to name)."""
    try:
        return np.asarray(value)
    except (TypeError, ValueError):
        return value


class GivenFolds(Validation):
    """Fold labels ``0..K-1`` given by the user, one per sample (of the recordings
    concatenated); each fold is predicted by a fit to the others."""

    labels: Int[ArrayLike, " T"] = eqx.field(converter=_as_labels)
    kind: ClassVar[str] = "given folds"

    def __check_init__(self):
        labels = self.labels
        if not isinstance(labels, np.ndarray) or labels.ndim != 1 \
                or labels.dtype.kind not in "iu" or labels.size == 0 or labels.min() < 0:
            raise ValueError(f"fold labels must be integers >= 0, one per sample, got "
                             f"shape {np.shape(labels)}")

    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        labels = np.asarray(self.labels)
        T = sum(r.n_samples for r in recordings)
        if labels.shape != (T,):
            raise ValueError(f"fold labels must be integers >= 0, one per sample ({T}), got "
                             f"shape {labels.shape}")
        if labels.max() < 1:
            raise ValueError("fold labels must name at least 2 folds")
        return _partition(labels, [f"fold {k + 1}" for k in range(int(labels.max()) + 1)])

    def describe(self) -> str:
        return f"{int(np.max(self.labels)) + 1} given folds, each predicted by a fit to the others"


class SpeedSplits(Validation):
    """One split per joint: fit the samples where that joint moves slower than
    ``fit_below`` of its peak speed, predict those where it moves faster than
    ``predict_above`` (peak: the 99.5 % quantile of ``|qd|`` over all recordings). The
    model is asked to extrapolate each joint's speed by up to ``1 / fit_below``."""

    fit_below: float = eqx.field(default=FIT_BELOW, converter=as_float)
    predict_above: float = eqx.field(default=PREDICT_ABOVE, converter=as_float)
    kind: ClassVar[str] = "speed splits"

    def __check_init__(self):
        lo, hi = self.fit_below, self.predict_above
        if not (isinstance(lo, float) and isinstance(hi, float) and 0 < lo <= hi < 1):
            raise ValueError(f"SpeedSplits needs 0 < fit_below <= predict_above < 1 (fractions "
                             f"of each joint's peak speed), got {lo!r} and {hi!r}")

    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        qd = np.concatenate([r.qd for r in recordings])
        peak = peak_speed(qd)
        moving = np.flatnonzero(peak > 0)
        if moving.size == 0:
            raise ValueError("speed splits: no joint moves in the data (every joint's "
                             "speed is 0): they need a motion")
        speed = np.abs(qd[:, moving]) / peak[moving]
        train = tuple(speed[:, i] < self.fit_below for i in range(moving.size))
        test = tuple(speed[:, i] > self.predict_above for i in range(moving.size))
        for i, (a, b) in enumerate(zip(train, test)):
            if not a.any() or not b.any():
                raise ValueError(
                    f"speed splits: joint {moving[i] + 1} never moves "
                    f"{'slower' if not a.any() else 'faster'} than "
                    f"{self.fit_below if not a.any() else self.predict_above:g} of its peak "
                    f"speed: nothing to {'fit' if not a.any() else 'predict'}; choose "
                    f"another validation")
        return Splits(train, test, tuple(f"joint {j + 1} faster" for j in moving))

    def describe(self) -> str:
        return (f"for each joint, a fit to the samples where it moves below "
                f"{self.fit_below:g} of its peak speed predicts those above "
                f"{self.predict_above:g} (a model extrapolating in speed, as on a faster "
                f"motion)")


class RecordingFolds(Validation):
    """Leave one recording out: each recording is predicted by a fit to the others."""

    kind: ClassVar[str] = "recording folds"
    min_recordings: ClassVar[int] = 2

    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        if len(recordings) < self.min_recordings:
            raise ValueError("RecordingFolds (leave one recording out) needs at least 2 "
                             "recordings")
        labels = np.concatenate([np.full(r.n_samples, k) for k, r in enumerate(recordings)])
        return _partition(labels, [f"recording {k + 1} ({r.source})"
                                   for k, r in enumerate(recordings)])

    def describe(self) -> str:
        return "each recording predicted by a fit to the others"


def _as_tuple(value: object) -> object:
    """A sequence as a tuple (anything else as given, for the check to name)."""
    return tuple(value) if isinstance(value, (list, tuple)) else value


class Pooled(Validation):
    """The splits of several validations together: a model is scored on all of them (the
    mean over every split), as new motions are partly like the fitted one (phase folds)
    and partly faster (speed splits). The default of ``sedsabso-jax identify``:
    ``Pooled((PhaseFolds(), SpeedSplits()))``, with :class:`RecordingFolds` for the phase
    folds where there are several recordings."""

    validations: tuple[Validation, ...] = eqx.field(default=(), converter=_as_tuple)
    kind: ClassVar[str] = "pooled"

    def __check_init__(self):
        found = self.validations
        if not isinstance(found, tuple) or len(found) < 2 or not all(
                isinstance(v, Validation) for v in found):
            raise ValueError(f"Pooled needs at least two validations (PhaseFolds(), "
                             f"SpeedSplits(), ...), got {self.validations!r}")

    def splits(self, recordings: Sequence[Measurements]) -> Splits:
        parts = [v.splits(recordings) for v in self.validations]
        periods = {p.period_s for p in parts if p.period_s is not None}
        return Splits(tuple(m for p in parts for m in p.train),
                      tuple(m for p in parts for m in p.test),
                      tuple(n for p in parts for n in p.names),
                      period_s=periods.pop() if len(periods) == 1 else None,
                      parts=tuple(v.kind for v, p in zip(self.validations, parts)
                                  for _ in range(len(p))))

    @property
    def min_recordings(self) -> int:  # type: ignore[override]
        return max(v.min_recordings for v in self.validations)

    def describe(self) -> str:
        return "; and ".join(v.describe() for v in self.validations)

    def settings(self) -> dict:
        return {"kind": self.kind, "validations": [v.settings() for v in self.validations]}
