"""The command's default as one call: choose the torque model and the estimator by
validation, then (physically consistent fits) the pull to the prior, then fit, and
judge the fit on held-out data::

    report = select_and_identify(robot, data, held_out=other_run, limits=limits)
    print(report.text())          # what `sedsabso-jax identify` prints
    report.write(settings, out_dir, json_path)

``sedsabso-jax identify`` is this function with its flags turned into objects
(:func:`estimator_candidates` for ``--method`` and ``--weights``,
:func:`~._model.candidate_models` for ``--friction``); the rules between its options are
stated once, in :class:`Choice`, which the command builds from its flags before it loads
any data."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from typing import Any, ClassVar, cast

import equinox as eqx

from ..dynamics._robot import Robot
from ..measurements._container import Measurements
from ._estimators import PhysicallyConsistent
from ._fitting import Estimator, Limits, ProgressCallback, Sigma
from ._identify import Data, identify, model_of, one_or_more, recordings_of
from ._model import TorqueModel, candidate_models
from ._options import as_float, as_int, check_count
from ._report import IdentificationReport
from ._splits import PhaseFolds, Pooled, RecordingFolds, SpeedSplits, Validation
from ._validation import (
    DEFAULT_FOLDS,
    ESTIMATOR_CANDIDATES,
    PRIOR_STRENGTHS,
    choose_prior_strength,
    select_model,
)

#: The weightings a fixed estimator is tried with (None: equal), simplest first.
SIGMA_CANDIDATES = (None, "residual", "limits")
#: ``sigma`` of :func:`estimator_candidates` that leaves the weighting to validation.
AUTO = "auto"


def estimator_candidates(method: str | None = None, sigma: Sigma = AUTO, **options: Any
                         ) -> tuple[Estimator, ...]:
    """The estimators the default chooses among.

    - ``method`` None: :data:`~._validation.ESTIMATOR_CANDIDATES` (OLS, Gautier's WLS,
      WLS by the limits), or those of them with weighting ``sigma``;
    - a registered name (``"L1"``, ``"SEDSABSO"``, ...) with ``sigma`` :data:`AUTO`: that
      estimator with each weighting of :data:`SIGMA_CANDIDATES` (WLS without None, which
      is its residual weighting), except a costly one (a box search: every run is
      costly), which searches no weighting (equal weights);
    - a name and a ``sigma``: that estimator alone.

    ``sigma``: :data:`AUTO`, None or ``"equal"``, ``"residual"``, ``"limits"``;
    ``options``: the named estimator's options (``runs``, ``iterations``, ``seed``, ...;
    those it does not have are ignored)."""
    if sigma != AUTO and sigma != "equal" and sigma not in SIGMA_CANDIDATES:
        raise ValueError(f"sigma must be {AUTO!r}, 'equal' (None), 'residual' or 'limits', "
                         f"got {sigma!r}")
    if method is None:
        wanted = None if sigma == "equal" else sigma
        return tuple(e for e in ESTIMATOR_CANDIDATES if sigma == AUTO or e.sigma == wanted)
    first = Estimator.named(method, **options)
    if sigma == "equal":  # None where that is equal weights, else explicit
        sigma = None if first.default_weighting == "equal" else "equal"
    if sigma != AUTO:
        return (Estimator.named(method, sigma=sigma, **options),)
    if first.costly:
        return (first,)
    return tuple(Estimator.named(method, sigma=s, **options) for s in SIGMA_CANDIDATES
                 if s is not None or first.default_weighting == "equal")


class DefaultValidation(eqx.Module):
    """What :func:`select_and_identify` chooses by unless told, made for the recordings
    (:meth:`of`): ``Pooled((PhaseFolds(folds), SpeedSplits()))``, with
    :class:`~._splits.RecordingFolds` (leave one recording out) instead of the phase folds
    for several recordings."""

    folds: int = eqx.field(default=DEFAULT_FOLDS, converter=as_int)
    kind: ClassVar[str] = "default"
    min_recordings: ClassVar[int] = 1

    def __check_init__(self):
        check_count("folds", self.folds, 2)

    def of(self, recordings: Sequence[Measurements]) -> Validation:
        """The validation of ``recordings``."""
        interpolation: Validation = (RecordingFolds() if len(recordings) > 1
                                     else PhaseFolds(self.folds))
        return Pooled((interpolation, SpeedSplits()))


@dataclasses.dataclass(frozen=True)
class Names:
    """How :class:`Choice`'s messages name the options: :func:`select_and_identify`'s
    arguments unless told (the command line gives its flags)."""

    physical: str = "physical=True"
    prior_strength: str = "prior_strength"
    prior_cv: str = "prior_strength='cv'"
    no_validation: str = "validation=None"
    one_candidate: str = "give one estimator and one torque model"
    offset_per_recording: str = "one torque offset per recording"
    validation: str = "validation"
    several: str = "several recordings"


class Choice(eqx.Module):
    """How :func:`select_and_identify` chooses, with the rules between its options stated
    once and checked when built (a one-line ValueError naming the options as ``names``
    spells them): the command line builds one from its flags before it loads any data.

    ``validation``: what chooses (a :class:`~._splits.Validation`, a
    :class:`DefaultValidation`, or None: nothing is validated, one candidate is fitted);
    ``physical``: only physically consistent fits (True), only unconstrained ones (False),
    or both (None); ``prior_strength``: a number, or ``"cv"`` to choose it by validation;
    ``candidates``: torque models x estimators given; ``recordings``: the recordings
    fitted together; ``offset_per_recording``: whether a model has one offset each."""

    validation: Validation | DefaultValidation | None = DefaultValidation()
    physical: bool | None = None
    prior_strength: float | str = eqx.field(default=0.0, converter=as_float)
    candidates: int = 1
    recordings: int = 1
    offset_per_recording: bool = False
    names: Names = Names()

    def __check_init__(self):
        n = self.names
        if self.physical not in (None, True, False):
            raise ValueError(f"physical must be None (both, chosen by validation), True or "
                             f"False, got {self.physical!r}")
        if self.prior_strength != "cv" and not (isinstance(self.prior_strength, float)
                                                and self.prior_strength >= 0):
            raise ValueError(f"{n.prior_strength} must be a number >= 0 or 'cv', got "
                             f"{self.prior_strength!r}")
        if self.prior_strength != 0.0 and self.physical is not True:
            raise ValueError(f"{n.prior_strength} needs {n.physical}: the pull to the "
                             f"a-priori parameters is part of the physically consistent fit")
        if self.prior_strength == "cv" and self.validation is None:
            raise ValueError(f"{n.prior_cv} chooses by validation, which {n.no_validation} "
                             f"turns off: give a number")
        if self.validation is None and self.candidates > 1:
            raise ValueError(f"{n.no_validation} turns validation off, so nothing can be "
                             f"chosen by it: {n.one_candidate}")
        if self.offset_per_recording and self.recordings < 2:
            raise ValueError(f"{n.offset_per_recording} needs {n.several}")
        if self.validation is not None and self.recordings < self.validation.min_recordings:
            raise ValueError(f"{n.validation} ({self.validation.kind}) needs {n.several}")

    def validation_of(self, recordings: Sequence[Measurements]) -> Validation | None:
        """The validation for ``recordings`` (None: none)."""
        return None if self.validation is None else self.validation.of(recordings)

    def estimators(self, estimators: tuple[Estimator, ...]) -> tuple[Estimator, ...]:
        """The candidates to fit: each estimator as given (``physical`` False, or nothing
        validated with ``physical`` None), physically consistent (True, fitted with a
        number ``prior_strength``), or both (None: the physically consistent form of each
        least-squares estimator after it)."""
        if self.physical is False or (self.physical is None and self.validation is None):
            return estimators
        if self.physical:
            physical = tuple(cast(PhysicallyConsistent, e.physically_consistent())
                             for e in estimators)
            if isinstance(self.prior_strength, str):  # "cv": chosen after the model
                return physical
            return tuple(dataclasses.replace(e, prior_strength=self.prior_strength)
                         for e in physical)
        # a least-squares fit (on normal equations) has a physically consistent form
        return tuple(f for e in estimators for f in (
            (e, e.physically_consistent()) if e.normal_equations and not e.physical else (e,)))


class _Stages:
    """One ``progress(label, done, total)`` over the stages of a call: each stage reports
    its own fits (1..its total) and is told how many fits the stages after it make."""

    def __init__(self, progress: ProgressCallback | None):
        self.progress, self.done = progress, 0

    def stage(self, later: int) -> ProgressCallback | None:
        if self.progress is None:
            return None
        report, start = self.progress, self.done

        def step(label: str, done: int, total: int) -> None:
            self.done = start + done
            report(label, self.done, start + total + later)

        return step


def select_and_identify(robot: Robot, data: Data, *, held_out: Data | None = None,
                        limits: Limits = None,
                        models: TorqueModel | Iterable[TorqueModel] | None = None,
                        estimators: Estimator | Iterable[Estimator] | None = None,
                        validation: Validation | DefaultValidation | None = DefaultValidation(),
                        physical: bool | None = None, prior_strength: float | str = 0.0,
                        progress: ProgressCallback | None = None) -> IdentificationReport:
    """Identify ``robot`` from ``data`` as ``sedsabso-jax identify`` does by default.

    1. Model choice: every estimator of ``estimators`` (default
       :data:`~._validation.ESTIMATOR_CANDIDATES`; one :class:`~._fitting.Estimator` or a
       sequence, e.g. :func:`estimator_candidates`), unconstrained and physically
       consistent (``physical`` None; True: only physically consistent, False: only
       unconstrained), with every torque model of ``models`` (default
       :func:`~._model.candidate_models` of the robot) is scored by ``validation`` and the
       simplest within one standard error of the lowest is kept
       (:func:`~._validation.select_model`). The default, :class:`DefaultValidation`,
       pools 5 folds of the motion's phase (leave one recording out for several
       recordings), where the model interpolates, with :class:`~._splits.SpeedSplits`,
       where it must extrapolate in speed as on a faster motion: its score is the error to
       expect on new motions, and the report gives each part's too. With one candidate, it
       is only validated (``validation=None``: not at all).
    2. ``prior_strength``, a number or ``"cv"`` (chosen from
       :data:`~._validation.PRIOR_STRENGTHS` by the same validation,
       :func:`~._validation.choose_prior_strength`), pulls a physically consistent fit
       toward the robot's a-priori parameters.
    3. The fit on all of ``data``, judged on it, on the validation and on ``held_out``
       (never used to choose or fit).

    ``data``: a :class:`~sedsabso_jax.Measurements`, several (recordings of one rate,
    fitted together; models with one torque offset per recording:
    ``candidate_models(robot, recordings=len(data))``), or ``(times, q, qd, qdd, tau)``;
    ``held_out`` likewise (one recording); ``limits``: per-joint torque limits (the NRMS
    measure and the 1/limit weighting; candidates weighting by them are skipped
    without); ``progress(label, done, total)``: called after each fit, ``done`` running
    1..``total`` over the whole call (None: quiet). The rules between the options are
    :class:`Choice`'s. Returns the :class:`~._report.IdentificationReport` the command
    prints (``text()``) and writes (``write(...)``)."""
    held = None if held_out is None else recordings_of(robot, held_out)
    if held is not None and len(held) > 1:
        raise ValueError("held_out must be one recording")
    recordings = recordings_of(robot, data)
    models = candidate_models(robot) if models is None else tuple(
        model_of(robot, m) for m in one_or_more(models, TorqueModel))
    estimators = ESTIMATOR_CANDIDATES if estimators is None else one_or_more(estimators,
                                                                             Estimator)
    choice = Choice(validation, physical, prior_strength, len(models) * len(estimators),
                    len(recordings), any(m.recordings > 1 for m in models))
    estimators = choice.estimators(estimators)
    chosen_by = choice.validation_of(recordings)
    # the fits after the model choice, for the progress: the prior's validation, the fit
    later = 1 + (len(PRIOR_STRENGTHS) * len(chosen_by.splits(recordings))
                 if progress is not None and chosen_by is not None
                 and choice.prior_strength == "cv"
                 else 0)
    stages = _Stages(progress)
    selection = cv = None
    if chosen_by is None:
        estimator, model = estimators[0], models[0]
    else:
        selection = select_model(robot, recordings, models=models, estimators=estimators,
                                 validation=chosen_by, limits=limits,
                                 progress=stages.stage(later))
        estimator, model = selection.estimator, selection.model
        cv = selection.cross_validation
    prior_selection = None
    if choice.physical is True and choice.prior_strength == "cv":
        prior_selection = choose_prior_strength(robot, recordings, estimator, model,
                                                strengths=PRIOR_STRENGTHS,
                                                validation=chosen_by,  # type: ignore[arg-type]
                                                limits=limits, progress=stages.stage(1))
        estimator, cv = prior_selection.estimator, prior_selection.cross_validation
    ident = identify(robot, recordings, estimator, model, limits=limits)
    if progress is not None:
        progress("fit on all the data", stages.done + 1, stages.done + 1)
    return IdentificationReport.evaluate(ident, recordings, None if held is None else held[0],
                                         limits,
                                         cross_validation=cv, selection=selection,
                                         prior_selection=prior_selection)
