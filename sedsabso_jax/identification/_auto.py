"""The command's default as one call: choose the torque model and the estimator by
validation, then (physically consistent fits) the pull to the prior, then fit, and
judge the fit on held-out data::

    report = select_and_identify(robot, data, held_out=other_run, limits=limits)
    print(report.text())          # what `sedsabso-jax identify` prints
    report.write(settings, out_dir, json_path)

``sedsabso-jax identify`` is this function with its flags turned into arguments
(:func:`estimator_candidates` for ``--method`` and ``--weights``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Int

from ..dynamics._base_parameters import BaseParameters, base_parameters
from ..dynamics._robot import Robot
from ..measurements._container import Measurements
from ..measurements._transmission import TransmissionLike
from ._estimators import OLS, BoxSearch, PhysicallyConsistent
from ._fitting import Estimator, Limits, ProgressCallback, Sigma
from ._identify import Data, identify, recordings_of, torque_model
from ._model import TorqueModel
from ._report import IdentificationReport
from ._splits import GivenFolds, PhaseFolds, Pooled, RecordingFolds, SpeedSplits, Validation
from ._validation import (
    DEFAULT_FOLDS,
    ESTIMATOR_CANDIDATES,
    FRICTION_CANDIDATES,
    PRIOR_STRENGTHS,
    choose_prior_strength,
    cross_validate,
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
      is its residual weighting), except a box search: every run of one is costly, so no
      weighting search (equal weights);
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
    if sigma == "equal":  # None where that is equal weights (as 0.2 wrote it), else explicit
        sigma = None if first.default_weighting == "equal" else "equal"
    if sigma != AUTO:
        return (Estimator.named(method, sigma=sigma, **options),)
    if isinstance(first, BoxSearch):
        return (first,)
    return tuple(Estimator.named(method, sigma=s, **options) for s in SIGMA_CANDIDATES
                 if s is not None or first.default_weighting == "equal")


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
                        limits: Limits = None, transmission: TransmissionLike = None,
                        estimators: Estimator | Iterable[Estimator] | None = None,
                        frictions: str | Iterable[str | TorqueModel] | None = None,
                        validation: Validation | None = None,
                        folds: int | Int[ArrayLike, " T"] = DEFAULT_FOLDS,
                        physical: bool | None = None, prior_strength: float | str = 0.0,
                        offset_per_recording: bool = False, base: BaseParameters | None = None,
                        progress: ProgressCallback | None = None) -> IdentificationReport:
    """Identify ``robot`` from ``data`` as ``sedsabso-jax identify`` does by default.

    1. Model choice: every estimator of ``estimators`` (default
       :data:`~._validation.ESTIMATOR_CANDIDATES`; one :class:`~._fitting.Estimator` or a
       sequence, e.g. :func:`estimator_candidates`), unconstrained and physically
       consistent (``physical`` None; True: only physically consistent, False: only
       unconstrained), with every torque model of ``frictions`` (default
       :data:`~._validation.FRICTION_CANDIDATES`) is scored by ``validation`` and the
       simplest within one standard error of the lowest is kept
       (:func:`~._validation.select_model`). The default validation,
       :func:`default_validation`, pools ``folds`` folds of the motion's phase (a count,
       or fold labels; leave one recording out for several recordings), where the model
       interpolates, with :class:`~._splits.SpeedSplits`, where it must extrapolate in
       speed as on a faster motion: its score is the error to expect on new motions, and
       the report gives each part's too. With one candidate, it is only validated
       (``folds=0``: not at all).
    2. ``prior_strength``, a number or ``"cv"`` (chosen from
       :data:`~._validation.PRIOR_STRENGTHS` by the same validation,
       :func:`~._validation.choose_prior_strength`), pulls a physically consistent fit
       toward the robot's a-priori parameters.
    3. The fit on all of ``data``, judged on it, on the validation and on ``held_out``
       (never used to choose or fit).

    ``data``: a :class:`~sedsabso_jax.Measurements`, several (recordings of one rate,
    fitted together; ``offset_per_recording``: one torque offset per joint and
    recording), or ``(times, q, qd, qdd, tau)``; ``held_out`` likewise (one recording);
    ``limits``: per-joint torque limits (the NRMS measure and the 1/limit weighting;
    candidates weighting by them are skipped without); ``transmission``, ``base``: as in
    :func:`~._identify.identify`; ``progress(label, done, total)``: called after each
    fit, ``done`` running 1..``total`` over the whole call (None: quiet). Returns the
    :class:`~._report.IdentificationReport` the command prints (``text()``) and writes
    (``write(...)``)."""
    held = None if held_out is None else recordings_of(robot, held_out)
    if held is not None and len(held) > 1:
        raise ValueError("held_out must be one recording")
    estimators = ESTIMATOR_CANDIDATES if estimators is None else (
        (estimators,) if isinstance(estimators, Estimator) else tuple(estimators))
    frictions = FRICTION_CANDIDATES if frictions is None else (
        (frictions,) if isinstance(frictions, (str, TorqueModel)) else tuple(frictions))
    if physical not in (None, True, False):
        raise ValueError(f"physical must be None (both, chosen by validation), True or False, "
                         f"got {physical!r}")
    if prior_strength != 0.0 and physical is not True:
        raise ValueError("prior_strength needs physical=True: the pull to the a-priori "
                         "parameters is part of the physically consistent fit")
    off = np.ndim(folds) == 0 and not folds  # folds: a count, or fold labels
    if prior_strength == "cv" and off:
        raise ValueError("prior_strength='cv' chooses by validation, which folds=0 turns "
                         "off: give a number")
    # None: both kinds, where validation can choose between them
    estimators = _with_physical(estimators, False if physical is None and off else physical)
    if physical is True and prior_strength != "cv":  # the candidates fit with the pull
        estimators = tuple(dataclasses.replace(e, prior_strength=float(prior_strength))  # type: ignore[type-var]
                           for e in estimators)
    choose = len(frictions) * len(estimators) > 1
    if off and choose:
        raise ValueError("folds=0 turns validation off, so nothing can be chosen by it: "
                         "give one estimator and one friction model")
    if off and validation is not None:
        raise ValueError("folds=0 turns validation off: give no validation, or folds > 1")
    recordings = recordings_of(robot, data)
    if validation is None and not off:
        validation = default_validation(recordings, folds)
    base = base_parameters(robot) if base is None else base
    common: dict[str, Any] = dict(limits=limits, transmission=transmission, base=base,
                                  offset_per_recording=offset_per_recording)
    # the fits after the model choice, for the progress: the prior's validation, the fit
    later = 1 + (len(PRIOR_STRENGTHS) * len(validation.splits(recordings))
                 if progress is not None and validation is not None and prior_strength == "cv"
                 else 0)
    stages = _Stages(progress)
    selection = cv = None
    model: TorqueModel | str
    if validation is None:
        estimator, model = estimators[0], frictions[0]
    else:
        selection = select_model(robot, recordings, estimators=estimators,
                                 frictions=frictions, validation=validation,
                                 progress=stages.stage(later), **common)
        estimator, model = selection.estimator, selection.model
        cv = selection.cross_validation
    if not isinstance(model, TorqueModel):
        model = torque_model(robot, model, transmission=transmission, base=base,
                             recordings=len(recordings) if offset_per_recording else 1)
    prior_selection = None
    if physical is True and prior_strength == "cv":
        prior_selection = choose_prior_strength(robot, recordings, estimator, model,
                                                strengths=PRIOR_STRENGTHS,
                                                validation=validation, limits=limits,
                                                progress=stages.stage(1))
        estimator, cv = prior_selection.estimator, prior_selection.cross_validation
    ident = identify(robot, recordings, estimator, model, limits=limits)
    if progress is not None:
        progress("fit on all the data", stages.done + 1, stages.done + 1)
    return IdentificationReport.evaluate(ident, recordings, None if held is None else held[0],
                                         limits,
                                         cross_validation=cv, selection=selection,
                                         prior_selection=prior_selection)


def default_validation(recordings: Sequence[Measurements],
                       folds: int | Int[ArrayLike, " T"] = DEFAULT_FOLDS) -> Validation:
    """What ``select_and_identify`` chooses by unless told: ``Pooled((PhaseFolds(folds),
    SpeedSplits()))`` (:class:`~._splits.GivenFolds` for fold labels), with
    :class:`~._splits.RecordingFolds` instead of the phase folds for several
    recordings."""
    interpolation: Validation = RecordingFolds() if len(recordings) > 1 else (
        GivenFolds(folds) if np.ndim(folds) == 1 else PhaseFolds(int(folds)))  # type: ignore[arg-type]
    return Pooled((interpolation, SpeedSplits()))


def _with_physical(estimators: tuple[Estimator, ...], physical: bool | None
                   ) -> tuple[Estimator, ...]:
    """The candidates for ``physical``: each estimator as given (False), physically
    consistent (True; OLS and WLS only), or both (None: the physically consistent form
    of each least-squares estimator after it)."""
    if physical is False:
        return estimators
    out: list[Estimator] = []
    for e in estimators:
        if isinstance(e, PhysicallyConsistent):
            out.append(e)
        elif isinstance(e, OLS):
            out += [PhysicallyConsistent(e)] if physical else [e, PhysicallyConsistent(e)]
        elif physical:
            raise ValueError(f"physical=True is a least-squares fit: use method 'OLS' or "
                             f"'WLS', not {e.name!r}")
        else:
            out.append(e)
    return tuple(out)
