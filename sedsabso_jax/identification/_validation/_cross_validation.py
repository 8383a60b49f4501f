"""The validation of one estimator and torque model over a validation's splits
(:func:`cross_validation_of`): each split's training samples fitted as any fit is
(:func:`~.._fit._fit.fit`: on their normal equations where the estimator reads only
them, the model's stages as its terms ask), its test samples predicted; and whether one
validation is worse than another (:func:`not_worse`). :mod:`._splits` makes the
splits, :mod:`._selection` has the public functions built on this."""

from __future__ import annotations

import dataclasses
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from threadpoolctl import threadpool_limits

from .._default._policy import DEFAULT
from .._estimators._estimator import Estimator, describe
from .._fit._fit import fit as fit_model
from .._fit._samples import Samples
from .._metrics import Metrics, validation_metrics
from .._model._torque_model import TorqueModel
from ._splits import Splits

#: Excess errors below this fraction of the best validated error are ties
#: (:attr:`~.._default._policy.Default.tie_fraction`).
TIE_FRACTION = DEFAULT.tie_fraction
#: The one-standard-error rule's test (:meth:`~.._default._policy.Default.not_worse`).
not_worse = DEFAULT.not_worse
#: The environment variable that sets how many threads fit a validation's splits at once
#: (default: one per core the process may use; 1: in turn, on the calling thread).
THREADS_VARIABLE = "SEDSABSO_JAX_THREADS"
_THREADS = "sedsabso-jax-split"
_POOLS: dict[int, ThreadPoolExecutor] = {}


def split_threads() -> int:
    """How many threads fit a validation's splits at once (:data:`THREADS_VARIABLE`)."""
    given = os.environ.get(THREADS_VARIABLE)
    if given is None:
        return (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                else os.cpu_count() or 1)
    if not given.strip().isdigit() or int(given) < 1:
        raise ValueError(f"{THREADS_VARIABLE} must be a whole number of threads >= 1, got "
                         f"{given!r}")
    return int(given)


def _map(one: Callable, *args):
    """``map(one, *args)``, on :func:`split_threads` threads at once; in turn where that
    is one, or where called from a split's thread (a validation inside a split's fit: the
    threads would otherwise wait on themselves)."""
    threads = split_threads()
    if threads == 1 or threading.current_thread().name.startswith(_THREADS):
        return map(one, *args)
    if threads not in _POOLS:
        _POOLS[threads] = ThreadPoolExecutor(threads, thread_name_prefix=_THREADS)
    return _POOLS[threads].map(one, *args)


@dataclasses.dataclass(frozen=True, eq=False)
class CrossValidation:
    """Predictions of one identification setting on samples it was not fitted to, split
    by a :class:`~._splits.Validation`, and their errors.

    Attributes:
        metrics: :class:`~.._metrics.Metrics` of all predicted samples together (each
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
        residuals, tested: the predicted samples' errors (measured - predicted, ``(N,
            n)``, each split's stacked) and their indices into the validated samples
            (``(N,)``; a sample predicted by several splits appears once per split).
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
    residuals: np.ndarray | None = dataclasses.field(default=None, repr=False)
    tested: np.ndarray | None = dataclasses.field(default=None, repr=False)

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


def cross_validation_of(estimator: Estimator, model: TorqueModel, samples: Samples,
                        splits: Splits, limits: np.ndarray | None, validation: dict, *,
                        on_fit: Callable[[], object] | None = None,
                        made: Callable[[np.ndarray], Samples] | None = None
                        ) -> CrossValidation:
    """Fit ``estimator`` and ``model`` to each split's training samples of ``samples``
    (the recordings, stacked) and predict its test samples; ``validation`` the settings
    of the validation that made the splits; ``on_fit()`` after each fit (in the splits'
    order, on the calling thread); ``made(train)``: the samples of a split instead, made
    knowing only its training mask (a delay searched on them). The splits are fitted on
    :func:`split_threads` threads at once (``made`` is called from them); the numbers do
    not depend on how many."""
    every = np.arange(samples.q.shape[0])

    def one(train: np.ndarray, test: np.ndarray) -> tuple:
        these = samples if made is None else made(train)
        fitted = fit_model(estimator, model, these.split(train), limits, warn=False)
        measured = these.tau[test]
        predicted = these.split(test).predict(fitted.model, fitted.fit.x)
        return (measured, predicted, every[test],
                score_of(validation_metrics(measured, predicted, limits)))

    # many small factorisations: one BLAS thread each (docs/explanation/
    # identification-defaults.md); the user's setting is restored on leaving. The splits
    # are fitted on the CPU's cores at once (each split's numbers its own, whichever
    # thread fits it), taken in order
    with threadpool_limits(limits=1, user_api="blas"):
        if not model.waiting:
            samples.rows(model)  # the splits' rows are taken from the whole's
        done = []
        for result in _map(one, splits.train, splits.test):
            done.append(result)
            if on_fit is not None:
                on_fit()
    measured, predicted, tested, scores = (list(x) for x in zip(*done))
    settings = {**describe(estimator, model, limits), "sigma": estimator.sigma}
    measured_all, predicted_all = np.concatenate(measured), np.concatenate(predicted)
    return CrossValidation(
        metrics=validation_metrics(measured_all, predicted_all, limits),
        fold_scores=np.asarray(scores), period_s=splits.period_s, folds=splits.labels,
        n_parameters=model.dim, settings=settings, estimator=estimator, model=model,
        validation=validation, split_names=splits.names, split_parts=splits.parts,
        residuals=measured_all - predicted_all, tested=np.concatenate(tested))

