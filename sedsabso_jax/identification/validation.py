"""Judging an identification on motion it was not fitted to: cross-validation over
non-repeating stretches of a recording, and the choice of a model by it.

A recording of an excitation trajectory usually repeats its motion (the KUKA LWR4+ runs hold
two periods of one trajectory, the Panda's one and a half): a contiguous block held out of
one period is fitted in the other, so contiguous-block cross-validation measures
repeatability. Here the folds are stretches of the trajectory's PHASE (:func:`phase_folds`):
the recording's repeat period is found from the positions' autocorrelation, and fold ``k``
holds every sample whose phase lies in ``[k/K, (k+1)/K)`` of the period, in every period.
A recording that does not repeat has phase = time, and the folds are contiguous blocks.

:func:`cross_validate` fits on ``K - 1`` folds and predicts the held-out one, ``K`` times;
the out-of-fold predictions are compared with the measured torques (NRMS over the torque
limits where they are known, else the relative RMS). :func:`select_model` cross-validates a
grid of torque models and weightings and keeps the simplest that is not worse than the
best by more than one standard error (the one-standard-error rule: Hastie, Tibshirani &
Friedman, *The Elements of Statistical Learning*, 2009, Sec. 7.10), with the standard
error taken of the PAIRED fold-by-fold differences to the best: the folds differ in
difficulty far more than the models do, and that common part cancels in the differences
(unpaired, the rule once kept a model without the torque offset whose error was higher on
every fold of the KUKA LWR4+ data). Excesses below 1 % of the best error
(:data:`TIE_FRACTION`) count as ties, so a model is not made more complex for a gain no
one could use. Nothing here looks at held-out files: they are for judging the choice,
never for making it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..dynamics.base_parameters import base_parameters
from ..measurements.transmission import coupled_motors
from .identify import check_data, fit_regressor, prepare
from .metrics import Metrics, validation_metrics

#: Folds of :func:`cross_validate` unless told otherwise.
DEFAULT_FOLDS = 5
#: A lag whose normalised autocorrelation reaches this is a repeat of the motion.
REPEAT_CORRELATION = 0.95
#: Excess errors below this fraction of the best cross-validated error are ties: a model
#: is not made more complex for less.
TIE_FRACTION = 0.01
#: The candidate torque models of :func:`select_model`, simplest first.
FRICTION_CANDIDATES = ("viscous-coulomb", "viscous-coulomb+offset",
                       "viscous-coulomb+offset+armature",
                       "viscous-coulomb+offset+quadratic+smooth")
#: The candidate weightings: (method, sigma), simplest first.
WEIGHTING_CANDIDATES = (("OLS", None), ("WLS", "residual"), ("WLS", "limits"))
#: The candidate pulls of a physically consistent fit toward the a-priori parameters
#: (:func:`choose_prior_strength`; multiples of the data term's mean curvature), none first.
PRIOR_STRENGTHS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)


def repeat_period(times, q, *, correlation: float = REPEAT_CORRELATION) -> float | None:
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


def phase_folds(times, q, folds: int = DEFAULT_FOLDS) -> tuple[np.ndarray, float | None]:
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
        metrics: :class:`~.metrics.Metrics` of all out-of-fold predictions together.
        fold_scores: the error of each fold (NRMS over the limits %, else relative RMS %).
        score: their mean, the cross-validated error; ``standard_error`` its standard
            error over the folds.
        period_s: the repeat period the folds follow (None: contiguous blocks).
        folds: the fold of each sample; ``n_parameters``: the model's parameters.
    """

    metrics: Metrics
    fold_scores: np.ndarray
    period_s: float | None
    folds: np.ndarray
    n_parameters: int
    settings: dict

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


def _score(metrics: Metrics) -> float:
    if metrics.nrms_limits_percent is not None:
        return metrics.nrms_limits_percent
    return metrics.relative_rms_percent_overall


def _folds_of(robot, times, q, qd, qdd, tau, folds):
    """Checked arrays, the fold of each sample and the period: phase folds for an int
    ``folds``, or ``folds`` itself as given labels ``0..K-1`` (one per sample)."""
    q, qd, qdd, tau = check_data(robot, q, qd, qdd, tau)
    times = np.asarray(times, dtype=float)
    if times.shape != (q.shape[0],):
        raise ValueError(f"times must have one entry per sample ({q.shape[0]}), got shape "
                         f"{times.shape}")
    if np.ndim(folds) == 1:
        labels, period = np.asarray(folds), None
        if labels.shape != times.shape or labels.dtype.kind not in "iu" or labels.min() < 0:
            raise ValueError(f"fold labels must be integers >= 0, one per sample "
                             f"({times.shape[0]}), got shape {labels.shape}")
        folds = int(labels.max()) + 1
        if folds < 2:
            raise ValueError("fold labels must name at least 2 folds")
    else:
        labels, period = phase_folds(times, q, folds)
    for k in range(folds):
        if not np.any(labels == k):
            raise ValueError(f"fold {k + 1} of {folds} is empty: the recording is too short "
                             f"for {folds} folds")
    return (q, qd, qdd, tau), labels, period


def _cross_validate(setup, Y, tau, labels, period, sigma) -> CrossValidation:
    folds = int(labels.max()) + 1
    predicted = np.zeros_like(tau)
    scores = []
    for k in range(folds):
        test = labels == k
        fit = fit_regressor(setup, Y[~test], tau[~test], warn=False)
        predicted[test] = Y[test] @ fit.x
        scores.append(_score(validation_metrics(tau[test], predicted[test], setup.limits)))
    return CrossValidation(
        metrics=validation_metrics(tau, predicted, setup.limits),
        fold_scores=np.asarray(scores), period_s=period, folds=labels,
        n_parameters=setup.model.dim, settings={**setup.settings(), "sigma": sigma})


def cross_validate(robot, times, q, qd, qdd, tau, *, folds=DEFAULT_FOLDS,
                   **settings) -> CrossValidation:
    """Cross-validate :func:`~.identify.identify` with ``settings`` (its keyword arguments)
    over ``folds`` phase folds of the recording (module docstring), or over given fold
    labels (an integer array, one per sample)."""
    (q, qd, qdd, tau), labels, period = _folds_of(robot, times, q, qd, qdd, tau, folds)
    setup = prepare(robot, warn=False, **settings)
    return _cross_validate(setup, setup.model.regressor(q, qd, qdd), tau, labels, period,
                           settings.get("sigma"))


@dataclasses.dataclass(frozen=True, eq=False)
class Selection:
    """What :func:`select_model` returns: every candidate's cross-validation (in the order
    tried) and the chosen one's settings (``identify`` keyword arguments)."""

    candidates: tuple[tuple[dict, CrossValidation], ...]
    chosen: dict
    best: dict

    def table(self) -> list[list[str]]:
        """Rows ``[method, sigma, friction, parameters, CV error +- SE, chosen]``."""
        rows = []
        for settings, cv in self.candidates:
            mark = "chosen" if settings is self.chosen else (
                "lowest" if settings is self.best else "")
            rows.append([settings["method"], str(settings.get("sigma") or "equal"),
                         settings["friction"], str(cv.n_parameters),
                         f"{cv.score:.4f} +- {cv.standard_error:.4f}", mark])
        return rows

    def as_dict(self) -> dict:
        return {"rule": "simplest candidate whose fold-by-fold excess over the lowest "
                        "cross-validated error is at most one standard error (or 1 % of "
                        "the lowest)",
                "chosen": self.chosen, "lowest": self.best,
                "candidates": [{"settings": s, **cv.as_dict()} for s, cv in self.candidates]}


def select_model(robot, times, q, qd, qdd, tau, *, frictions=None, weightings=None,
                 folds=DEFAULT_FOLDS, **settings) -> Selection:
    """Choose the friction terms and the weighting by cross-validation (module
    docstring). ``frictions`` (default :data:`FRICTION_CANDIDATES`) and ``weightings``
    (``(method, sigma)`` pairs, default :data:`WEIGHTING_CANDIDATES`; those needing torque
    limits are skipped without ``limits``) are the grid; ``settings`` go to every fit
    (``limits``, ``transmission``, ``base``, ``physical``, ...). A transmission with a
    coupled motor adds the ``coupling`` term to every candidate."""
    frictions = tuple(FRICTION_CANDIDATES if frictions is None else frictions)
    weightings = tuple(WEIGHTING_CANDIDATES if weightings is None else weightings)
    if settings.get("limits") is None:
        weightings = tuple(w for w in weightings if w[1] != "limits")
    if not frictions or not weightings:
        raise ValueError("select_model needs at least one friction model and one weighting")
    K = getattr(settings.get("transmission"), "matrix", settings.get("transmission"))
    coupled = K is not None and bool(coupled_motors(K))
    (q, qd, qdd, tau), labels, period = _folds_of(robot, times, q, qd, qdd, tau, folds)
    if settings.get("base") is None:  # computed once for every candidate
        settings = {**settings, "base": base_parameters(robot)}
    tried = []
    for friction in frictions:
        if coupled and "coupling" not in friction:
            friction = friction + "+coupling"
        Y = None  # one regressor per torque model, shared by the weightings
        for method, sigma in weightings:
            public = {"method": method, "sigma": sigma, "friction": friction}
            setup = prepare(robot, warn=False, **{**settings, **public})
            Y = setup.model.regressor(q, qd, qdd) if Y is None else Y
            tried.append((public, _cross_validate(setup, Y, tau, labels, period, sigma)))
    best_settings, best = min(tried, key=lambda c: c[1].score)
    # simplest: fewest parameters, then the earlier (simpler) weighting
    order = sorted(range(len(tried)), key=lambda i: (tried[i][1].n_parameters, i))
    chosen = next(tried[i][0] for i in order if _not_worse(tried[i][1], best))
    return Selection(candidates=tuple(tried), chosen=chosen, best=best_settings)


@dataclasses.dataclass(frozen=True, eq=False)
class PriorSelection:
    """What :func:`choose_prior_strength` returns: each strength's cross-validation (in
    the order tried) and the chosen and the lowest strength."""

    candidates: tuple[tuple[float, CrossValidation], ...]
    chosen: float
    best: float

    def table(self) -> list[list[str]]:
        """Rows ``[strength, CV error +- SE, chosen]``."""
        return [[f"{s:g}", f"{cv.score:.4f} +- {cv.standard_error:.4f}",
                 "chosen" if s == self.chosen else ("lowest" if s == self.best else "")]
                for s, cv in self.candidates]

    def as_dict(self) -> dict:
        return {"rule": "strongest pull to the prior whose fold-by-fold excess over the "
                        "lowest cross-validated error is at most one standard error (or 1 % "
                        "of the lowest)",
                "chosen": self.chosen, "lowest": self.best,
                "candidates": [{"prior_strength": s, **cv.as_dict()}
                               for s, cv in self.candidates]}


def choose_prior_strength(robot, times, q, qd, qdd, tau, *, strengths=PRIOR_STRENGTHS,
                          folds=DEFAULT_FOLDS, **settings) -> PriorSelection:
    """Choose how strongly a physically consistent fit is pulled toward the a-priori
    parameters (``prior_strength`` of :func:`~.identify.identify`) by cross-validation over
    the same phase folds as :func:`select_model`: every strength in ``strengths`` is
    cross-validated with ``settings`` (``physical=True`` is implied; ``method``,
    ``friction``, ``sigma``, ``prior``, ``limits``, ...), and the STRONGEST pull whose
    fold-by-fold excess over the lowest error is within one standard error is kept (the
    one-standard-error rule: the most regularised model the data cannot tell from the
    best). The held-out folds are fitted by nothing, chosen by nothing else."""
    strengths = tuple(float(v) for v in strengths)
    if not strengths or any(not (np.isfinite(v) and v >= 0) for v in strengths):
        raise ValueError(f"strengths must be numbers >= 0, at least one, got {strengths}")
    if settings.get("method", "OLS") not in ("OLS", "WLS"):
        raise ValueError("the pull to the prior is a physically consistent least-squares "
                         "fit: method 'OLS' or 'WLS'")
    (q, qd, qdd, tau), labels, period = _folds_of(robot, times, q, qd, qdd, tau, folds)
    settings = {**settings, "physical": True}
    if settings.get("base") is None:
        settings["base"] = base_parameters(robot)
    tried, Y = [], None
    for v in strengths:
        setup = prepare(robot, warn=False, **{**settings, "prior_strength": v})
        Y = setup.model.regressor(q, qd, qdd) if Y is None else Y
        tried.append((v, _cross_validate(setup, Y, tau, labels, period,
                                         settings.get("sigma"))))
    best_v, best = min(tried, key=lambda c: c[1].score)
    chosen = max(v for v, cv in tried if _not_worse(cv, best))
    return PriorSelection(candidates=tuple(tried), chosen=chosen, best=best_v)


def _not_worse(cv: CrossValidation, best: CrossValidation) -> bool:
    """Whether ``cv``'s mean excess over ``best``, fold by fold, is at most one standard
    error of that excess, or below :data:`TIE_FRACTION` of the best error."""
    excess = cv.fold_scores - best.fold_scores
    k = len(excess)
    se = float(np.std(excess, ddof=1) / np.sqrt(k)) if k > 1 else 0.0
    return float(np.mean(excess)) <= max(se, TIE_FRACTION * best.score)
