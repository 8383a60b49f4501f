"""The folds of a motion's phase, the splits a validation makes (:class:`Splits`), and the
validation of one estimator and torque model over them (:func:`cross_validation_of`):
each split's training samples fitted (on their normal equations for the least-squares
estimators, :mod:`._compressed`), its test samples predicted. :mod:`._splits` makes the
splits, :mod:`._validation` has the public functions built on this."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from jaxtyping import ArrayLike, Float, Int
from threadpoolctl import threadpool_limits

from ._compressed import subset_problems
from ._fitting import Estimator, FitProblem, describe
from ._metrics import Metrics, validation_metrics
from ._model import TorqueModel
from ._shapes import Samples
from ._shapes import fit as fit_model

#: Folds of :func:`~._validation.cross_validate` unless told otherwise.
DEFAULT_FOLDS = 5
#: A lag whose normalised autocorrelation reaches this is a repeat of the motion.
REPEAT_CORRELATION = 0.95
#: Excess errors below this fraction of the best validated error are ties: a model
#: is not made more complex for less.
TIE_FRACTION = 0.01


def repeat_period(times: Float[ArrayLike, " T"], q: Float[ArrayLike, "T n"], *,
                  correlation: float = REPEAT_CORRELATION) -> float | None:
    """The period [s] after which the positions ``q (T, n)`` repeat (the lag of highest
    normalised autocorrelation between 10 % and 90 % of the recording, if it reaches
    ``correlation``), or None when the motion does not repeat."""
    times, q = np.asarray(times, dtype=float), np.asarray(q, dtype=float)
    step = max(1, len(times) // 1500)  # the motion is slow: a coarse grid finds the period
    t, x = times[::step], q[::step]
    x = (x - x.mean(0)) / np.where(x.std(0) > 0, x.std(0), 1.0)
    T = len(t)
    best, lag_best = -np.inf, None
    for lag in range(max(1, T // 10), max(2, 9 * T // 10)):
        a, b = x[:-lag], x[lag:]
        r = np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b))
        if r > best:
            best, lag_best = r, lag
    if lag_best is None or best < correlation:
        return None
    return float(t[lag_best] - t[0])


def phase_folds(times: Float[ArrayLike, " T"], q: Float[ArrayLike, "T n"],
                folds: int = DEFAULT_FOLDS) -> tuple[Int[np.ndarray, " T"], float | None]:
    """``(fold of each sample, period)``: folds of the trajectory's phase (module
    docstring); contiguous blocks when the motion does not repeat (period None)."""
    times = np.asarray(times, dtype=float)
    if not isinstance(folds, (int, np.integer)) or isinstance(folds, bool) or folds < 2:
        raise ValueError(f"folds must be an integer >= 2, got {folds!r}")
    period = repeat_period(times, q)
    span = period if period is not None else (times[-1] - times[0]) * (1 + 1e-12)
    phase = np.mod((times - times[0]) / span, 1.0)
    return np.minimum((phase * folds).astype(int), folds - 1), period


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


@dataclasses.dataclass(frozen=True, eq=False)
class CrossValidation:
    """Predictions of one identification setting on samples it was not fitted to, split
    by a :class:`~._splits.Validation`, and their errors.

    Attributes:
        metrics: :class:`~._metrics.Metrics` of all predicted samples together (each
            split's, stacked: for folds, the out-of-fold predictions).
        fold_scores: the error of each split (NRMS over the limits %, else relative RMS %).
        score: their mean, the validated error; ``standard_error`` its standard error
            over the splits.
        period_s: the repeat period phase folds follow (None: contiguous folds, or
            another validation).
        folds: the fold of each sample where the splits are folds (else None);
            ``n_parameters``: the model's parameters.
        settings: the estimator's and the model's settings (JSON-ready but for arrays).
        estimator, model: what was validated.
        validation: the validation's settings (``kind`` and its options);
            ``split_names`` one per split.
    """

    metrics: Metrics
    fold_scores: np.ndarray
    period_s: float | None
    folds: np.ndarray | None
    n_parameters: int
    settings: dict
    estimator: Estimator | None = None
    model: TorqueModel | None = None
    validation: dict = dataclasses.field(default_factory=lambda: {"kind": "phase folds"})
    split_names: tuple[str, ...] = ()
    split_parts: tuple[str, ...] = ()

    @property
    def part_scores(self) -> dict[str, float]:
        """The mean error of each kind of split (``{"phase folds": ..., "speed splits":
        ...}`` for pooled validations; one entry otherwise)."""
        parts = self.split_parts or (self.validation["kind"],) * len(self.fold_scores)
        return {k: float(np.mean([v for p, v in zip(parts, self.fold_scores) if p == k]))
                for k in dict.fromkeys(parts)}

    @property
    def score(self) -> float:
        return float(np.mean(self.fold_scores))

    @property
    def standard_error(self) -> float:
        k = len(self.fold_scores)
        return float(np.std(self.fold_scores, ddof=1) / np.sqrt(k)) if k > 1 else 0.0

    @property
    def measure(self) -> str:
        return ("nrms_limits_percent" if self.metrics.nrms_limits_percent is not None
                else "relative_rms_percent")

    def as_dict(self) -> dict:
        return {"measure": self.measure, "score": self.score,
                "standard_error": self.standard_error, "fold_scores": self.fold_scores,
                "folds": len(self.fold_scores), "period_s": self.period_s,
                "validation": self.validation, "splits": list(self.split_names),
                "part_scores": self.part_scores,
                "n_parameters": self.n_parameters, "settings": self.settings,
                "metrics": self.metrics.as_dict()}


def score_of(metrics: Metrics) -> float:
    """The validation's measure: NRMS over the limits %, else relative RMS %."""
    if metrics.nrms_limits_percent is not None:
        return metrics.nrms_limits_percent
    return metrics.relative_rms_percent_overall


class SplitRows:
    """The rows ``Y (T, n, d)``, ``tau (T, n)`` of one torque model and the fit problem
    of each split's training samples: compressed to their normal equations
    (:mod:`._compressed`, formed once for every least-squares estimator that validates
    this model) or, for the others, the rows themselves."""

    def __init__(self, model: TorqueModel, Y: Float[np.ndarray, "T n d"],
                 tau: Float[np.ndarray, "T n"], limits: Float[np.ndarray, " n"] | None,
                 splits: Splits, samples: Samples | None = None):
        self.model, self.Y, self.tau, self.limits, self.splits = model, Y, tau, limits, splits
        self.samples = samples  # what a model that is not linear is fitted anew from
        self._compressed: list[FitProblem] | None = None

    def problems(self, estimator: Estimator) -> list[FitProblem]:
        if estimator.normal_equations:
            if self._compressed is None:
                self._compressed = subset_problems(self.model, self.Y, self.tau, self.limits,
                                                   list(self.splits.train))
            return self._compressed
        return [FitProblem(self.model, self.Y[k], self.tau[k], self.limits, warn=False)
                for k in self.splits.train]


def cross_validation_of(estimator: Estimator, rows: SplitRows, validation: dict, *,
                        on_fit: Callable[[], object] | None = None) -> CrossValidation:
    """Fit ``estimator`` to each split's training samples of ``rows`` and predict its
    test samples; ``validation`` the settings of the validation that made the splits;
    ``on_fit()`` after each fit."""
    splits, Y, tau, limits = rows.splits, rows.Y, rows.tau, rows.limits
    measured, predicted, scores = [], [], []
    # many small factorisations: one BLAS thread each (OpenBLAS's threads made the KUKA
    # LWR4+'s default identify 1.3x slower on 2 idle cores, 14.1-15.1 s against
    # 10.5-10.9 s); the user's setting is restored on leaving
    with threadpool_limits(limits=1, user_api="blas"):
        problems = None if rows.model.nonlinear else rows.problems(estimator)
        for k, test in enumerate(splits.test):
            measured.append(tau[test])
            if problems is not None:
                predicted.append(Y[test] @ estimator.fit(problems[k]).x)
            else:
                predicted.append(_refit_and_predict(estimator, rows, k, test))
            scores.append(score_of(validation_metrics(measured[-1], predicted[-1], limits)))
            if on_fit is not None:
                on_fit()
    settings = {**describe(estimator, rows.model, limits), "sigma": estimator.sigma}
    return CrossValidation(
        metrics=validation_metrics(np.concatenate(measured), np.concatenate(predicted), limits),
        fold_scores=np.asarray(scores), period_s=splits.period_s, folds=splits.labels,
        n_parameters=rows.model.dim, settings=settings, estimator=estimator, model=rows.model,
        validation=validation, split_names=splits.names, split_parts=splits.parts)


def _refit_and_predict(estimator: Estimator, rows: SplitRows, k: int,
                       test: np.ndarray) -> np.ndarray:
    """Split ``k``'s test torques as predicted by the whole fit of a model that is not
    linear (:attr:`~._model.TorqueModel.nonlinear`; :func:`~._shapes.fit`: its scales
    searched, its load settled) to the split's training samples."""
    if rows.samples is None:
        raise ValueError("a torque model that is not linear is validated from its samples")
    fitted = fit_model(estimator, rows.model, rows.samples.subset(rows.splits.train[k]),
                       rows.limits, warn=False)
    return rows.samples.subset(test).predict(fitted.model, fitted.fit.x)


def not_worse(cv: CrossValidation, best: CrossValidation) -> bool:
    """Whether ``cv``'s mean excess over ``best``, fold by fold, is at most one standard
    error of that excess, or below :data:`TIE_FRACTION` of the best error."""
    excess = cv.fold_scores - best.fold_scores
    k = len(excess)
    se = float(np.std(excess, ddof=1) / np.sqrt(k)) if k > 1 else 0.0
    return float(np.mean(excess)) <= max(se, TIE_FRACTION * best.score)
