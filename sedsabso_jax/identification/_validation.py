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
grid of torque models and estimators and keeps the simplest that is not worse than the
best by more than one standard error (the one-standard-error rule: Hastie, Tibshirani &
Friedman, *The Elements of Statistical Learning*, 2009, Sec. 7.10), with the standard
error taken of the PAIRED fold-by-fold differences to the best: the folds differ in
difficulty far more than the models do, and that common part cancels in the differences
(unpaired, the rule once kept a model without the torque offset whose error was higher on
every fold of the KUKA LWR4+ data). Excesses below 1 % of the best error
(:data:`TIE_FRACTION`) count as ties, so a model is not made more complex for a gain no
one could use. Nothing here looks at held-out files: they are for judging the choice,
never for making it.

Each takes the data as a :class:`~sedsabso_jax.Measurements` or ``(times, q, qd, qdd,
tau)``, estimator objects (:mod:`._estimators`) and torque models (a
:class:`~._model.TorqueModel` or friction terms). 0.2's forms ``(robot, times, q, qd, qdd,
tau, **identify_settings)`` keep working through 0.3.x with a ``DeprecationWarning``.
"""


from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Int

from .. import _deprecation
from ..dynamics._base_parameters import BaseParameters, base_parameters
from ..dynamics._robot import Robot
from ..measurements._transmission import TransmissionLike, coupled_motors
from ._estimators import OLS, WLS, PhysicallyConsistent
from ._fitting import Estimator, Limits, ProgressCallback, Sigma, per_joint
from ._folds import DEFAULT_FOLDS as DEFAULT_FOLDS
from ._folds import REPEAT_CORRELATION as REPEAT_CORRELATION
from ._folds import TIE_FRACTION as TIE_FRACTION
from ._folds import CrossValidation as CrossValidation
from ._folds import cross_validation_of, fold_labels, not_worse
from ._folds import phase_folds as phase_folds
from ._folds import repeat_period as repeat_period
from ._identify import Data, data_arrays, torque_model
from ._legacy import estimator_from, from_keywords
from ._model import SMOOTH_VELOCITY, TorqueModel

#: The candidate torque models of :func:`select_model`, simplest first.
FRICTION_CANDIDATES = ("viscous-coulomb", "viscous-coulomb+offset",
                       "viscous-coulomb+offset+armature",
                       "viscous-coulomb+offset+quadratic+smooth")
#: The candidate estimators of :func:`select_model` (their weightings), simplest first.
ESTIMATOR_CANDIDATES = (OLS(), WLS("residual"), WLS("limits"))
#: 0.2's form of :data:`ESTIMATOR_CANDIDATES`: (method, sigma) pairs.
WEIGHTING_CANDIDATES = tuple((e.name, e.sigma) for e in ESTIMATOR_CANDIDATES)
#: The candidate pulls of a physically consistent fit toward the a-priori parameters
#: (:func:`choose_prior_strength`; multiples of the data term's mean curvature), none first.
PRIOR_STRENGTHS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)


def _old_form(what: str, data, positional: tuple, count: int):
    """0.2's ``what(robot, times, q, qd, qdd, tau, **settings)``: the data tuple, with a
    warning."""
    if positional:
        if len(positional) != count:
            raise TypeError(f"{what}() takes (robot, data, ...), or 0.2's (robot, times, q, "
                            f"qd, qdd, tau, ...)")
        data = (data, *positional)
    _deprecation.warn(f"{what}(robot, times, q, qd, qdd, tau, method=..., friction=..., ...)",
                      f"{what}(robot, data, ...) with estimator objects and torque models")
    return data


class _Fits:
    """Counts fits for ``progress(label, done, total)`` (None: counts nothing)."""

    def __init__(self, progress: ProgressCallback | None, total: int):
        self.progress, self.total, self.done = progress, total, 0

    def after(self, label: str) -> Callable[[], None] | None:
        """The ``on_fit`` of :func:`~._folds.cross_validation_of` for fits labelled so."""
        if self.progress is None:
            return None
        report = self.progress

        def fitted() -> None:
            self.done += 1
            report(label, self.done, self.total)

        return fitted


def _n_folds(labels) -> int:
    return int(labels.max()) + 1


def _recording(robot, data, folds):
    """Checked ``(times, q, qd, qdd, tau)`` of ``data``, the fold labels and the period."""
    times, q, qd, qdd, tau = data_arrays(robot, data, times=True)
    labels, period = fold_labels(times, q, folds)
    return (q, qd, qdd, tau), labels, period


def cross_validate(robot: Robot, data: Data, estimator: Estimator = OLS(),
                   model: TorqueModel | str | None = None, *old_args: Any,
                   folds: int | Int[ArrayLike, " T"] = DEFAULT_FOLDS, limits: Limits = None,
                   transmission: TransmissionLike = None, base: BaseParameters | None = None,
                   smooth_velocity: float = SMOOTH_VELOCITY,
                   progress: ProgressCallback | None = None, **old_keywords: Any
                   ) -> CrossValidation:
    """Cross-validate :func:`~._identify.identify` ``(robot, data, estimator, model)`` over
    ``folds`` phase folds of the recording (module docstring), or over given fold labels
    (an integer array, one per sample). ``limits``, ``transmission``, ``base`` and
    ``smooth_velocity`` as in :func:`~._identify.identify`; ``progress(label, done,
    total)`` is called after each fold's fit (``total``: the folds)."""
    if old_args or old_keywords:
        data = _old_form("cross_validate", data, (estimator, model, *old_args), 4)
        estimator, model = from_keywords(robot, old_keywords, transmission=transmission,
                                         base=base, smooth_velocity=smooth_velocity)
        transmission, base, smooth_velocity = None, None, SMOOTH_VELOCITY
    model = torque_model(robot, model, transmission=transmission, base=base,
                         smooth_velocity=smooth_velocity)
    limits = per_joint("limits", limits, robot.n_joints)
    _check_estimator(estimator).check(model, limits)
    (q, qd, qdd, tau), labels, period = _recording(robot, data, folds)
    fits = _Fits(progress, _n_folds(labels))
    return cross_validation_of(estimator, model, model.regressor(q, qd, qdd), tau, limits,
                               labels, period,
                               on_fit=fits.after(f"{estimator.name}, {model.friction}"))


def _check_estimator(estimator):
    if not isinstance(estimator, Estimator):
        raise TypeError(f"estimator must be an Estimator (OLS(), WLS(...), L1(), "
                        f"BoxSearch(...), ...), got {estimator!r}")
    return estimator


@dataclasses.dataclass(frozen=True, eq=False)
class Selection:
    """What :func:`select_model` returns: every candidate's cross-validation (in the order
    tried) as ``(settings, cross-validation)`` pairs, where ``settings`` is ``{"method",
    "sigma", "friction"}``; the chosen and the lowest candidate's settings; ``options``
    the ``(estimator, model)`` of each candidate. :attr:`estimator` and :attr:`model` are
    the chosen ones: ``identify(robot, data, sel.estimator, sel.model)`` fits it."""

    candidates: tuple[tuple[dict, CrossValidation], ...]
    chosen: dict
    best: dict
    options: tuple[tuple[Estimator, TorqueModel], ...] = ()

    def _index(self, settings) -> int:
        return next(i for i, (s, _) in enumerate(self.candidates) if s is settings)

    @property
    def estimator(self) -> Estimator:
        return self.options[self._index(self.chosen)][0]

    @property
    def model(self) -> TorqueModel:
        return self.options[self._index(self.chosen)][1]

    @property
    def cross_validation(self) -> CrossValidation:
        """The chosen candidate's cross-validation."""
        return self.candidates[self._index(self.chosen)][1]

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


def select_model(robot: Robot, data: Data, *old_args: Any,
                 estimators: Estimator | Iterable[Estimator] | None = None,
                 frictions: str | TorqueModel | Iterable[str | TorqueModel] | None = None,
                 folds: int | Int[ArrayLike, " T"] = DEFAULT_FOLDS, limits: Limits = None,
                 transmission: TransmissionLike = None, base: BaseParameters | None = None,
                 smooth_velocity: float = SMOOTH_VELOCITY,
                 progress: ProgressCallback | None = None,
                 weightings: Iterable[tuple[str, Sigma]] | None = None,
                 **old_keywords: Any) -> Selection:
    """Choose the torque model and the estimator by cross-validation (module docstring).

    ``estimators`` (default :data:`ESTIMATOR_CANDIDATES`; those weighting by the torque
    limits are skipped without ``limits``) and ``frictions`` (default
    :data:`FRICTION_CANDIDATES`: friction strings, or TorqueModels) are the grid, simplest
    first; a ``transmission`` with a coupled motor adds the ``coupling`` term to every
    friction string. ``progress(label, done, total)`` is called after each fit (``total``:
    candidates x folds).
    0.2's ``weightings`` ((method, sigma) pairs) and keyword settings (``physical``, ...)
    keep working, deprecated."""
    if old_args or old_keywords or weightings is not None:
        if old_args or old_keywords:
            data = _old_form("select_model", data, old_args, 4)
        else:
            _deprecation.warn("select_model(weightings=...)", "estimators=(OLS(), ...)")
        estimators = tuple(estimator_from(robot, method=m, sigma=s, **old_keywords)
                           for m, s in (weightings or WEIGHTING_CANDIDATES))
    estimators = ESTIMATOR_CANDIDATES if estimators is None else (
        (estimators,) if isinstance(estimators, Estimator) else tuple(estimators))
    frictions = FRICTION_CANDIDATES if frictions is None else (
        (frictions,) if isinstance(frictions, (str, TorqueModel)) else tuple(frictions))
    limits = per_joint("limits", limits, robot.n_joints)
    if limits is None:
        estimators = tuple(e for e in estimators if getattr(e, "sigma", None) != "limits")
    if not frictions or not estimators:
        raise ValueError("select_model needs at least one friction model and one estimator")
    for e in estimators:
        _check_estimator(e)
    K: Any = getattr(transmission, "matrix", transmission)
    coupled = K is not None and bool(coupled_motors(K))
    (q, qd, qdd, tau), labels, period = _recording(robot, data, folds)
    if base is None:  # computed once for every candidate
        base = base_parameters(robot)
    tried, options = [], []
    fits = _Fits(progress, len(frictions) * len(estimators) * _n_folds(labels))
    for friction in frictions:
        if isinstance(friction, str) and coupled and "coupling" not in friction:
            friction = friction + "+coupling"
        model = torque_model(robot, friction, transmission=transmission, base=base,
                             smooth_velocity=smooth_velocity) if isinstance(friction, str) \
            else torque_model(robot, friction)
        Y = model.regressor(q, qd, qdd)  # one regressor per torque model
        for estimator in estimators:
            estimator.check(model, limits)
            settings = {"method": estimator.name, "sigma": getattr(estimator, "sigma", None),
                        "friction": friction if isinstance(friction, str) else model.friction}
            on_fit = fits.after(f"{estimator.name}, {model.friction}")
            tried.append((settings, cross_validation_of(estimator, model, Y, tau, limits,
                                                        labels, period, on_fit=on_fit)))
            options.append((estimator, model))
    best_settings, best = min(tried, key=lambda c: c[1].score)
    # simplest: fewest parameters, then the earlier (simpler) estimator
    order = sorted(range(len(tried)), key=lambda i: (tried[i][1].n_parameters, i))
    chosen = next(tried[i][0] for i in order if not_worse(tried[i][1], best))
    return Selection(candidates=tuple(tried), chosen=chosen, best=best_settings,
                     options=tuple(options))


@dataclasses.dataclass(frozen=True, eq=False)
class PriorSelection:
    """What :func:`choose_prior_strength` returns: each strength's cross-validation (in
    the order tried), the chosen and the lowest strength, and the estimator of each
    (``estimators``); :attr:`estimator` is the chosen one."""

    candidates: tuple[tuple[float, CrossValidation], ...]
    chosen: float
    best: float
    estimators: tuple[Estimator, ...] = ()

    @property
    def estimator(self) -> Estimator:
        return self.estimators[[s for s, _ in self.candidates].index(self.chosen)]

    @property
    def cross_validation(self) -> CrossValidation:
        """The chosen strength's cross-validation."""
        return dict(self.candidates)[self.chosen]

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


def choose_prior_strength(robot: Robot, data: Data,
                          estimator: Estimator = PhysicallyConsistent(),
                          model: TorqueModel | str | None = None, *old_args: Any,
                          strengths: Iterable[float] = PRIOR_STRENGTHS,
                          folds: int | Int[ArrayLike, " T"] = DEFAULT_FOLDS, limits: Limits = None,
                          transmission: TransmissionLike = None,
                          base: BaseParameters | None = None,
                          smooth_velocity: float = SMOOTH_VELOCITY,
                          progress: ProgressCallback | None = None, **old_keywords: Any
                          ) -> PriorSelection:
    """Choose how strongly a physically consistent fit is pulled toward the a-priori
    parameters (``prior_strength`` of :class:`~._estimators.PhysicallyConsistent`; an
    ``OLS`` or ``WLS`` ``estimator`` is made physically consistent) by cross-validation
    over the same phase folds as :func:`select_model`: every strength in ``strengths`` is
    cross-validated, and the STRONGEST pull whose fold-by-fold excess over the lowest
    error is within one standard error is kept (the one-standard-error rule: the most
    regularised model the data cannot tell from the best). The held-out folds are fitted
    by nothing, chosen by nothing else. ``progress(label, done, total)`` is called after
    each fit (``total``: strengths x folds)."""
    strengths = tuple(float(v) for v in strengths)
    if not strengths or any(not (np.isfinite(v) and v >= 0) for v in strengths):
        raise ValueError(f"strengths must be numbers >= 0, at least one, got {strengths}")
    if old_args or old_keywords:
        data = _old_form("choose_prior_strength", data, (estimator, model, *old_args), 4)
        keywords = {"method": "OLS", **old_keywords, "physical": True}
        if keywords["method"] not in ("OLS", "WLS"):
            raise ValueError("the pull to the prior is a physically consistent least-squares "
                             "fit: method 'OLS' or 'WLS'")
        estimator, model = from_keywords(robot, keywords, transmission=transmission,
                                         base=base, smooth_velocity=smooth_velocity)
        transmission, base, smooth_velocity = None, None, SMOOTH_VELOCITY
    if isinstance(estimator, OLS):
        estimator = PhysicallyConsistent(estimator)
    if not isinstance(estimator, PhysicallyConsistent):
        raise ValueError(f"the pull to the prior is a physically consistent least-squares "
                         f"fit: PhysicallyConsistent(...) (of OLS or WLS), not {estimator!r}")
    model = torque_model(robot, model, transmission=transmission, base=base,
                         smooth_velocity=smooth_velocity)
    limits = per_joint("limits", limits, robot.n_joints)
    estimator.check(model, limits)
    (q, qd, qdd, tau), labels, period = _recording(robot, data, folds)
    Y = model.regressor(q, qd, qdd)
    tried, estimators = [], []
    fits = _Fits(progress, len(strengths) * _n_folds(labels))
    for v in strengths:
        estimators.append(dataclasses.replace(estimator, prior_strength=v))
        tried.append((v, cross_validation_of(estimators[-1], model, Y, tau, limits, labels,
                                             period, on_fit=fits.after(f"prior strength {v:g}"))))
    best_v, best = min(tried, key=lambda c: c[1].score)
    chosen = max(v for v, cv in tried if not_worse(cv, best))
    return PriorSelection(candidates=tuple(tried), chosen=chosen, best=best_v,
                          estimators=tuple(estimators))
