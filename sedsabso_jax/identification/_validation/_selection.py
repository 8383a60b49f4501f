"""Judging an identification on samples it was not fitted to, and choosing by it.

A :class:`~._splits.Validation` cuts the data into splits, each a set of samples to fit
and one to predict: phase folds (:class:`~._splits.PhaseFolds`, the model interpolates),
speed splits (:class:`~._splits.SpeedSplits`, it extrapolates in speed), leave one
recording out (:class:`~._splits.RecordingFolds`), or several pooled.
:func:`cross_validate` fits and predicts every split (one score per split: NRMS over the
torque limits where known, else the relative RMS; their mean the validated error);
:func:`select_model` validates a grid of torque models and estimators and keeps the
simplest not worse than the best by the one-standard-error rule of the paired
split-by-split differences (:meth:`~.._default._policy.Default.not_worse`, with ties below
:data:`TIE_FRACTION`); :func:`choose_prior_strength` keeps the strongest pull to the prior
the rule allows. Held-out files are never read here. Why: docs/explanation/
identification-defaults.md.
"""


from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from typing import cast

import numpy as np

from ...dynamics._robot import Robot
from ...measurements._container import Measurements
from .._default._policy import DEFAULT
from .._estimators._estimator import (
    Estimator,
    Limits,
    ProgressCallback,
    checked_estimator,
    per_joint,
)
from .._estimators._least_squares import OLS, PhysicallyConsistent
from .._fit._samples import Samples, recorded
from .._model._candidates import candidate_models
from .._model._checks import model_of
from .._model._torque_model import TorqueModel
from .._options import one_or_more
from .._recordings import Data, recordings_of
from .._work import parts
from ._cross_validation import TIE_FRACTION as TIE_FRACTION
from ._cross_validation import CrossValidation as CrossValidation
from ._cross_validation import cross_validation_of, not_worse
from ._kept_terms import KeptTerms
from ._phase import DEFAULT_FOLDS as DEFAULT_FOLDS
from ._progress import Fits, grid_seconds, kept_seconds, split_seconds, train_rows
from ._screened_terms import Screen, ScreenedTerms, screen_seconds, with_screened
from ._splits import PhaseFolds, Splits, Validation

#: The candidate estimators of :func:`select_model` and the pulls toward the a-priori
#: parameters of :func:`choose_prior_strength` (the default's,
#: :class:`~.._default._policy.Default`).
ESTIMATOR_CANDIDATES = DEFAULT.estimators
PRIOR_STRENGTHS = DEFAULT.prior_strengths


@dataclasses.dataclass(frozen=True, eq=False)
class Prepared:
    """The recordings of ``data``, checked and stacked (the samples every candidate is
    fitted to), and a validation's splits of them."""

    recordings: list[Measurements]
    samples: Samples
    splits: Splits
    validation: Validation

    @classmethod
    def of(cls, robot: Robot, data: Data, validation: Validation) -> Prepared:
        if not isinstance(validation, Validation):
            raise TypeError(f"validation must be a Validation (PhaseFolds(), SpeedSplits(), "
                            f"RecordingFolds(), GivenFolds(labels), Pooled(...)), got "
                            f"{validation!r}")
        recordings, samples = recorded(robot, data)
        return cls(recordings, samples, validation.splits(recordings), validation)

    def validate(self, estimator: Estimator, model: TorqueModel, limits: np.ndarray | None,
                 on_fit: Callable[[], None] | None = None) -> CrossValidation:
        model.check_recordings(len(self.recordings))
        settings = {**self.validation.settings(), "description": self.validation.describe()}
        return cross_validation_of(estimator, model, self.samples, self.splits, limits,
                                   settings, on_fit=on_fit)


def cross_validate(robot: Robot, data: Data, estimator: Estimator = OLS(),
                   model: TorqueModel | None = None, *,
                   validation: Validation = PhaseFolds(), limits: Limits = None,
                   progress: ProgressCallback | Fits | None = None) -> CrossValidation:
    """Validate :func:`~sedsabso_jax.identify` ``(robot, data, estimator, model)``: fit each
    split of ``validation`` (a :class:`~._splits.Validation`; default
    :data:`DEFAULT_FOLDS` phase folds) and predict it. ``data``: one recording or several
    (stacked); ``model`` and ``limits`` as in :func:`~sedsabso_jax.identify`;
    ``progress(label, done, total)`` is called after each split's fit (``done`` and
    ``total``: the estimated seconds of the fits done and of all, :mod:`.._work`)."""
    prepared = Prepared.of(robot, data, validation)
    model = model_of(robot, model)
    limits = per_joint("limits", limits, robot.n_joints)
    checked_estimator(estimator).check(model, limits)
    each = split_seconds(train_rows(prepared.samples, prepared.splits), estimator, model,
                         parts(estimator, model))
    fits = Fits.of(progress)
    fits.ahead(sum(each))
    return prepared.validate(estimator, model, limits,
                             fits.after(f"{estimator.name}, {model.friction}", each))


@dataclasses.dataclass(frozen=True, eq=False)
class Selection:
    """What :func:`select_model` returns: every candidate's validation (in the order
    tried) as ``(settings, validation)`` pairs, where ``settings`` is ``{"method",
    "sigma", "friction"}``; the chosen and the lowest candidate's settings; ``options``
    the ``(estimator, model)`` of each candidate; ``screen`` the screen of the choice's
    scales (:class:`~._screened_terms.Screen`) or None. :attr:`estimator` and
    :attr:`model` are the chosen ones: ``identify(robot, data, sel.estimator,
    sel.model)`` fits it."""

    candidates: tuple[tuple[dict, CrossValidation], ...]
    chosen: dict
    best: dict
    options: tuple[tuple[Estimator, TorqueModel], ...] = ()
    screen: Screen | None = None

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
        """The chosen candidate's validation (the one it was chosen by)."""
        return self.candidates[self._index(self.chosen)][1]

    @property
    def parts(self) -> tuple[str, ...]:
        """The kinds of split the validation pools (one for a validation of one kind)."""
        return tuple(self.cross_validation.part_scores)

    def table(self) -> list[list[str]]:
        """Rows ``[method, sigma, physical, friction, parameters, error +- SE, (each
        part's mean error of pooled splits,) chosen]``."""
        rows = []
        parts = self.parts if len(self.parts) > 1 else ()
        for settings, cv in self.candidates:
            mark = "chosen" if settings is self.chosen else (
                "lowest" if settings is self.best else "")
            rows.append([settings["method"], str(settings.get("sigma") or "equal"),
                         "yes" if settings.get("physical") else "no", settings["friction"]
                         + (f" [{settings['signals']}]" if "signals" in settings else ""),
                         str(cv.n_parameters), f"{cv.score:.4f} +- {cv.standard_error:.4f}",
                         *(f"{cv.part_scores[k]:.4f}" for k in parts), mark])
        return rows

    def as_dict(self) -> dict:
        kept = any(s.get("kept_terms") for s, _ in self.candidates)
        return {"rule": "simplest candidate (fewest parameters, then physically consistent, "
                        "then the earlier estimator) whose split-by-split excess over the "
                        "lowest validated error is at most one standard error (or 1 % of "
                        "the lowest)" + ("; then the kept terms (the rows with kept_terms) "
                                         "added to it, kept unless their excess over it is "
                                         "above one standard error (or 1 % of it)"
                                         if kept else "") + (
                            "; then its scales searched where they validate better (the "
                            "screen; the row with screened)" if self.screen else ""),
                "chosen": self.chosen, "lowest": self.best,
                "candidates": [{"settings": s, **cv.as_dict(),
                                **{k: True for k in ("kept_terms", "screened") if s.get(k)}}
                               for s, cv in self.candidates],
                "screen": None if self.screen is None else self.screen.as_dict()}


#: The index of the candidate the one-standard-error rule picks among validations
#: ``(scores, physical)`` (:meth:`~.._default._policy.Default.simplest`).
simplest_not_worse = DEFAULT.simplest


def select_model(robot: Robot, data: Data, *,
                 models: TorqueModel | Iterable[TorqueModel] | None = None,
                 estimators: Estimator | Iterable[Estimator] | None = None,
                 validation: Validation = PhaseFolds(), limits: Limits = None,
                 kept: KeptTerms | None = None, screened: ScreenedTerms | None = None,
                 progress: ProgressCallback | Fits | None = None) -> Selection:
    """Choose the torque model and the estimator by validation (module docstring).

    ``models`` (default :func:`~sedsabso_jax.identification.candidate_models` of the robot: its
    :data:`~sedsabso_jax.identification.FRICTION_CANDIDATES`) and ``estimators`` (default
    :data:`ESTIMATOR_CANDIDATES`; those weighting by the torque limits are skipped
    without ``limits``; physically consistent ones count as simpler than the same
    unconstrained) are the grid, simplest first. Every candidate is scored by
    ``validation`` (default phase folds, as in :func:`cross_validate`; a
    :class:`~._splits.Pooled` validation's parts are scored from the same fits:
    :attr:`~._cross_validation.CrossValidation.part_scores`). ``kept``: terms added to
    the choice, with its estimator, and kept unless they validate worse
    (:class:`~._kept_terms.KeptTerms`; their rows come last, ``"kept_terms": True`` in
    their settings). ``screened``: scales searched where they validate better, screened
    on the choice (:class:`~._screened_terms.ScreenedTerms`; the choice with them
    searched comes last where the screen passes, ``"screened": True`` in its settings;
    :attr:`Selection.screen`). ``progress(label, done, total)`` is called after each fit, ``done``
    and ``total`` the estimated seconds of the fits done and of all (:mod:`.._work`;
    the kept terms' estimated for the costliest candidate until the choice is made)."""
    estimators = ESTIMATOR_CANDIDATES if estimators is None else one_or_more(estimators,
                                                                             Estimator)
    limits = per_joint("limits", limits, robot.n_joints)
    if limits is None:
        estimators = tuple(e for e in estimators if not checked_estimator(e).needs_limits)
    prepared = Prepared.of(robot, data, validation)
    if screened is not None:  # their scales' smallest from the velocities' noise
        screened = screened.at_noise(recordings_of(robot, data))
    models = candidate_models(robot) if models is None else tuple(
        model_of(robot, m) for m in one_or_more(models, TorqueModel))
    if not models or not estimators:
        raise ValueError("select_model needs at least one torque model and one estimator")
    grid = [(estimator, model) for model in models for estimator in estimators]
    rows = train_rows(prepared.samples, prepared.splits)
    each, seen = grid_seconds(rows, grid), set().union(*(parts(e, m) for e, m in grid))
    fits = Fits.of(progress)
    last = models[-1] if kept is None or not kept.models(models[-1]) \
        else kept.models(models[-1])[-1]
    fits.ahead(sum(map(sum, each)) + max(
        (0.0 if kept is None else sum(map(sum, kept_seconds(rows, kept, e, models[-1], seen))))
        + (0.0 if screened is None else screen_seconds(screened, e, last, prepared.samples,
                                                      prepared.splits)) for e in estimators))
    tried, options = [], []
    for (estimator, model), seconds in zip(grid, each):
        checked_estimator(estimator).check(model, limits)
        settings = {"method": estimator.name, "sigma": estimator.sigma,
                    "physical": estimator.physical, "friction": model.friction}
        on_fit = fits.after(f"{estimator.name}{' physical' * estimator.physical}, "
                            f"{model.friction}", seconds)
        tried.append((settings, prepared.validate(estimator, model, limits, on_fit)))
        options.append((estimator, model))
    index = simplest_not_worse([cv for _, cv in tried], [e.physical for e, _ in options])
    if kept is not None:
        index = _with_kept(kept, index, tried, options, prepared, limits, fits)
    screen = None
    if screened is not None:
        index, screen = with_screened(screened, index, tried, options, prepared, limits, fits)
    best_settings = min(tried, key=lambda c: c[1].score)[0]
    chosen = tried[index][0]
    return Selection(candidates=tuple(tried), chosen=chosen, best=best_settings,
                     options=tuple(options), screen=screen)


def revalidated(selection: Selection, robot: Robot, data: Data, validation: Validation,
                limits: Limits, signals: str,
                progress: ProgressCallback | Fits | None = None) -> Selection:
    """``selection`` with its choice validated again on ``data``, made by the signal
    chain ``signals`` (a row with ``"signals"`` in its settings, the one chosen)."""
    prepared = Prepared.of(robot, data, validation)
    index = selection._index(selection.chosen)
    estimator, model = selection.options[index]
    each = split_seconds(train_rows(prepared.samples, prepared.splits), estimator, model)
    fits = Fits.of(progress)
    fits.ahead(sum(each))
    settings = {**selection.chosen, "signals": signals}
    cv = prepared.validate(estimator, model, per_joint("limits", limits, robot.n_joints),
                           fits.after(f"{estimator.name}, {model.friction}, {signals}", each))
    return Selection(candidates=(*selection.candidates, (settings, cv)), chosen=settings,
                     best=selection.best, options=(*selection.options, (estimator, model)),
                     screen=selection.screen)


def _with_kept(kept: KeptTerms, index: int, tried: list, options: list,
               prepared: Prepared, limits: np.ndarray | None, fits: Fits) -> int:
    """Validate ``kept``'s terms added to candidate ``index`` (appended to ``tried`` and
    ``options``); the index of the candidate kept."""
    estimator, model = options[index]
    each = kept_seconds(train_rows(prepared.samples, prepared.splits), kept, estimator,
                        model, set().union(*(parts(e, m) for e, m in options)))
    fits.ahead(sum(map(sum, each)))
    found = []
    for with_terms, seconds in zip(kept.models(model), each):
        checked_estimator(estimator).check(with_terms, limits)
        settings = {**tried[index][0], "friction": with_terms.friction, "kept_terms": True}
        on_fit = fits.after(f"{estimator.name}, {with_terms.friction} (kept unless worse)",
                            seconds)
        tried.append((settings, prepared.validate(estimator, with_terms, limits, on_fit)))
        options.append((estimator, with_terms))
        found.append(len(tried) - 1)
    which = kept.kept(tried[index][1], [tried[i][1] for i in found])
    return index if which is None else found[which]


@dataclasses.dataclass(frozen=True, eq=False)
class PriorSelection:
    """What :func:`choose_prior_strength` returns: each strength's validation (in
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
        """The chosen strength's validation."""
        return dict(self.candidates)[self.chosen]

    def table(self) -> list[list[str]]:
        """Rows ``[strength, CV error +- SE, chosen]``."""
        return [[f"{s:g}", f"{cv.score:.4f} +- {cv.standard_error:.4f}",
                 "chosen" if s == self.chosen else ("lowest" if s == self.best else "")]
                for s, cv in self.candidates]

    def as_dict(self) -> dict:
        return {"rule": "strongest pull to the prior whose fold-by-fold excess over the "
                        "lowest validated error is at most one standard error (or 1 % "
                        "of the lowest)",
                "chosen": self.chosen, "lowest": self.best,
                "candidates": [{"prior_strength": s, **cv.as_dict()}
                               for s, cv in self.candidates]}


def choose_prior_strength(robot: Robot, data: Data,
                          estimator: Estimator = PhysicallyConsistent(),
                          model: TorqueModel | None = None, *,
                          strengths: Iterable[float] = PRIOR_STRENGTHS,
                          validation: Validation = PhaseFolds(), limits: Limits = None,
                          progress: ProgressCallback | Fits | None = None) -> PriorSelection:
    """Choose how strongly a physically consistent fit is pulled toward the a-priori
    parameters (``prior_strength`` of :class:`~sedsabso_jax.PhysicallyConsistent`; an
    ``OLS`` or ``WLS`` ``estimator`` is made physically consistent) by ``validation``
    (as in :func:`cross_validate`): every strength in ``strengths`` is validated, and the
    STRONGEST pull whose split-by-split excess over the lowest error is within one
    standard error is kept (the one-standard-error rule: the most regularised model the
    data cannot tell from the best). The predicted samples are fitted by nothing, chosen
    by nothing else. ``progress(label, done, total)`` is called after each fit (``done``
    and ``total``: estimated seconds, as in :func:`cross_validate`)."""
    strengths = tuple(float(v) for v in strengths)
    if not strengths or any(not (np.isfinite(v) and v >= 0) for v in strengths):
        raise ValueError(f"strengths must be numbers >= 0, at least one, got {strengths}")
    estimator = cast(PhysicallyConsistent, checked_estimator(estimator).physically_consistent())
    prepared = Prepared.of(robot, data, validation)
    model = model_of(robot, model)
    limits = per_joint("limits", limits, robot.n_joints)
    estimator.check(model, limits)
    tried, estimators = [], []
    each = split_seconds(train_rows(prepared.samples, prepared.splits), estimator, model)
    fits = Fits.of(progress)
    fits.ahead(sum(each) * len(strengths))
    for v in strengths:
        estimators.append(dataclasses.replace(estimator, prior_strength=v))
        tried.append((v, prepared.validate(estimators[-1], model, limits,
                                           fits.after(f"prior strength {v:g}", each))))
    best_v, best = min(tried, key=lambda c: c[1].score)
    chosen = max(v for v, cv in tried if not_worse(cv, best))
    return PriorSelection(candidates=tuple(tried), chosen=chosen, best=best_v,
                          estimators=tuple(estimators))
