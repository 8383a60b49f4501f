"""Cross-validation of one estimator and torque model over folds of the motion's phase
(:mod:`._validation` has the module's story and the public functions built on this)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from jaxtyping import ArrayLike, Float, Int

from ._fitting import Estimator, FitProblem, describe
from ._metrics import Metrics, validation_metrics
from ._model import TorqueModel

#: Folds of :func:`~._validation.cross_validate` unless told otherwise.
DEFAULT_FOLDS = 5
#: A lag whose normalised autocorrelation reaches this is a repeat of the motion.
REPEAT_CORRELATION = 0.95
#: Excess errors below this fraction of the best cross-validated error are ties: a model
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
class CrossValidation:
    """Out-of-fold predictions of one identification setting and their errors.

    Attributes:
        metrics: :class:`~._metrics.Metrics` of all out-of-fold predictions together.
        fold_scores: the error of each fold (NRMS over the limits %, else relative RMS %).
        score: their mean, the cross-validated error; ``standard_error`` its standard
            error over the folds.
        period_s: the repeat period the folds follow (None: contiguous blocks).
        folds: the fold of each sample; ``n_parameters``: the model's parameters.
        settings: the estimator's and the model's settings (JSON-ready but for arrays).
        estimator, model: what was cross-validated.
    """

    metrics: Metrics
    fold_scores: np.ndarray
    period_s: float | None
    folds: np.ndarray
    n_parameters: int
    settings: dict
    estimator: Estimator | None = None
    model: TorqueModel | None = None

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
                "n_parameters": self.n_parameters, "settings": self.settings,
                "metrics": self.metrics.as_dict()}


def score_of(metrics: Metrics) -> float:
    """The cross-validation's measure: NRMS over the limits %, else relative RMS %."""
    if metrics.nrms_limits_percent is not None:
        return metrics.nrms_limits_percent
    return metrics.relative_rms_percent_overall


def fold_labels(times: Float[np.ndarray, " T"], q: Float[np.ndarray, "T n"],
                folds: int | Int[ArrayLike, " T"]) -> tuple[Int[np.ndarray, " T"], float | None]:
    """The fold of each sample and the period: phase folds for an int ``folds``, or
    ``folds`` itself as given labels ``0..K-1`` (one per sample)."""
    if np.ndim(folds) == 1:
        labels, period = np.asarray(folds), None
        if labels.shape != times.shape or labels.dtype.kind not in "iu" or labels.min() < 0:
            raise ValueError(f"fold labels must be integers >= 0, one per sample "
                             f"({times.shape[0]}), got shape {labels.shape}")
        folds = int(labels.max()) + 1
        if folds < 2:
            raise ValueError("fold labels must name at least 2 folds")
    else:  # folds is an int here (np.ndim 0), which mypy cannot tell
        labels, period = phase_folds(times, q, folds)  # type: ignore[arg-type]
    for k in range(folds):  # type: ignore[arg-type]
        if not np.any(labels == k):
            raise ValueError(f"fold {k + 1} of {folds} is empty: the recording is too short "
                             f"for {folds} folds")
    return labels, period


def cross_validation_of(estimator: Estimator, model: TorqueModel, Y: Float[np.ndarray, "T n d"],
                        tau: Float[np.ndarray, "T n"], limits: Float[np.ndarray, " n"] | None,
                        labels: Int[np.ndarray, " T"], period: float | None, *,
                        on_fit: Callable[[], object] | None = None) -> CrossValidation:
    """Fit ``estimator`` to all folds but one of the rows ``Y (T, n, d)``, ``tau (T, n)``
    and predict that one, for each fold of ``labels``; ``on_fit()`` after each fit."""
    folds = int(labels.max()) + 1
    predicted = np.zeros_like(tau)
    scores = []
    for k in range(folds):
        test = labels == k
        fit = estimator.fit(FitProblem(model, Y[~test], tau[~test], limits, warn=False))
        predicted[test] = Y[test] @ fit.x
        scores.append(score_of(validation_metrics(tau[test], predicted[test], limits)))
        if on_fit is not None:
            on_fit()
    settings = {**describe(estimator, model, limits), "sigma": getattr(estimator, "sigma", None)}
    return CrossValidation(
        metrics=validation_metrics(tau, predicted, limits), fold_scores=np.asarray(scores),
        period_s=period, folds=labels, n_parameters=model.dim, settings=settings,
        estimator=estimator, model=model)


def not_worse(cv: CrossValidation, best: CrossValidation) -> bool:
    """Whether ``cv``'s mean excess over ``best``, fold by fold, is at most one standard
    error of that excess, or below :data:`TIE_FRACTION` of the best error."""
    excess = cv.fold_scores - best.fold_scores
    k = len(excess)
    se = float(np.std(excess, ddof=1) / np.sqrt(k)) if k > 1 else 0.0
    return float(np.mean(excess)) <= max(se, TIE_FRACTION * best.score)
